//! Opening a store (creating it, or recognising it by its marker) and
//! taking its lock.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::files::*;
use super::names::*;
use super::*;
use crate::pipeline::key::sha256_hex;

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

impl Store {
    /// Opens the store at `root` for writing: a missing or empty directory
    /// becomes a new store (with its marker); a directory with files must
    /// carry our marker (a version-1 marker gets an id), or be provably a
    /// store whose marker was damaged (`Store::is_damaged_store`), or is
    /// refused, so nothing of a user's is ever treated as debris.
    pub fn open(root: &Path) -> Result<Store, StoreError> {
        Store::view(root)?.writable()
    }

    /// The viewed store made writable as [`Store::open`] says: created (with
    /// its marker) when missing or empty, its layout completed.
    pub fn writable(self) -> Result<Store, StoreError> {
        let root = self.root.clone();
        let root = root.as_path();
        let mut store = self;
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
            reporter: Reporter::default(),
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
    pub(super) fn temporary_tag(&self) -> String {
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

    /// The store, reporting what it does (a wait for its lock) to `sink`.
    pub fn reporting_to(mut self, sink: impl Fn(&StoreEvent) + Send + Sync + 'static) -> Store {
        self.reporter = Reporter(Some(Arc::new(sink)));
        self
    }

    /// Reports who holds the lock a call is about to wait for, and `purpose`.
    fn announce_wait(&self, path: &Path, purpose: &'static str) {
        let holder = fs::read_to_string(path).unwrap_or_default();
        let holder = match holder.trim() {
            "" => "another process".to_string(),
            writer => format!("process {writer}"),
        };
        self.reporter.report(StoreEvent::WaitingForLock {
            path: path.to_path_buf(),
            holder,
            purpose,
        });
    }

    /// Takes the exclusive lock (`gc`: no writer runs meanwhile), waiting
    /// (and reporting the wait) while another process holds it.
    pub fn lock(&self) -> Result<StoreLock, StoreError> {
        let (mut file, path) = self.lock_file()?;
        if file.try_lock().is_err() {
            self.announce_wait(&path, "");
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
            self.announce_wait(&path, "for gc to finish ");
            file.lock_shared().map_err(io_error(&path))?;
        }
        Ok(StoreLock { _file: file })
    }
}
