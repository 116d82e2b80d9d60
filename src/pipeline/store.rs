//! The content-addressed artifact store.
//!
//! Layout under the store root:
//!
//! ```text
//! store.lock                          exclusive lock held by `run` and `gc`
//! tmp/<key>.<pid>/                    staging directories (never trusted)
//! artifacts/<stage>/<key>/            one directory per artifact:
//!     manifest.json                   key, parameters, inputs, file hashes, provenance
//!     <table>.parquet                 output tables
//! refs/<stage>/<instance>.json        the last key computed for a stage instance
//! ```
//!
//! An artifact is written into a staging directory, every file is fsynced,
//! the manifest is written last, and the directory is renamed into place: a
//! run killed at any point leaves only staging debris, which nothing trusts and
//! the next locked run removes.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::key::{InputRecord, sha256_hex};

/// A store operation failed.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// Filesystem failure at a path.
    #[error("{path}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
    /// A manifest or ref could not be encoded or decoded.
    #[error("{path}")]
    Json {
        /// The path.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
}

fn io_error(path: &Path) -> impl FnOnce(io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// One output file as recorded in a manifest.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileRecord {
    /// File name inside the artifact directory.
    pub name: String,
    /// SHA-256 of the file's bytes (what `verify` checks).
    pub sha256: String,
    /// SHA-256 of the table's data and its own metadata, without the
    /// executor's provenance (what downstream keys depend on: early cutoff).
    pub content_sha256: String,
    /// Size in bytes.
    pub bytes: u64,
    /// Data rows.
    pub rows: u64,
}

/// Everything known about an artifact.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Content key (the directory name).
    pub key: String,
    /// Stage name.
    pub stage: String,
    /// Stage version.
    pub version: u32,
    /// Instance that first produced this key.
    pub instance: String,
    /// Resolved parameters.
    pub params: Value,
    /// Inputs with their file hashes.
    pub inputs: Vec<InputRecord>,
    /// Output files.
    pub files: Vec<FileRecord>,
    /// `ternary <version>` that wrote it.
    pub tool: String,
    /// Wall time of the computation in seconds.
    pub wall_seconds: f64,
}

/// The last computation of a stage instance, for `status` to explain staleness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstanceRef {
    /// Key computed last.
    pub key: String,
    /// Stage version then.
    pub version: u32,
    /// Parameters then.
    pub params: Value,
    /// Inputs then.
    pub inputs: Vec<InputRecord>,
}

/// The result of re-hashing one artifact.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VerifyReport {
    /// Stage name.
    pub stage: String,
    /// Key (directory name).
    pub key: String,
    /// Problems found; empty when intact.
    pub problems: Vec<String>,
}

/// An artifact store rooted at a directory.
#[derive(Clone, Debug)]
pub struct Store {
    root: PathBuf,
}

/// The exclusive store lock; released on drop.
pub struct StoreLock {
    _file: File,
}

impl Store {
    /// Opens (creating if needed) the store at `root`.
    pub fn open(root: &Path) -> Result<Store, StoreError> {
        for dir in ["artifacts", "refs", "tmp"] {
            let path = root.join(dir);
            fs::create_dir_all(&path).map_err(io_error(&path))?;
        }
        Ok(Store {
            root: root.to_path_buf(),
        })
    }

    /// The store root.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Takes the exclusive lock, waiting (with a message on stderr) while another
    /// process holds it.
    pub fn lock(&self) -> Result<StoreLock, StoreError> {
        let path = self.root.join("store.lock");
        let mut file = OpenOptions::new()
            .create(true)
            .truncate(false)
            .read(true)
            .write(true)
            .open(&path)
            .map_err(io_error(&path))?;
        if file.try_lock().is_err() {
            let holder = fs::read_to_string(&path).unwrap_or_default();
            eprintln!(
                "waiting for the store lock {} (held by process {}) ...",
                path.display(),
                holder.trim()
            );
            file.lock().map_err(io_error(&path))?;
        }
        file.set_len(0).map_err(io_error(&path))?;
        write!(file, "{}", std::process::id()).map_err(io_error(&path))?;
        Ok(StoreLock { _file: file })
    }

