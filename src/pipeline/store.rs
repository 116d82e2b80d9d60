//! The content-addressed artifact store.
//!
//! Layout under the store root:
//!
//! ```text
//! ternary-store.json                  marker: format, layout version and this store's id,
//!                                     written when ternary creates the store
//! store.lock                          lock: shared by writing `run`s, exclusive for `gc`
//! tmp/<key>.<id>.<pid>@<host>/        staging directories (never trusted)
//! tmp/<key>.<id>.<pid>@<host>.old/    an artifact being replaced (`--force`, repair)
//! artifacts/<stage>/<key>/            one directory per artifact:
//!     manifest.json                   key, parameters, inputs, file hashes, provenance
//!     <table>.parquet                 output tables
//! refs/<stage>/<instance>.json        the last key computed for a stage instance
//! slurm/                              Slurm scripts and task logs (`ternary slurm`)
//! ```
//!
//! An artifact is written into a staging directory, every file is fsynced,
//! the manifest is written last, and the directory is renamed into place: a
//! run killed at any point leaves only staging debris, which nothing trusts and
//! the next locked run removes.
//!
//! The store never deletes what it did not create: a directory is opened as a
//! store only when it carries our marker (or is empty, or is missing, and then
//! gets one; or its marker was damaged and everything else in it is provably
//! ternary's: sealed manifests listing exactly their files), a marker that is
//! not ours is never written over, and only debris named with this store's id
//! is ever removed. Every
//! artifact is checked before it is trusted ([`Store::inspect`]): its manifest
//! must name its key, the key must follow from the manifest's parameters and
//! inputs, the directory must hold exactly the listed files, and each file
//! must hash to its recorded SHA-256.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::code::CodeRecord;
use super::key::{InputRecord, canonical_json, hex, sha256_hex, stage_key};
use super::table::content_sha256_of_file;

/// Name of the marker file at the store root.
pub const MARKER: &str = "ternary-store.json";

/// Store layout version written into the marker; a store with a higher one
/// is refused (it was written by a newer ternary). 2: the marker carries the
/// store's id, and debris is named with it (a version-1 marker, ours without
/// an id, gets one at the next writing open).
pub const FORMAT_VERSION: u32 = 2;

/// The top-level entries a ternary store consists of.
const LAYOUT: [&str; 6] = [MARKER, "store.lock", "artifacts", "refs", "tmp", "slurm"];

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
    /// The directory holds files and is not a ternary store.
    #[error(
        "{path} is not a ternary store: it has no {MARKER} of ternary's and is not empty (it holds {found}); \
         point `store.path` at a new or empty directory"
    )]
    NotAStore {
        /// The directory.
        path: PathBuf,
        /// A few of its entries.
        found: String,
    },
    /// The marker exists but cannot be read, or names another format or version.
    #[error("{path}: {message}")]
    Marker {
        /// The marker file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Two writers of one key produced different files: a stage is not
    /// deterministic.
    #[error(
        "{0}: a concurrent writer committed different bytes under the same key (a stage is not deterministic; please report it)"
    )]
    Diverged(PathBuf),
    /// The store directory does not exist (commands that only read).
    #[error("no store at {0}: `ternary run` creates it")]
    Missing(PathBuf),
}

fn io_error(path: &Path) -> impl FnOnce(io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The marker's content.
#[derive(Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Marker {
    /// Always `ternary-store`.
    format: String,
    /// Layout version.
    version: u32,
    /// The store's id (16 hex digits), in every name of its debris; absent in
    /// version-1 markers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    id: Option<String>,
}

/// The format field of our markers.
const MARKER_FORMAT: &str = "ternary-store";

impl Marker {
    /// A current marker for a new store at `root`: an id from the root, the
    /// time and the process (two stores never share one).
    fn new(root: &Path) -> Marker {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let seed = format!("{}|{nanos}|{}", root.display(), writer_name());
        Marker {
            format: MARKER_FORMAT.to_string(),
            version: FORMAT_VERSION,
            id: Some(sha256_hex(seed.as_bytes())[..16].to_string()),
        }
    }
}

/// What the marker file says about a directory.
enum MarkerState {
    /// Our marker, with the store's id (`None`: a version-1 marker).
    Ours(Option<String>),
    /// No marker file.
    Missing,
    /// A file of that name that is not a marker of ours (a user's, or ours
    /// damaged): never written over unless the rest proves the store ours.
    NotOurs,
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
    /// The code that computed it (absent, hence empty, in manifests written
    /// before code fingerprints).
    #[serde(default)]
    pub code: CodeRecord,
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
    /// SHA-256 of the manifest's canonical JSON without this field, so that
    /// any edit shows ([`Manifest::sealed`]). Absent in manifests written
    /// before it existed, which are checked without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub manifest_sha256: Option<String>,
}

