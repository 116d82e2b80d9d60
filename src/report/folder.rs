//! The folder a report is written into, and what the report may write there:
//! the folder is resolved (every link and `..` followed) before it is held
//! against the store, every file is written by a temporary file renamed
//! over it (never through a link), and a file of an earlier report is
//! replaced only while it holds what that report wrote (its record,
//! [`RECORD`], says so): a figure the user edited, or a link put in its
//! place, is kept, and the report refuses to go on, naming it.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Component, Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::pipeline::key::sha256_hex;
use crate::pipeline::path_names::joined_inside;
use crate::pipeline::store::write_atomically;

/// The record of what a report wrote: `{ "<relative path>": "<sha256>" }`.
pub const RECORD: &str = ".ternary-report.json";

/// `path` absolute, with every link and `..` resolved as far as the path
/// exists and `..` taken lexically beyond (as `realpath -m` does).
pub fn resolved(path: &Path) -> Result<PathBuf> {
    let absolute = std::path::absolute(path)?;
    let mut out = PathBuf::new();
    for component in absolute.components() {
        match component {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => {
                out.push(other);
                if let Ok(real) = fs::canonicalize(&out) {
                    out = real;
                }
            }
        }
    }
    Ok(out)
}

/// The report folder, checked and with the record of the earlier report.
pub struct ReportFolder {
    /// The folder as given.
    dir: PathBuf,
    /// What the earlier report wrote (empty for a new folder).
    earlier: BTreeMap<String, String>,
    /// What this report writes.
    written: BTreeMap<String, String>,
}

impl ReportFolder {
    /// Opens `dir` for a report of the store at `store_root`: refused when it
    /// resolves inside the store, is a link or not a directory, or holds
    /// files without an earlier report's page (`is_earlier_page` tells).
    pub fn open(
        dir: &Path,
        store_root: &Path,
        is_earlier_page: impl Fn(&Path) -> bool,
        page: &str,
    ) -> Result<ReportFolder> {
        let (target, root) = (resolved(dir)?, resolved(store_root)?);
        if target.starts_with(&root) {
            bail!(
                "{} is inside the store {} (it resolves to {}): a report goes elsewhere (the store holds only what `run` writes)",
                dir.display(),
                store_root.display(),
                target.display()
            );
        }
        if fs::symlink_metadata(dir).is_ok_and(|m| m.file_type().is_symlink()) {
            bail!(
                "{} is a link (to {}): give the folder itself",
                dir.display(),
                target.display()
            );
        }
        let folder = ReportFolder {
            dir: dir.to_path_buf(),
            earlier: BTreeMap::new(),
            written: BTreeMap::new(),
        };
        if !dir.exists() {
            return Ok(folder);
        }
        if !dir.is_dir() {
            bail!("{} is not a directory", dir.display());
        }
        let mut entries =
            fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        if entries.next().is_none() {
            return Ok(folder);
        }
        if !is_earlier_page(&dir.join(page)) {
            bail!(
                "{} holds files and no earlier report ({} is missing or not ternary's): a report goes into a new or empty directory, or over an earlier one",
                dir.display(),
                dir.join(page).display()
            );
        }
        let earlier = fs::read(dir.join(RECORD))
            .ok()
            .and_then(|bytes| serde_json::from_slice(&bytes).ok())
            .unwrap_or_default();
        Ok(ReportFolder { earlier, ..folder })
    }

    /// Creates the subfolder `name` (a real directory, not a link).
    pub fn subfolder(&self, name: &str) -> Result<()> {
        let path = self.path(name)?;
        if fs::symlink_metadata(&path).is_ok_and(|m| !m.is_dir()) {
            bail!(
                "{} is not a directory of the earlier report (a link or a file): move it away",
                path.display()
            );
        }
        fs::create_dir_all(&path).with_context(|| format!("creating {}", path.display()))
    }

    /// Writes `bytes` to the relative `name` atomically, unless the file
    /// there holds something other than what the earlier report wrote.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        let path = self.path(name)?;
        let sha256 = sha256_hex(bytes);
        if let Ok(meta) = fs::symlink_metadata(&path) {
            let current = meta
                .is_file()
                .then(|| fs::read(&path).ok())
                .flatten()
                .map(|old| sha256_hex(&old));
            let ours = current.as_ref().is_some_and(|current| {
                *current == sha256 || self.earlier.get(name) == Some(current)
            });
            if !ours {
                bail!(
                    "{} differs from what the earlier report wrote (edited, or not ternary's): it is kept; move it away to write the report here",
                    path.display()
                );
            }
        }
        write_atomically(&path, bytes, &std::process::id().to_string())
            .with_context(|| format!("writing {}", path.display()))?;
        self.written.insert(name.to_string(), sha256);
        Ok(())
    }

    /// Writes the record of what this report wrote (after everything else).
    pub fn finish(self) -> Result<()> {
        let text = serde_json::to_vec_pretty(&self.written)?;
        let path = self.dir.join(RECORD);
        write_atomically(&path, &text, &std::process::id().to_string())
            .with_context(|| format!("writing {}", path.display()))
    }

    /// The folder joined with the relative `name`, inside it.
    fn path(&self, name: &str) -> Result<PathBuf> {
        joined_inside(&self.dir, name).map_err(anyhow::Error::msg)
    }
}