    /// Directory of the artifact `key` of `stage`.
    pub fn artifact_dir(&self, stage: &str, key: &str) -> PathBuf {
        self.root.join("artifacts").join(stage).join(key)
    }

    fn ref_path(&self, stage: &str, instance: &str) -> PathBuf {
        self.root
            .join("refs")
            .join(stage)
            .join(format!("{instance}.json"))
    }

    /// The manifest of an artifact whose files are all present with their
    /// recorded sizes (a cheap check; `verify` re-hashes).
    pub fn intact_manifest(&self, stage: &str, key: &str) -> Option<Manifest> {
        let dir = self.artifact_dir(stage, key);
        let manifest: Manifest = read_json(&dir.join("manifest.json")).ok()?;
        let sizes_match = manifest.files.iter().all(|file| {
            fs::metadata(dir.join(&file.name)).is_ok_and(|meta| meta.len() == file.bytes)
        });
        (manifest.key == key && sizes_match).then_some(manifest)
    }

    /// Starts writing the artifact `key` of `stage` in a fresh staging directory.
    pub fn begin(&self, stage: &str, key: &str) -> Result<Staging, StoreError> {
        let dir = self
            .root
            .join("tmp")
            .join(format!("{key}.{}", std::process::id()));
        if dir.exists() {
            fs::remove_dir_all(&dir).map_err(io_error(&dir))?;
        }
        fs::create_dir_all(&dir).map_err(io_error(&dir))?;
        Ok(Staging {
            dir,
            target: self.artifact_dir(stage, key),
            trash: self
                .root
                .join("tmp")
                .join(format!("{key}.{}.old", std::process::id())),
            files: Vec::new(),
        })
    }

    /// Records the last computed key of a stage instance (atomically).
    pub fn write_ref(
        &self,
        stage: &str,
        instance: &str,
        entry: &InstanceRef,
    ) -> Result<(), StoreError> {
        let path = self.ref_path(stage, instance);
        let dir = path.parent().unwrap_or(&self.root).to_path_buf();
        fs::create_dir_all(&dir).map_err(io_error(&dir))?;
        let temporary = dir.join(format!(".{instance}.json.{}", std::process::id()));
        write_json(&temporary, entry)?;
        fs::rename(&temporary, &path).map_err(io_error(&path))
    }

    /// The last computed key of a stage instance, if any.
    pub fn read_ref(&self, stage: &str, instance: &str) -> Option<InstanceRef> {
        read_json(&self.ref_path(stage, instance)).ok()
    }

    /// Every artifact directory as `(stage, key)`, sorted.
    pub fn artifacts(&self) -> Result<Vec<(String, String)>, StoreError> {
        let mut found = Vec::new();
        for stage in sorted_entries(&self.root.join("artifacts"))? {
            for key in sorted_entries(&self.root.join("artifacts").join(&stage))? {
                found.push((stage.clone(), key));
            }
        }
        Ok(found)
    }

    /// Staging directories left by interrupted runs.
    pub fn staging_debris(&self) -> Result<Vec<PathBuf>, StoreError> {
        let tmp = self.root.join("tmp");
        Ok(sorted_entries(&tmp)?
            .into_iter()
            .map(|name| tmp.join(name))
            .collect())
    }

    /// Removes staging debris. Call only while holding the lock.
    pub fn clean_staging(&self, _lock: &StoreLock) -> Result<usize, StoreError> {
        let debris = self.staging_debris()?;
        for path in &debris {
            fs::remove_dir_all(path).map_err(io_error(path))?;
        }
        Ok(debris.len())
    }