impl Manifest {
    /// SHA-256 of the canonical JSON of everything but `manifest_sha256`.
    fn seal(&self) -> String {
        let unsealed = Manifest {
            manifest_sha256: None,
            ..self.clone()
        };
        let value = serde_json::to_value(&unsealed).unwrap_or(Value::Null);
        sha256_hex(canonical_json(&value).as_bytes())
    }

    /// The manifest with its seal set.
    pub fn sealed(self) -> Manifest {
        let seal = self.seal();
        Manifest {
            manifest_sha256: Some(seal),
            ..self
        }
    }
}

/// The last computation of a stage instance, for `status` to explain staleness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InstanceRef {
    /// Key computed last.
    pub key: String,
    /// The stage's code then (empty in refs written before code fingerprints).
    #[serde(default)]
    pub code: CodeRecord,
    /// Parameters then.
    pub params: Value,
    /// Inputs then.
    pub inputs: Vec<InputRecord>,
}

impl From<&Manifest> for InstanceRef {
    fn from(manifest: &Manifest) -> InstanceRef {
        InstanceRef {
            key: manifest.key.clone(),
            code: manifest.code.clone(),
            params: manifest.params.clone(),
            inputs: manifest.inputs.clone(),
        }
    }
}

/// How deeply [`Store::inspect`] checks an artifact.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Depth {
    /// Manifest, key, listing and file sizes: no file is read.
    Sizes,
    /// Also the SHA-256 of every file's bytes (what `run` and `status` use).
    Hashes,
    /// Also every table's content hash, decoded from its Parquet file (`verify`).
    Contents,
}

/// An artifact store rooted at a directory.
#[derive(Clone, Debug)]
pub struct Store {
    root: PathBuf,
    /// The id from the marker; `None` for a store read without one (a
    /// version-1 marker, or a damaged one), which then names no debris its own.
    id: Option<String>,
}

/// The exclusive store lock; released on drop.
pub struct StoreLock {
    _file: File,
}

/// `true` for a lower-case hex SHA-256 (an artifact key).
pub fn is_key(name: &str) -> bool {
    name.len() == 64 && name.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// `true` for a store id: 16 lower-case hex digits.
fn is_store_id(text: &str) -> bool {
    text.len() == 16 && text.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}

/// `true` for the staging names [`Store::begin`] of the store `id` creates:
/// `<key>.<id>.<writer>` and `<key>.<id>.<writer>.old`, the writer
/// `<pid>@<host>`. Names without the id (another store's, a user's, or
/// ternary's before stores had ids) are not.
fn is_staging_name(name: &str, id: &str) -> bool {
    let name = name.strip_suffix(".old").unwrap_or(name);
    let Some((key, rest)) = name.split_once('.') else {
        return false;
    };
    let Some(writer) = rest.strip_prefix(id).and_then(|w| w.strip_prefix('.')) else {
        return false;
    };
    is_key(key) && is_writer_name(writer)
}

/// `true` for a [`writer_name`]: `<pid>@<host>`.
fn is_writer_name(text: &str) -> bool {
    text.split_once('@').is_some_and(|(pid, host)| {
        !pid.is_empty()
            && pid.bytes().all(|b| b.is_ascii_digit())
            && !host.is_empty()
            && host
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'.')
    })
}

/// `true` when the staging entry `name` (or a temporary file's name ending
/// in `.<pid>`) was made by a process that still runs on this host: a run in
/// progress, not debris of an interrupted one.
pub fn is_live_staging(name: &str) -> bool {
    let name = name.strip_suffix(".old").unwrap_or(name);
    let ours = writer_name();
    let this_host = ours.split_once('@').map_or("", |(_, host)| host);
    let (pid, host) = match name.rsplit_once('@') {
        Some((rest, host)) => (rest.rsplit('.').next().unwrap_or_default(), host),
        None => (name.rsplit('.').next().unwrap_or_default(), this_host),
    };
    host == this_host
        && !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && Path::new("/proc").join(pid).exists()
}

