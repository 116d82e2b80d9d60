//! Staging an artifact and committing it into place.

use std::fs;
use std::path::PathBuf;

use super::files::*;
use super::*;
use crate::pipeline::key::sha256_hex;

/// An artifact being written. Nothing in it is visible until
/// [`Staging::commit`]; dropped uncommitted, it removes its directory.
pub struct Staging {
    pub(super) dir: PathBuf,
    pub(super) target: PathBuf,
    pub(super) trash: PathBuf,
    pub(super) files: Vec<FileRecord>,
    pub(super) committed: bool,
}

impl Staging {
    /// Writes and fsyncs one output file whose table content hashes to `content_sha256`.
    pub fn write_file(
        &mut self,
        name: &str,
        bytes: &[u8],
        rows: u64,
        content_sha256: String,
    ) -> Result<(), StoreError> {
        let path = self.dir.join(name);
        write_synced(&path, bytes)?;
        self.files.push(FileRecord {
            name: name.to_string(),
            sha256: sha256_hex(bytes),
            content_sha256,
            bytes: bytes.len() as u64,
            rows,
        });
        Ok(())
    }

    /// Files written so far.
    pub fn files(&self) -> &[FileRecord] {
        &self.files
    }

    /// Seals and writes the manifest last, then renames the directory into
    /// place and returns the sealed manifest. With `replace`, an artifact
    /// already under the key (damaged, or recomputed by `--force`) is moved
    /// aside first. Otherwise an artifact that appeared under the key
    /// meanwhile (a concurrent writer) is kept and this copy discarded, after
    /// checking that both hold the same files ([`StoreError::Diverged`] if not).
    pub fn commit(mut self, manifest: Manifest, replace: bool) -> Result<Manifest, StoreError> {
        let manifest = manifest.sealed();
        let manifest_path = self.dir.join("manifest.json");
        let text = serde_json::to_vec_pretty(&manifest).map_err(|source| StoreError::Json {
            path: manifest_path.clone(),
            source,
        })?;
        write_synced(&manifest_path, &text)?;
        sync_dir(&self.dir)?;
        let parent = self.target.parent().unwrap_or(&self.dir).to_path_buf();
        fs::create_dir_all(&parent).map_err(io_error(&parent))?;
        if replace && self.target.exists() {
            fs::rename(&self.target, &self.trash).map_err(io_error(&self.target))?;
        }
        if let Err(error) = fs::rename(&self.dir, &self.target) {
            if !self.target.is_dir() {
                return Err(io_error(&self.target)(error));
            }
            return self.keep_theirs(manifest);
        }
        self.committed = true;
        sync_dir(&parent)?;
        if self.trash.exists() {
            fs::remove_dir_all(&self.trash).map_err(io_error(&self.trash))?;
        }
        Ok(manifest)
    }

    /// Another writer committed the same key first: keep its artifact when it
    /// holds the same files (this copy is then removed on drop).
    fn keep_theirs(self, ours: Manifest) -> Result<Manifest, StoreError> {
        let theirs: Manifest = read_json(&self.target.join("manifest.json"))?;
        let hashes = |m: &Manifest| -> Vec<(String, String)> {
            let mut files: Vec<_> = m
                .files
                .iter()
                .map(|f| (f.name.clone(), f.sha256.clone()))
                .collect();
            files.sort();
            files
        };
        if hashes(&theirs) != hashes(&ours) {
            return Err(StoreError::Diverged(self.target.clone()));
        }
        Ok(theirs)
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: what remains is debris that the next run alone on
            // the store, or gc, removes.
            let _ = fs::remove_dir_all(&self.dir);
        }
    }
}
