//! What `gc` and `verify` find and remove: foreign entries, staging debris,
//! artifacts no instance names.

use std::fs;
use std::path::PathBuf;

use super::files::*;
use super::names::*;
use super::*;

impl Store {
    /// Entries under `artifacts/`, `tmp/` and `refs/` that ternary did not
    /// name: never removed, only reported.
    pub fn foreign_entries(&self) -> Result<Vec<PathBuf>, StoreError> {
        let mut foreign = Vec::new();
        for stage in stage_folders(&self.root.join("artifacts"), &mut foreign)? {
            for key in sorted_entries(&self.root.join("artifacts").join(&stage))? {
                let path = self.artifact_dir(&stage, &key);
                if !is_key(&key) || !path.is_dir() {
                    foreign.push(path);
                    continue;
                }
                if path.join("manifest.json").is_file() {
                    let inside = self.foreign_in_artifact(&stage, &key, &[]);
                    foreign.extend(inside.into_iter().map(|name| path.join(name)));
                }
            }
        }
        let id = self.id.as_deref().unwrap_or_default();
        let tmp = self.root.join("tmp");
        let records = self.outside_records()?;
        for name in sorted_entries(&tmp)? {
            if records.contains(&name) {
                continue;
            }
            if !(is_staging_name(&name, id) && tmp.join(&name).is_dir()) {
                foreign.push(tmp.join(name));
            }
        }
        let refs = self.root.join("refs");
        for stage in stage_folders(&refs, &mut foreign)? {
            for name in sorted_entries(&refs.join(&stage))? {
                let path = refs.join(&stage).join(&name);
                let ours =
                    (name.ends_with(".json") || is_json_temporary(&name, id)) && path.is_file();
                if !ours {
                    foreign.push(path);
                }
            }
        }
        Ok(foreign)
    }

    /// Staging directories left by interrupted runs, and temporary refs: only
    /// names with this store's id (none when it has no id).
    pub fn staging_debris(&self) -> Result<Vec<PathBuf>, StoreError> {
        let Some(id) = self.id.as_deref() else {
            return Ok(Vec::new());
        };
        let tmp = self.root.join("tmp");
        let mut debris: Vec<PathBuf> = sorted_entries(&tmp)?
            .into_iter()
            .filter(|name| is_staging_name(name, id))
            .map(|name| tmp.join(name))
            .filter(|path| path.is_dir())
            .collect();
        for name in sorted_entries(&self.root)? {
            if is_json_temporary(&name, id) {
                debris.push(self.root.join(name));
            }
        }
        let refs = self.root.join("refs");
        for stage in sorted_entries(&refs)? {
            for name in sorted_entries(&refs.join(&stage))? {
                if is_json_temporary(&name, id) {
                    debris.push(refs.join(&stage).join(name));
                }
            }
        }
        Ok(debris)
    }

    /// Removes staging debris, in the store and (by their records) outside
    /// it. Call only while holding the lock.
    pub fn clean_staging(&self, _lock: &StoreLock) -> Result<usize, StoreError> {
        let outside = self.clean_outside_records()?;
        let debris = self.staging_debris()?;
        for path in &debris {
            let removed = if path.is_dir() {
                fs::remove_dir_all(path)
            } else {
                fs::remove_file(path)
            };
            removed.map_err(io_error(path))?;
        }
        Ok(debris.len() + outside)
    }

    /// Removes an artifact directory. Call only while holding the lock.
    /// The directory is first renamed into `gc`'s own debris
    /// (`tmp/<key>.<id>.<writer>.old`), so that a `gc` killed while deleting
    /// leaves debris the next locked command removes, never a half artifact.
    pub fn remove_artifact(
        &self,
        _lock: &StoreLock,
        stage: &str,
        key: &str,
    ) -> Result<u64, StoreError> {
        let dir = self.artifact_dir(stage, key);
        let bytes = directory_bytes(&dir);
        let trash = self.staging_dir(key, &writer_name(), ".old");
        if trash.exists() {
            fs::remove_dir_all(&trash).map_err(io_error(&trash))?;
        }
        fs::create_dir_all(self.root.join("tmp")).map_err(io_error(&self.root))?;
        fs::rename(&dir, &trash).map_err(io_error(&dir))?;
        sync_dir(&self.root.join("artifacts").join(stage))?;
        fs::remove_dir_all(&trash).map_err(io_error(&trash))?;
        Ok(bytes)
    }
}
