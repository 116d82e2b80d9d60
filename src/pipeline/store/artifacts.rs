//! Reading and writing artifacts and refs.

use std::fs;
use std::path::PathBuf;

use rayon::prelude::*;

use super::check::*;
use super::files::*;
use super::names::*;
use super::*;
use crate::pipeline::path_names::joined_inside;

impl Store {
    /// Directory of the artifact `key` of `stage`.
    pub fn artifact_dir(&self, stage: &str, key: &str) -> PathBuf {
        self.root.join("artifacts").join(stage).join(key)
    }

    /// The ref of a stage instance, `refs/<stage>/<instance>.json`, checked
    /// to lie inside the store whatever the names hold.
    fn ref_path(&self, stage: &str, instance: &str) -> Result<PathBuf, StoreError> {
        joined_inside(&self.root, &format!("refs/{stage}/{instance}.json")).map_err(|message| {
            StoreError::Name {
                root: self.root.clone(),
                message,
            }
        })
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

    /// The staging directory `tmp/<key>.<id>.<writer><suffix>` of this
    /// store (`suffix` empty, or `.old` for an artifact set aside): the one
    /// naming of [`is_staging_name`], which the next locked command removes.
    pub(super) fn staging_dir(&self, key: &str, writer: &str, suffix: &str) -> PathBuf {
        let id = self.id.as_deref().unwrap_or("unknown");
        self.root
            .join("tmp")
            .join(format!("{key}.{id}.{writer}{suffix}"))
    }

    /// [`Store::begin`] for the writer named `writer` (`<pid>@<host>`).
    pub(super) fn begin_as(
        &self,
        stage: &str,
        key: &str,
        writer: &str,
    ) -> Result<Staging, StoreError> {
        joined_inside(&self.root, &format!("artifacts/{stage}/{key}")).map_err(|message| {
            StoreError::Name {
                root: self.root.clone(),
                message,
            }
        })?;
        let dir = self.staging_dir(key, writer, "");
        if dir.exists() {
            fs::remove_dir_all(&dir).map_err(io_error(&dir))?;
        }
        fs::create_dir_all(&dir).map_err(io_error(&dir))?;
        Ok(Staging {
            dir,
            target: self.artifact_dir(stage, key),
            trash: self.staging_dir(key, writer, ".old"),
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
        let path = self.ref_path(stage, instance)?;
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
        read_json(&self.ref_path(stage, instance).ok()?).ok()
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
}
