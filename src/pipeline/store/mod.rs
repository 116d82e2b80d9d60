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
//!
//! One concern per file: opening and locking a store (`open`), reading and
//! writing artifacts and refs (`artifacts`), checking an artifact before it
//! is trusted (`check`), staging and committing (`staging`), what `gc` and
//! `verify` find (`gc`), the names ternary gives (`names`) and the file
//! steps they are built from (`files`); this file holds the types they share.

mod artifacts;
mod check;
mod files;
mod gc;
mod names;
mod open;
mod outside;
mod staging;

pub use check::listing_problem;
pub use files::write_atomically;
pub use names::{is_key, is_live_staging};
pub use outside::OutsideStaging;
pub use staging::Staging;

use std::fmt;
use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::pipeline::code::CodeRecord;
use crate::pipeline::key::{InputRecord, canonical_json, sha256_hex};

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
    /// A stage's or an instance's name cannot name a file inside the store
    /// (the configuration refuses such names; this is the store's own check).
    #[error("{root}: {message}")]
    Name {
        /// The store root.
        root: PathBuf,
        /// Which name and why.
        message: String,
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
    /// CPU time of the computation in seconds, every thread of the process
    /// that ran it (absent where the platform does not tell, and in
    /// manifests written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_seconds: Option<f64>,
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
    /// Where it reports waits ([`Store::reporting_to`]).
    reporter: Reporter,
}

/// Something a store reports while it works, for its user to hear of (the
/// command line prints it on stderr).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StoreEvent {
    /// A call is about to wait for the store lock.
    WaitingForLock {
        /// The lock file.
        path: PathBuf,
        /// Who holds it: `process <pid>@<host>`, or `another process`.
        holder: String,
        /// What the wait is for: empty, or `for gc to finish `.
        purpose: &'static str,
    },
}

impl fmt::Display for StoreEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StoreEvent::WaitingForLock {
                path,
                holder,
                purpose,
            } => write!(
                f,
                "waiting for the store lock {} (held by {holder}) {purpose}...",
                path.display()
            ),
        }
    }
}

/// Where a store sends its [`StoreEvent`]s: nowhere unless
/// [`Store::reporting_to`] names a sink.
#[derive(Clone, Default)]
struct Reporter(Option<Arc<Sink>>);

/// A receiver of [`StoreEvent`]s, shared by the clones of a store.
type Sink = dyn Fn(&StoreEvent) + Send + Sync;

impl Reporter {
    /// Hands `event` to the sink, if there is one.
    fn report(&self, event: StoreEvent) {
        if let Some(sink) = &self.0 {
            sink(&event);
        }
    }
}

impl fmt::Debug for Reporter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let to = if self.0.is_some() {
            "a sink"
        } else {
            "nowhere"
        };
        write!(f, "Reporter({to})")
    }
}

/// The exclusive store lock; released on drop.
pub struct StoreLock {
    _file: File,
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
    use super::check::manifest_problems;
    use super::*;
    use crate::pipeline::key::stage_key;
    use std::fs;

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
            cpu_seconds: None,
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
}
