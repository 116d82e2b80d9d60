//! `ternary verify --bundle`, and the `SHA256SUMS` it checks: every file's
//! size and hash against the descriptor and the sums.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::Result;
use serde_json::Value;

use crate::pipeline::key::sha256_hex;

/// Every file of a bundle, relative, sorted.
pub(super) fn files_of(dir: &Path) -> Result<Vec<String>> {
    let mut found = Vec::new();
    let mut pending = vec![PathBuf::new()];
    while let Some(relative) = pending.pop() {
        for entry in fs::read_dir(dir.join(&relative))? {
            let entry = entry?;
            let path = relative.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                pending.push(path);
            } else {
                found.push(path.to_string_lossy().into_owned());
            }
        }
    }
    found.sort();
    Ok(found)
}

/// `<sha256>  <path>` of every file but `SHA256SUMS`.
pub(super) fn sha256sums(dir: &Path) -> Result<String> {
    let mut out = String::new();
    for path in files_of(dir)? {
        if path == "SHA256SUMS" {
            continue;
        }
        let bytes = fs::read(dir.join(&path))?;
        let _ = writeln!(out, "{}  {path}", sha256_hex(&bytes));
    }
    Ok(out)
}

/// Checks a bundle: the descriptor's required fields, every resource's size
/// and hash, and `SHA256SUMS` against every file. Returns the report and the
/// number of problems.
pub fn verify_bundle(dir: &Path) -> Result<(String, usize)> {
    let mut problems = Vec::new();
    let descriptor_path = dir.join("datapackage.json");
    let descriptor: Value = match fs::read(&descriptor_path) {
        Err(error) => {
            problems.push(format!("datapackage.json: {error}"));
            Value::Null
        }
        Ok(bytes) => serde_json::from_slice(&bytes).unwrap_or_else(|error| {
            problems.push(format!("datapackage.json: not JSON ({error})"));
            Value::Null
        }),
    };
    if !descriptor.is_null() {
        problems.extend(descriptor_problems(dir, &descriptor));
    }
    problems.extend(sums_problems(dir)?);
    let mut out = String::new();
    for problem in &problems {
        let _ = writeln!(out, "PROBLEM  {problem}");
    }
    let resources = descriptor["resources"].as_array().map_or(0, Vec::len);
    let _ = writeln!(
        out,
        "verify --bundle: {} resources, {} problems in {}",
        resources,
        problems.len(),
        dir.display()
    );
    Ok((out, problems.len()))
}

/// Required fields of the package and of each resource, and each resource's
/// file against its `bytes` and `hash` where it records them (a table
/// records neither: `SHA256SUMS` holds its hash).
fn descriptor_problems(dir: &Path, descriptor: &Value) -> Vec<String> {
    let mut problems = Vec::new();
    for field in [
        "$schema",
        "name",
        "title",
        "version",
        "licenses",
        "resources",
    ] {
        if descriptor.get(field).is_none_or(Value::is_null) {
            problems.push(format!("datapackage.json: missing `{field}`"));
        }
    }
    let resources = descriptor["resources"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    if resources.is_empty() {
        problems.push("datapackage.json: no resource".into());
    }
    for (k, resource) in resources.iter().enumerate() {
        let Some(path) = resource["path"].as_str() else {
            problems.push(format!("datapackage.json: resources[{k}] has no `path`"));
            continue;
        };
        let required: &[&str] = if resource["type"] == "table" {
            &["name", "format", "mediatype", "schema"]
        } else {
            &["name", "format", "mediatype", "bytes", "hash"]
        };
        for field in required {
            if resource.get(field).is_none_or(Value::is_null) {
                problems.push(format!("{path}: the descriptor lacks `{field}`"));
            }
        }
        if path.split('/').any(|part| part == ".." || part.is_empty()) {
            problems.push(format!("{path}: not a path inside the bundle"));
            continue;
        }
        match fs::read(dir.join(path)) {
            Err(error) => problems.push(format!("{path}: {error}")),
            Ok(bytes) => problems.extend(size_and_hash_problems(path, resource, &bytes)),
        }
    }
    problems
}

/// A file's size and SHA-256 against the `bytes` and `hash` its resource
/// records, when it records them.
fn size_and_hash_problems(path: &str, resource: &Value, bytes: &[u8]) -> Vec<String> {
    let mut problems = Vec::new();
    if let Some(recorded) = resource.get("bytes")
        && recorded.as_u64() != Some(bytes.len() as u64)
    {
        problems.push(format!(
            "{path}: {} bytes but the descriptor records {recorded}",
            bytes.len()
        ));
    }
    let hash = format!("sha256:{}", sha256_hex(bytes));
    if let Some(recorded) = resource.get("hash")
        && recorded.as_str() != Some(hash.as_str())
    {
        problems.push(format!(
            "{path}: {hash} but the descriptor records {recorded}"
        ));
    }
    problems
}

/// `SHA256SUMS` against the files: each listed file hashes to its line, and
/// every file of the bundle is listed.
fn sums_problems(dir: &Path) -> Result<Vec<String>> {
    let mut problems = Vec::new();
    let sums = match fs::read_to_string(dir.join("SHA256SUMS")) {
        Ok(text) => text,
        Err(error) => return Ok(vec![format!("SHA256SUMS: {error}")]),
    };
    let mut listed = BTreeMap::new();
    for line in sums.lines() {
        match line.split_once("  ") {
            Some((sha, path)) => {
                listed.insert(path.to_string(), sha.to_string());
            }
            None => problems.push(format!("SHA256SUMS: malformed line `{line}`")),
        }
    }
    for (path, sha) in &listed {
        match fs::read(dir.join(path)) {
            Err(error) => problems.push(format!("{path}: {error}")),
            Ok(bytes) if &sha256_hex(&bytes) != sha => {
                problems.push(format!("{path}: does not match its line in SHA256SUMS"))
            }
            Ok(_) => {}
        }
    }
    for path in files_of(dir)? {
        if path != "SHA256SUMS" && !listed.contains_key(&path) {
            problems.push(format!("{path}: not listed in SHA256SUMS"));
        }
    }
    Ok(problems)
}