/// `true` for a temporary marker of any store: `.ternary-store.json.<id>.<pid>`.
fn is_marker_temporary(name: &str) -> bool {
    name.strip_prefix(".ternary-store.json.")
        .and_then(|tag| tag.split_once('.'))
        .is_some_and(|(id, pid)| {
            is_store_id(id) && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

/// `<pid>@<host>`: names this process among writers on many nodes sharing a store.
fn writer_name() -> String {
    let host = fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let host: String = host
        .trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '.')
        .collect();
    let host = if host.is_empty() {
        "localhost".into()
    } else {
        host
    };
    format!("{}@{host}", std::process::id())
}

/// `true` for the temporary names [`write_atomically`] of the store `id`
/// creates for refs and the marker: `.<name>.json.<id>.<pid>`.
fn is_json_temporary(name: &str, id: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|rest| rest.rsplit_once(".json."))
        .and_then(|(file, tag)| Some((file, tag.strip_prefix(id)?.strip_prefix('.')?)))
        .is_some_and(|(file, pid)| {
            !file.is_empty() && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())
        })
}

impl Store {
    /// Opens the store at `root` for writing: a missing or empty directory
    /// becomes a new store (with its marker); a directory with files must
    /// carry our marker (a version-1 marker gets an id), or be provably a
    /// store whose marker was damaged ([`Store::is_damaged_store`]), or is
    /// refused, so nothing of a user's is ever treated as debris.
    pub fn open(root: &Path) -> Result<Store, StoreError> {
        let mut store = Store::view(root)?;
        if store.id.is_none() {
            fs::create_dir_all(root).map_err(io_error(root))?;
            // Under the exclusive lock, which debris cleaning also takes: a
            // concurrent run never removes the marker's temporary file.
            let _lock = store.lock()?;
            store.id = match store.marker_state()? {
                MarkerState::Ours(Some(id)) => Some(id),
                _ => {
                    for name in sorted_entries(root)? {
                        if is_marker_temporary(&name) {
                            let path = root.join(name);
                            fs::remove_file(&path).map_err(io_error(&path))?;
                        }
                    }
                    let marker = Marker::new(root);
                    let text =
                        serde_json::to_vec_pretty(&marker).map_err(|source| StoreError::Json {
                            path: store.marker_path(),
                            source,
                        })?;
                    let id = marker.id.clone();
                    store.id = id.clone();
                    write_atomically(&store.marker_path(), &text, &store.temporary_tag())?;
                    id
                }
            };
        }
        for dir in ["artifacts", "refs", "tmp"] {
            let path = root.join(dir);
            fs::create_dir_all(&path).map_err(io_error(&path))?;
        }
        Ok(store)
    }

    /// Opens an existing store for reading: nothing is created, a missing
    /// directory is an error, and a directory without our marker is refused
    /// as in [`Store::open`].
    pub fn open_existing(root: &Path) -> Result<Store, StoreError> {
        if !root.is_dir() {
            return Err(StoreError::Missing(root.to_path_buf()));
        }
        Store::view(root)
    }

    /// A store to read, where a missing directory reads as an empty store
    /// (`status` before the first run): nothing is created.
    pub fn view(root: &Path) -> Result<Store, StoreError> {
        let mut store = Store {
            root: root.to_path_buf(),
            id: None,
        };
        match store.marker_state()? {
            MarkerState::Ours(id) => store.id = id,
            MarkerState::Missing | MarkerState::NotOurs => {
                let entries = sorted_entries(root)?;
                // A concurrent run creating the store may have renamed its
                // marker into place between the read and the listing.
                if let MarkerState::Ours(id) = store.marker_state()? {
                    store.id = id;
                    return Ok(store);
                }
                let ours = entries.is_empty()
                    || store.is_interrupted_creation(&entries)
                    || store.is_damaged_store(&entries)?;
                if !ours {
                    return Err(StoreError::NotAStore {
                        path: root.to_path_buf(),
                        found: summarize(&entries),
                    });
                }
            }
        }
        Ok(store)
    }

    fn marker_path(&self) -> PathBuf {
        self.root.join(MARKER)
    }

    /// What the marker says; an error when it names a newer layout version.
    fn marker_state(&self) -> Result<MarkerState, StoreError> {
        let path = self.marker_path();
        let bytes = match fs::read(&path) {
            Ok(bytes) => bytes,
            Err(error) if error.kind() == io::ErrorKind::NotFound => {
                return Ok(MarkerState::Missing);
            }
            Err(error) => return Err(io_error(&path)(error)),
        };
        match serde_json::from_slice::<Marker>(&bytes) {
            Ok(marker) if marker.format == MARKER_FORMAT && marker.version > FORMAT_VERSION => {
                Err(StoreError::Marker {
                    path,
                    message: format!(
                        "the store has layout version {}, newer than this ternary reads ({FORMAT_VERSION}): use a newer ternary",
                        marker.version
                    ),
                })
            }
            Ok(marker)
                if marker.format == MARKER_FORMAT
                    && marker.id.as_deref().is_none_or(is_store_id) =>
            {
                Ok(MarkerState::Ours(marker.id))
            }
            _ => Ok(MarkerState::NotOurs),
        }
    }

