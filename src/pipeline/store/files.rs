//! The file-system steps the store is built from: synced and atomic
//! writes, JSON reads, sorted listings.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::*;

pub(super) fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    let mut file = File::create(path).map_err(io_error(path))?;
    file.write_all(bytes).map_err(io_error(path))?;
    file.sync_all().map_err(io_error(path))
}

/// Writes `path` by a synced temporary file `.<name>.<tag>` renamed over it,
/// then syncs the directory: readers see the old or the new file, never a part.
pub fn write_atomically(path: &Path, bytes: &[u8], tag: &str) -> Result<(), StoreError> {
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temporary = dir.join(format!(".{name}.{tag}"));
    write_synced(&temporary, bytes)?;
    fs::rename(&temporary, path).map_err(io_error(path))?;
    sync_dir(&dir)
}

pub(super) fn sync_dir(path: &Path) -> Result<(), StoreError> {
    File::open(path)
        .and_then(|dir| dir.sync_all())
        .map_err(io_error(path))
}

pub(super) fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, StoreError> {
    let text = fs::read(path).map_err(io_error(path))?;
    serde_json::from_slice(&text).map_err(|source| StoreError::Json {
        path: path.to_path_buf(),
        source,
    })
}

/// The per-stage folders in `top` (`artifacts/`, `refs/`), sorted; any
/// other entry there is pushed to `foreign`.
pub(super) fn stage_folders(
    top: &Path,
    foreign: &mut Vec<PathBuf>,
) -> Result<Vec<String>, StoreError> {
    let (folders, others): (Vec<String>, Vec<String>) = sorted_entries(top)?
        .into_iter()
        .partition(|name| top.join(name).is_dir());
    foreign.extend(others.into_iter().map(|name| top.join(name)));
    Ok(folders)
}

pub(super) fn sorted_entries(dir: &Path) -> Result<Vec<String>, StoreError> {
    let mut names = Vec::new();
    let entries = match fs::read_dir(dir) {
        Ok(entries) => entries,
        // Missing, or a file where ternary keeps a directory (a user's
        // `artifacts/notes.txt`): nothing of ours inside; `foreign_entries`
        // reports the file.
        Err(error)
            if matches!(
                error.kind(),
                io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
            ) =>
        {
            return Ok(names);
        }
        Err(error) => return Err(io_error(dir)(error)),
    };
    for entry in entries {
        let entry = entry.map_err(io_error(dir))?;
        names.push(entry.file_name().to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}

pub(super) fn directory_bytes(dir: &Path) -> u64 {
    fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .filter_map(|entry| entry.metadata().ok())
                .map(|meta| meta.len())
                .sum()
        })
        .unwrap_or(0)
}
