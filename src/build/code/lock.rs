//! `Cargo.lock`: the locked version, checksum and dependencies of every
//! external crate a stage's code names.

use std::collections::BTreeSet;

use sha2::{Digest, Sha256};

use super::syntax::hex;

/// The locked packages: name, version, checksum and dependencies.
pub(super) struct Lock {
    pub(super) packages: Vec<LockedPackage>,
}

pub(super) struct LockedPackage {
    pub(super) name: String,
    pub(super) version: String,
    pub(super) checksum: String,
    pub(super) dependencies: Vec<String>,
    pub(super) local: bool,
}

impl Lock {
    pub(super) fn parse(text: &str) -> Result<Lock, String> {
        let value: toml::Table = toml::from_str(text).map_err(|e| format!("Cargo.lock: {e}"))?;
        let packages = value
            .get("package")
            .and_then(toml::Value::as_array)
            .ok_or("Cargo.lock: no [[package]]")?
            .iter()
            .map(|package| {
                let field = |name: &str| {
                    package
                        .get(name)
                        .and_then(toml::Value::as_str)
                        .unwrap_or_default()
                        .to_string()
                };
                LockedPackage {
                    name: field("name"),
                    version: field("version"),
                    checksum: field("checksum"),
                    dependencies: package
                        .get("dependencies")
                        .and_then(toml::Value::as_array)
                        .into_iter()
                        .flatten()
                        .filter_map(|d| d.as_str().map(str::to_string))
                        .collect(),
                    local: package.get("source").is_none(),
                }
            })
            .collect();
        Ok(Lock { packages })
    }

    /// The crate names (as Rust code spells them) the local package depends on.
    pub(super) fn root_dependencies(&self) -> BTreeSet<String> {
        self.packages
            .iter()
            .filter(|p| p.local)
            .flat_map(|p| &p.dependencies)
            .map(|d| d.split(' ').next().unwrap_or_default().replace('-', "_"))
            .collect()
    }

    /// The package a dependency entry (`name` or `name version ...`) means.
    pub(super) fn package(&self, entry: &str) -> Option<&LockedPackage> {
        let mut words = entry.split(' ');
        let name = words.next()?;
        let version = words.next();
        self.packages
            .iter()
            .find(|p| p.name == name && version.is_none_or(|v| v == p.version))
    }

    /// The part of the crate `rust_name` the local package depends on:
    /// `("crate <name> <version>", hex SHA-256 of the name, version and
    /// checksum of it and of everything it depends on)`.
    pub(super) fn part(&self, rust_name: &str) -> Option<(String, String)> {
        let local = self.packages.iter().find(|p| p.local)?;
        let direct = local
            .dependencies
            .iter()
            .find(|d| d.split(' ').next().unwrap_or_default().replace('-', "_") == rust_name)?;
        let package = self.package(direct)?;
        let mut closure = BTreeSet::new();
        let mut work = vec![direct.as_str()];
        while let Some(entry) = work.pop() {
            let Some(dependency) = self.package(entry) else {
                continue;
            };
            let line = format!(
                "{} {} {}\n",
                dependency.name, dependency.version, dependency.checksum
            );
            if closure.insert(line) {
                work.extend(dependency.dependencies.iter().map(String::as_str));
            }
        }
        let digest = hex(&Sha256::digest(closure.into_iter().collect::<String>()));
        Some((
            format!("crate {} {}", package.name, package.version),
            digest,
        ))
    }
}