    /// A store whose creation was killed before its marker was in place:
    /// only our lock file (empty or naming a writer `<pid>@<host>`) and
    /// temporary markers (`.ternary-store.json.<16 hex>.<pid>`).
    fn is_interrupted_creation(&self, entries: &[String]) -> bool {
        entries.iter().all(|entry| {
            if entry == "store.lock" {
                let holder = fs::read_to_string(self.root.join(entry)).unwrap_or_default();
                return holder.is_empty() || is_writer_name(&holder);
            }
            is_marker_temporary(entry)
        })
    }

    /// A store whose marker is missing or damaged: only the store's own
    /// top-level entries, at least one artifact, and every artifact under a
    /// key name with a sealed manifest that names it and lists exactly the
    /// files beside it. A user's folder shaped like a store (any JSON as a
    /// manifest, a file beside it) is not one.
    fn is_damaged_store(&self, entries: &[String]) -> Result<bool, StoreError> {
        if !entries.iter().all(|e| LAYOUT.contains(&e.as_str())) {
            return Ok(false);
        }
        let mut artifacts = 0;
        for stage in sorted_entries(&self.root.join("artifacts"))? {
            for key in sorted_entries(&self.root.join("artifacts").join(&stage))? {
                let dir = self.artifact_dir(&stage, &key);
                let sealed = is_key(&key)
                    && read_json::<Manifest>(&dir.join("manifest.json")).is_ok_and(|manifest| {
                        manifest.manifest_sha256.as_ref() == Some(&manifest.seal())
                            && manifest.key == key
                            && manifest.stage == stage
                            && self.foreign_in_artifact(&stage, &key, &[]).is_empty()
                    });
                if !sealed {
                    return Ok(false);
                }
                artifacts += 1;
            }
        }
        Ok(artifacts > 0)
    }

    /// `<id>.<pid>`: the tag of this process's temporary files.
    fn temporary_tag(&self) -> String {
        format!(
            "{}.{}",
            self.id.as_deref().unwrap_or("unknown"),
            std::process::id()
        )
    }

    /// The store root.
    pub fn root(&self) -> &Path {
        &self.root
    }

    fn lock_file(&self) -> Result<(File, PathBuf), StoreError> {
        let path = self.root.join("store.lock");
        let file = OpenOptions::new()
            .create(true)
            .truncate(false)
            .read(true)
            .write(true)
            .open(&path)
            .map_err(io_error(&path))?;
        Ok((file, path))
    }

    /// Says on stderr who holds the lock a call is about to wait for.
    fn announce_wait(path: &Path, what: &str) {
        let holder = fs::read_to_string(path).unwrap_or_default();
        let holder = match holder.trim() {
            "" => "another process".to_string(),
            writer => format!("process {writer}"),
        };
        eprintln!(
            "waiting for the store lock {} (held by {holder}) {what}...",
            path.display()
        );
    }

    /// Takes the exclusive lock (`gc`: no writer runs meanwhile), waiting
    /// with a message on stderr while another process holds it.
    pub fn lock(&self) -> Result<StoreLock, StoreError> {
        let (mut file, path) = self.lock_file()?;
        if file.try_lock().is_err() {
            Store::announce_wait(&path, "");
            file.lock().map_err(io_error(&path))?;
        }
        file.set_len(0).map_err(io_error(&path))?;
        write!(file, "{}", writer_name()).map_err(io_error(&path))?;
        Ok(StoreLock { _file: file })
    }