    /// Re-hashes every file of one artifact against its manifest.
    pub fn verify_artifact(&self, stage: &str, key: &str) -> VerifyReport {
        let dir = self.artifact_dir(stage, key);
        let mut problems = Vec::new();
        match read_json::<Manifest>(&dir.join("manifest.json")) {
            Err(error) => problems.push(format!("unreadable manifest: {error}")),
            Ok(manifest) => {
                if manifest.key != key || manifest.stage != stage {
                    problems.push(format!(
                        "manifest names {}/{}",
                        manifest.stage, manifest.key
                    ));
                }
                for file in &manifest.files {
                    match fs::read(dir.join(&file.name)) {
                        Err(error) => problems.push(format!("{}: {error}", file.name)),
                        Ok(bytes) => {
                            let sha = sha256_hex(&bytes);
                            if sha != file.sha256 {
                                problems.push(format!(
                                    "{}: sha256 {} but manifest records {}",
                                    file.name, sha, file.sha256
                                ));
                            }
                        }
                    }
                }
            }
        }
        VerifyReport {
            stage: stage.to_string(),
            key: key.to_string(),
            problems,
        }
    }

    /// Removes an artifact directory. Call only while holding the lock.
    pub fn remove_artifact(
        &self,
        _lock: &StoreLock,
        stage: &str,
        key: &str,
    ) -> Result<u64, StoreError> {
        let dir = self.artifact_dir(stage, key);
        let bytes = directory_bytes(&dir);
        fs::remove_dir_all(&dir).map_err(io_error(&dir))?;
        Ok(bytes)
    }
}

/// An artifact being written. Nothing in it is visible until [`Staging::commit`].
pub struct Staging {
    dir: PathBuf,
    target: PathBuf,
    trash: PathBuf,
    files: Vec<FileRecord>,
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

    /// Writes the manifest last, then renames the directory into place,
    /// replacing an older artifact of the same key (`--force`).
    pub fn commit(self, manifest: &Manifest) -> Result<PathBuf, StoreError> {
        let manifest_path = self.dir.join("manifest.json");
        let text = serde_json::to_vec_pretty(manifest).map_err(|source| StoreError::Json {
            path: manifest_path.clone(),
            source,
        })?;
        write_synced(&manifest_path, &text)?;
        sync_dir(&self.dir)?;
        let parent = self.target.parent().unwrap_or(&self.dir).to_path_buf();
        fs::create_dir_all(&parent).map_err(io_error(&parent))?;
        if self.target.exists() {
            fs::rename(&self.target, &self.trash).map_err(io_error(&self.target))?;
        }
        fs::rename(&self.dir, &self.target).map_err(io_error(&self.target))?;
        sync_dir(&parent)?;
        if self.trash.exists() {
            fs::remove_dir_all(&self.trash).map_err(io_error(&self.trash))?;
        }
        Ok(self.target)
    }
}

fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    let mut file = File::create(path).map_err(io_error(path))?;
    file.write_all(bytes).map_err(io_error(path))?;
    file.sync_all().map_err(io_error(path))
}

fn sync_dir(path: &Path) -> Result<(), StoreError> {
    File::open(path)
        .and_then(|dir| dir.sync_all())
        .map_err(io_error(path))
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), StoreError> {
    let text = serde_json::to_vec_pretty(value).map_err(|source| StoreError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    write_synced(path, &text)
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, StoreError> {
    let text = fs::read(path).map_err(io_error(path))?;
    serde_json::from_slice(&text).map_err(|source| StoreError::Json {
        path: path.to_path_buf(),
        source,
    })
}

fn sorted_entries(dir: &Path) -> Result<Vec<String>, StoreError> {
    let mut names = Vec::new();
    let entries = match fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(error) if error.kind() == io::ErrorKind::NotFound => return Ok(names),
        Err(error) => return Err(io_error(dir)(error)),
    };
    for entry in entries {
        let entry = entry.map_err(io_error(dir))?;
        names.push(entry.file_name().to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}

fn directory_bytes(dir: &Path) -> u64 {
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
