//! Staging outside the store: a directory a command of ours writes
//! elsewhere (an export's bundle, beside or inside its target) before it
//! moves the result into place. Each is named `<prefix><id>.<pid>@<host>`,
//! holds a marker file naming the same writer, and is recorded in the
//! store's `tmp/`, so that what a killed command left is found and removed
//! by its marker wherever it lies, and nothing else ever is: a user's
//! `.export-2023/` carries neither this store's id nor the marker.

use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::files::*;
use super::names::*;
use super::*;

/// The marker file inside an outside staging directory; it holds the
/// directory's tag, `<id>.<pid>@<host>`.
const MARKER_FILE: &str = ".ternary-staging";

/// What the store's `tmp/` records of an outside staging directory.
#[derive(Serialize, Deserialize)]
struct OutsideRecord {
    /// The staging directory, absolute.
    path: PathBuf,
}

/// An outside staging directory, marked and recorded: the command writes
/// into [`OutsideStaging::content`] and calls [`OutsideStaging::finish`]
/// once the content has been moved into place.
pub struct OutsideStaging {
    /// The staging directory (the marker and `content/` inside).
    pub dir: PathBuf,
    /// The record in the store's `tmp/`, when the store could take one.
    record: Option<PathBuf>,
}

impl OutsideStaging {
    /// Where the command writes what it stages.
    pub fn content(&self) -> PathBuf {
        self.dir.join("content")
    }

    /// Removes the staging directory (what is left of it) and its record.
    pub fn finish(self) -> Result<(), StoreError> {
        if self.dir.exists() {
            fs::remove_dir_all(&self.dir).map_err(io_error(&self.dir))?;
        }
        if let Some(record) = &self.record {
            fs::remove_file(record).map_err(io_error(record))?;
        }
        Ok(())
    }
}

impl Store {
    /// This process's tag among the store's writers, `<id>.<pid>@<host>`
    /// (`None` for a store without an id, which names no debris its own).
    fn writer_tag(&self) -> Option<String> {
        Some(format!("{}.{}", self.id.as_deref()?, writer_name()))
    }

    /// Creates the staging directory `<parent>/<prefix><tag>` with its
    /// marker and records it in `tmp/` (a store that cannot take the record,
    /// being read-only, still gets the marked directory).
    pub fn begin_outside(&self, parent: &Path, prefix: &str) -> Result<OutsideStaging, StoreError> {
        let tag = self
            .writer_tag()
            .unwrap_or_else(|| format!("unknown.{}", writer_name()));
        let dir =
            std::path::absolute(parent.join(format!("{prefix}{tag}"))).map_err(io_error(parent))?;
        if is_marked(&dir, &tag) {
            fs::remove_dir_all(&dir).map_err(io_error(&dir))?;
        }
        fs::create_dir(&dir).map_err(io_error(&dir))?;
        write_synced(&dir.join(MARKER_FILE), tag.as_bytes())?;
        fs::create_dir(dir.join("content")).map_err(io_error(&dir))?;
        let record = self.writer_tag().and_then(|tag| {
            let path = self.root.join("tmp").join(format!("outside.{tag}.json"));
            let text = serde_json::to_vec(&OutsideRecord { path: dir.clone() }).ok()?;
            write_synced(&path, &text).ok().map(|()| path)
        });
        Ok(OutsideStaging { dir, record })
    }

    /// Removes the outside staging directories `<parent>/<prefix><tag>` of
    /// this store whose writer no longer runs and whose marker names them.
    pub fn clean_outside(&self, parent: &Path, prefix: &str) -> Result<(), StoreError> {
        let Some(id) = self.id.as_deref() else {
            return Ok(());
        };
        for name in sorted_entries(parent)? {
            let Some(tag) = name.strip_prefix(prefix) else {
                continue;
            };
            let dir = parent.join(&name);
            if is_dead_tag(tag, id) && is_marked(&dir, tag) {
                fs::remove_dir_all(&dir).map_err(io_error(&dir))?;
            }
        }
        Ok(())
    }

    /// The records in `tmp/` of outside staging: `outside.<tag>.json`.
    pub(super) fn outside_records(&self) -> Result<Vec<String>, StoreError> {
        let id = self.id.as_deref().unwrap_or_default();
        Ok(sorted_entries(&self.root.join("tmp"))?
            .into_iter()
            .filter(|name| record_tag(name).is_some_and(|tag| is_tag_of(tag, id)))
            .collect())
    }

    /// Removes what killed commands left outside the store, by their
    /// records: each marked directory, then its record.
    pub(super) fn clean_outside_records(&self) -> Result<usize, StoreError> {
        let Some(id) = self.id.as_deref() else {
            return Ok(0);
        };
        let mut removed = 0;
        for name in self.outside_records()? {
            let tag = record_tag(&name).unwrap_or_default();
            if !is_dead_tag(tag, id) {
                continue;
            }
            let path = self.root.join("tmp").join(&name);
            if let Ok(record) = read_json::<OutsideRecord>(&path)
                && is_marked(&record.path, tag)
            {
                fs::remove_dir_all(&record.path).map_err(io_error(&record.path))?;
                removed += 1;
            }
            fs::remove_file(&path).map_err(io_error(&path))?;
        }
        Ok(removed)
    }
}

/// The tag of a record's name `outside.<tag>.json`.
fn record_tag(name: &str) -> Option<&str> {
    name.strip_prefix("outside.")?.strip_suffix(".json")
}

/// `true` for `<id>.<pid>@<host>` of the store `id`.
fn is_tag_of(tag: &str, id: &str) -> bool {
    tag.strip_prefix(id)
        .and_then(|rest| rest.strip_prefix('.'))
        .is_some_and(is_writer_name)
}

/// `true` for a tag of the store `id` whose writer ran on this host and no
/// longer runs (another host's writer may still be at work: kept).
fn is_dead_tag(tag: &str, id: &str) -> bool {
    is_tag_of(tag, id)
        && tag
            .rsplit_once('@')
            .is_some_and(|(_, host)| host == this_host())
        && !is_live_staging(tag)
}

/// `true` when `dir` is a directory (not a link to one) holding the marker
/// file with `tag`.
fn is_marked(dir: &Path, tag: &str) -> bool {
    let marker = dir.join(MARKER_FILE);
    fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir())
        && fs::symlink_metadata(&marker).is_ok_and(|m| m.is_file())
        && fs::read(&marker).is_ok_and(|bytes| bytes == tag.as_bytes())
}