    /// Takes the lock of a writing run: shared with other runs (many writers,
    /// on many nodes, commit artifacts at once), exclusive of `gc`. When no
    /// other process holds it, first removes debris of interrupted runs.
    pub fn lock_for_writing(&self) -> Result<StoreLock, StoreError> {
        let (file, path) = self.lock_file()?;
        if file.try_lock().is_ok() {
            let lock = StoreLock { _file: file };
            self.clean_staging(&lock)?;
            lock._file.lock_shared().map_err(io_error(&path))?;
            return Ok(lock);
        }
        if file.try_lock_shared().is_err() {
            Store::announce_wait(&path, "for gc to finish ");
            file.lock_shared().map_err(io_error(&path))?;
        }
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

    /// Checks the artifact `key` of `stage` to `depth` and returns its
    /// manifest, or every problem found. `outputs`, when given, are the file
    /// names the stage writes: the manifest must list exactly those.
    pub fn inspect(
        &self,
        stage: &str,
        key: &str,
        outputs: Option<&[String]>,
        depth: Depth,
    ) -> Result<Manifest, Vec<String>> {
        let dir = self.artifact_dir(stage, key);
        if !dir.is_dir() {
            return Err(vec!["no artifact directory".to_string()]);
        }
        let manifest: Manifest = read_json(&dir.join("manifest.json"))
            .map_err(|error| vec![format!("unreadable manifest: {}", error_chain(&error))])?;
        let mut problems = manifest_problems(&manifest, stage, key, outputs);
        let listed: Vec<&str> = manifest.files.iter().map(|f| f.name.as_str()).collect();
        match sorted_entries(&dir) {
            Err(error) => problems.push(error_chain(&error)),
            Ok(present) => {
                // Entries the manifest does not list are a user's: reported by
                // `foreign_entries`, kept, and no damage to the listed files.
                for name in &listed {
                    if !present.iter().any(|p| p == name) {
                        problems.push(format!("{name}: missing"));
                    }
                }
            }
        }
        if problems.is_empty() {
            problems = manifest
                .files
                .par_iter()
                .flat_map_iter(|file| file_problems(&dir, file, depth))
                .collect();
        }
        if problems.is_empty() {
            Ok(manifest)
        } else {
            Err(problems)
        }
    }

    /// Starts writing the artifact `key` of `stage` in a fresh staging
    /// directory named for this writer.
    pub fn begin(&self, stage: &str, key: &str) -> Result<Staging, StoreError> {
        self.begin_as(stage, key, &writer_name())
    }

    /// [`Store::begin`] for the writer named `writer` (`<pid>@<host>`).
    fn begin_as(&self, stage: &str, key: &str, writer: &str) -> Result<Staging, StoreError> {
        let id = self.id.as_deref().unwrap_or("unknown");
        let dir = self.root.join("tmp").join(format!("{key}.{id}.{writer}"));
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
                .join(format!("{key}.{id}.{writer}.old")),
            files: Vec::new(),
            committed: false,
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
        let text = serde_json::to_vec_pretty(entry).map_err(|source| StoreError::Json {
            path: path.clone(),
            source,
        })?;
        let dir = path.parent().unwrap_or(&self.root).to_path_buf();
        fs::create_dir_all(&dir).map_err(io_error(&dir))?;
        write_atomically(&path, &text, &self.temporary_tag())
    }

    /// The last computed key of a stage instance, if any.
    pub fn read_ref(&self, stage: &str, instance: &str) -> Option<InstanceRef> {
        read_json(&self.ref_path(stage, instance)).ok()
    }

    /// The most recently written manifest of `stage` that names `instance`:
    /// what `status` explains staleness against when the ref is lost.
    pub fn latest_manifest_of(&self, stage: &str, instance: &str) -> Option<Manifest> {
        let keys = sorted_entries(&self.root.join("artifacts").join(stage)).ok()?;
        keys.into_iter()
            .filter(|key| is_key(key))
            .filter_map(|key| {
                let path = self.artifact_dir(stage, &key).join("manifest.json");
                let modified = fs::metadata(&path).and_then(|m| m.modified()).ok()?;
                let manifest: Manifest = read_json(&path).ok()?;
                (manifest.instance == instance).then_some((modified, manifest))
            })
            .max_by(|a, b| a.0.cmp(&b.0))
            .map(|(_, manifest)| manifest)
    }

    /// Every artifact directory as `(stage, key)`, sorted; entries that are
    /// not named like artifacts are left out (see [`Store::foreign_entries`]).
    pub fn artifacts(&self) -> Result<Vec<(String, String)>, StoreError> {
        let mut found = Vec::new();
        for stage in sorted_entries(&self.root.join("artifacts"))? {
            for key in sorted_entries(&self.root.join("artifacts").join(&stage))? {
                if is_key(&key) && self.artifact_dir(&stage, &key).is_dir() {
                    found.push((stage.clone(), key));
                }
            }
        }
        Ok(found)
    }

    /// Entries of the artifact directory `key` of `stage` that ternary did
    /// not write: not `manifest.json`, not listed in the manifest (none when
    /// it cannot be read) and not among `outputs` (the files the stage
    /// writes, when the caller knows them), sorted.
    pub fn foreign_in_artifact(&self, stage: &str, key: &str, outputs: &[String]) -> Vec<String> {
        let dir = self.artifact_dir(stage, key);
        let listed: Vec<String> = read_json::<Manifest>(&dir.join("manifest.json"))
            .map(|manifest| manifest.files.into_iter().map(|f| f.name).collect())
            .unwrap_or_default();
        sorted_entries(&dir)
            .unwrap_or_default()
            .into_iter()
            .filter(|name| {
                name != "manifest.json" && !listed.contains(name) && !outputs.contains(name)
            })
            .collect()
    }

    /// Moves the artifact directory `key` of `stage` aside, to
    /// `<key>.kept-<n>` beside it: not a key, so a foreign entry that no
    /// command removes. Returns where it went.
    pub fn set_aside(&self, stage: &str, key: &str) -> Result<PathBuf, StoreError> {
        let dir = self.artifact_dir(stage, key);
        let aside = (1u32..)
            .map(|n| dir.with_file_name(format!("{key}.kept-{n}")))
            .find(|path| !path.exists())
            .unwrap_or_else(|| dir.with_file_name(format!("{key}.kept")));
        fs::rename(&dir, &aside).map_err(io_error(&dir))?;
        Ok(aside)
    }

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
        for name in sorted_entries(&tmp)? {
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

    /// Removes staging debris. Call only while holding the lock.
    pub fn clean_staging(&self, _lock: &StoreLock) -> Result<usize, StoreError> {
        let debris = self.staging_debris()?;
        for path in &debris {
            let removed = if path.is_dir() {
                fs::remove_dir_all(path)
            } else {
                fs::remove_file(path)
            };
            removed.map_err(io_error(path))?;
        }
        Ok(debris.len())
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

/// Problems of a manifest as a document: it must name this artifact, its key
/// must follow from its stage, code fingerprint, parameters and inputs, and it must
/// list plain, unique file names (exactly `outputs` when given).
fn manifest_problems(
    manifest: &Manifest,
    stage: &str,
    key: &str,
    outputs: Option<&[String]>,
) -> Vec<String> {
    let mut problems = Vec::new();
    if manifest
        .manifest_sha256
        .as_ref()
        .is_some_and(|seal| *seal != manifest.seal())
    {
        problems.push("the manifest was edited (its manifest_sha256 no longer matches)".into());
    }
    if manifest.key != key || manifest.stage != stage {
        problems.push(format!(
            "manifest names {}/{}",
            manifest.stage, manifest.key
        ));
    }
    if manifest.code.fingerprint.is_empty() {
        problems.push(
            "written by an earlier ternary, before keys followed the code: no current key names it (`ternary gc` removes it)"
                .to_string(),
        );
    } else if stage_key(
        &manifest.stage,
        &manifest.code.fingerprint,
        &manifest.params,
        &manifest.inputs,
    ) != manifest.key
    {
        problems.push(
            "the manifest's code fingerprint, parameters or inputs do not give its key".to_string(),
        );
    }
    let mut names: Vec<&str> = manifest.files.iter().map(|f| f.name.as_str()).collect();
    if names.is_empty() {
        problems.push("the manifest lists no file".to_string());
    }
    if let Some(name) = names
        .iter()
        .find(|name| name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.'))
    {
        problems.push(format!(
            "the manifest lists `{name}`, not a plain file name"
        ));
    }
    names.sort_unstable();
    if names.windows(2).any(|pair| pair[0] == pair[1]) {
        problems.push("the manifest lists a file twice".to_string());
    }
    if let Some(problem) = outputs.and_then(|outputs| listing_problem(manifest, outputs)) {
        problems.push(problem);
    }
    problems
}

/// Whether `manifest` lists exactly the files `outputs` (the files its stage
/// instance writes), and if not, how they differ.
pub fn listing_problem(manifest: &Manifest, outputs: &[String]) -> Option<String> {
    let mut names: Vec<&str> = manifest.files.iter().map(|f| f.name.as_str()).collect();
    names.sort_unstable();
    let mut expected: Vec<&str> = outputs.iter().map(String::as_str).collect();
    expected.sort_unstable();
    (names != expected).then(|| {
        format!(
            "the manifest lists [{}] but the stage writes [{}]",
            names.join(", "),
            expected.join(", ")
        )
    })
}

/// Problems of one listed file, checked to `depth`.
fn file_problems(dir: &Path, file: &FileRecord, depth: Depth) -> Vec<String> {
    let path = dir.join(&file.name);
    let name = &file.name;
    let size = match fs::metadata(&path) {
        Ok(meta) => meta.len(),
        Err(error) => return vec![format!("{name}: {error}")],
    };
    if size != file.bytes {
        return vec![format!(
            "{name}: {size} bytes but the manifest records {}",
            file.bytes
        )];
    }
    let mismatch = |sha: String| {
        vec![format!(
            "{name}: sha256 {sha} but the manifest records {}",
            file.sha256
        )]
    };
    match depth {
        Depth::Sizes => {}
        Depth::Hashes => match sha256_of_file(&path) {
            Err(error) => return vec![format!("{name}: {error}")],
            Ok(sha) if sha != file.sha256 => return mismatch(sha),
            Ok(_) => {}
        },
        Depth::Contents => {
            let bytes = match fs::read(&path) {
                Ok(bytes) => bytes,
                Err(error) => return vec![format!("{name}: {error}")],
            };
            let sha = sha256_hex(&bytes);
            if sha != file.sha256 {
                return mismatch(sha);
            }
            return content_problems(file, bytes);
        }
    }
    Vec::new()
}

/// Lower-case hex SHA-256 of a file, read in 1 MiB pieces.
fn sha256_of_file(path: &Path) -> io::Result<String> {
    use sha2::{Digest, Sha256};
    use std::io::Read;
    let mut file = File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let read = file.read(&mut buffer)?;
        if read == 0 {
            break;
        }
        hasher.update(&buffer[..read]);
    }
    Ok(hex(&hasher.finalize()))
}

/// Problems of a file's table content against its recorded content hash.
fn content_problems(file: &FileRecord, bytes: Vec<u8>) -> Vec<String> {
    let name = &file.name;
    match content_sha256_of_file(name, bytes) {
        Err(error) => vec![format!("{name}: {}", error_chain(&error))],
        Ok(content) if content != file.content_sha256 => vec![format!(
            "{name}: content sha256 {content} but the manifest records {}",
            file.content_sha256
        )],
        Ok(_) => Vec::new(),
    }
}

/// An error and its causes on one line.
pub fn error_chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        text.push_str(": ");
        text.push_str(&cause.to_string());
        source = cause.source();
    }
    text
}

/// A few entry names of a directory, for messages.
fn summarize(entries: &[String]) -> String {
    let shown: Vec<&str> = entries.iter().take(4).map(String::as_str).collect();
    let more = entries.len().saturating_sub(shown.len());
    if more > 0 {
        format!("{} and {more} more", shown.join(", "))
    } else {
        shown.join(", ")
    }
}

/// An artifact being written. Nothing in it is visible until
/// [`Staging::commit`]; dropped uncommitted, it removes its directory.
pub struct Staging {
    dir: PathBuf,
    target: PathBuf,
    trash: PathBuf,
    files: Vec<FileRecord>,
    committed: bool,
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

fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    let mut file = File::create(path).map_err(io_error(path))?;
    file.write_all(bytes).map_err(io_error(path))?;
    file.sync_all().map_err(io_error(path))
}

/// Writes `path` by a synced temporary file `.<name>.<tag>` renamed over it,
/// then syncs the directory: readers see the old or the new file, never a part.
fn write_atomically(path: &Path, bytes: &[u8], tag: &str) -> Result<(), StoreError> {
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

fn sync_dir(path: &Path) -> Result<(), StoreError> {
    File::open(path)
        .and_then(|dir| dir.sync_all())
        .map_err(io_error(path))
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, StoreError> {
    let text = fs::read(path).map_err(io_error(path))?;
    serde_json::from_slice(&text).map_err(|source| StoreError::Json {
        path: path.to_path_buf(),
        source,
    })
}

/// The per-stage folders in `top` (`artifacts/`, `refs/`), sorted; any
/// other entry there is pushed to `foreign`.
fn stage_folders(top: &Path, foreign: &mut Vec<PathBuf>) -> Result<Vec<String>, StoreError> {
    let (folders, others): (Vec<String>, Vec<String>) = sorted_entries(top)?
        .into_iter()
        .partition(|name| top.join(name).is_dir());
    foreign.extend(others.into_iter().map(|name| top.join(name)));
    Ok(folders)
}

fn sorted_entries(dir: &Path) -> Result<Vec<String>, StoreError> {
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

/// File names an artifact's tables are written to.
pub fn table_files(tables: &[&str]) -> Vec<String> {
    tables
        .iter()
        .map(|name| format!("{name}.parquet"))
        .collect()
}

/// Sorted `(name, content sha256)` of a manifest's files: what a downstream key hashes.
pub fn content_hashes(manifest: &Manifest) -> Vec<(String, String)> {
    let mut files: Vec<(String, String)> = manifest
        .files
        .iter()
        .map(|f| (f.name.clone(), f.content_sha256.clone()))
        .collect();
    files.sort();
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest_of(key: &str, files: &[FileRecord]) -> Manifest {
        Manifest {
            key: key.to_string(),
            stage: "source".into(),
            code: CodeRecord {
                fingerprint: "c".into(),
                parts: Default::default(),
            },
            instance: "a".into(),
            params: Value::Null,
            inputs: Vec::new(),
            files: files.to_vec(),
            tool: "test".into(),
            wall_seconds: 0.0,
            manifest_sha256: None,
        }
    }

    /// Two writers of one key: the first commits, the second keeps the
    /// first's artifact and leaves no staging behind; different bytes under
    /// one key are an error, not a silent overwrite.
    #[test]
    fn a_second_writer_of_a_key_keeps_the_first_copy() {
        let root = std::env::temp_dir().join(format!("ternary-race-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        let store = Store::open(&root).unwrap();
        let key = stage_key("source", "c", &Value::Null, &[]);
        let write = |bytes: &[u8], writer: &str| {
            let mut staging = store.begin_as("source", &key, writer).unwrap();
            staging
                .write_file("value.bin", bytes, 1, "c".into())
                .unwrap();
            let manifest = manifest_of(&key, staging.files());
            (staging, manifest)
        };
        let (first, first_manifest) = write(b"one", "1@node-a");
        let (second, second_manifest) = write(b"one", "1@node-b");
        let (third, third_manifest) = write(b"two", "2@node-a");
        let committed = first.commit(first_manifest, false).unwrap();
        let kept = second.commit(second_manifest, false).unwrap();
        assert_eq!(kept.manifest_sha256, committed.manifest_sha256);
        assert!(matches!(
            third.commit(third_manifest, false),
            Err(StoreError::Diverged(_))
        ));
        assert!(store.staging_debris().unwrap().is_empty());
        assert!(store.inspect("source", &key, None, Depth::Hashes).is_ok());
    }

    /// A manifest written before keys followed the code (a stage version, no
    /// code record) is named as such, not as an edit.
    #[test]
    fn a_manifest_from_before_code_fingerprints_is_named_as_such() {
        let mut old = serde_json::to_value(manifest_of(&"a".repeat(64), &[])).unwrap();
        let object = old.as_object_mut().unwrap();
        object.remove("code");
        object.insert("version".into(), 3.into());
        let manifest: Manifest = serde_json::from_value(old).unwrap();
        let problems = manifest_problems(&manifest, "source", &"a".repeat(64), None);
        assert!(
            problems
                .iter()
                .any(|p| p.contains("written by an earlier ternary")),
            "{problems:?}"
        );
        assert!(!problems.iter().any(|p| p.contains("do not give its key")));
    }

    /// `verify` during a run called that run's staging "from interrupted
    /// runs": a staging entry of a running process on this host is live.
    #[test]
    fn a_running_writers_staging_is_live_and_a_dead_ones_is_not() {
        let key = "a".repeat(64);
        let live = format!("{key}.0123456789abcdef.{}", writer_name());
        assert!(is_live_staging(&live));
        assert!(is_live_staging(&format!("{live}.old")));
        let dead = (100_000..u32::MAX)
            .find(|pid| !Path::new("/proc").join(pid.to_string()).exists())
            .unwrap();
        let host = writer_name().split_once('@').unwrap().1.to_string();
        assert!(!is_live_staging(&format!(
            "{key}.0123456789abcdef.{dead}@{host}"
        )));
        let elsewhere = format!("{key}.0123456789abcdef.{}@another-host", std::process::id());
        assert!(!is_live_staging(&elsewhere));
    }

    #[test]
    fn only_ternary_names_are_staging_or_ref_debris() {
        let key = "a".repeat(64);
        let id = "0123456789abcdef";
        assert!(is_staging_name(
            &format!("{key}.{id}.123@node-7.cluster"),
            id
        ));
        assert!(is_staging_name(&format!("{key}.{id}.123@node-7.old"), id));
        assert!(!is_staging_name(&format!("{key}.{id}.123@node/7"), id));
        // Without this store's id: another store's, a user's, or from
        // before stores had ids.
        assert!(!is_staging_name(&format!("{key}.123@node-7"), id));
        assert!(!is_staging_name(&format!("{key}.123"), id));
        assert!(!is_staging_name(&format!("{key}.fedcba9876543210.1@n"), id));
        assert!(!is_staging_name("my_project", id));
        assert!(!is_staging_name(&format!("{key}.{id}.x1@n"), id));
        assert!(!is_staging_name(
            &format!("{}.{id}.123@n", "A".repeat(64)),
            id
        ));
        assert!(is_json_temporary(&format!(".ipp-6.json.{id}.77"), id));
        assert!(!is_json_temporary(".ipp-6.json.77", id));
        assert!(!is_json_temporary("ipp-6.json", id));
        assert!(!is_json_temporary(".notes.json.bak", id));
    }
}
