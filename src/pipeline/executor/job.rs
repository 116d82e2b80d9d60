//! Computing one instance: its inputs read and checked against their
//! manifests, the stage run (whole or by shards), its tables and files
//! written and committed.

use std::collections::{BTreeMap, VecDeque};
use std::io::IsTerminal;
use std::ops::Range;
use std::path::Path;
use std::sync::Mutex;

use arrow_array::RecordBatch;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use super::*;
use crate::pipeline::clock::{CpuAccount, Stopwatch};
use crate::pipeline::key::sha256_hex;
use crate::pipeline::shards;
use crate::pipeline::store::{FileRecord, InstanceRef, Manifest, Staging, Store, table_files};
use crate::pipeline::table::{TableError, is_table_file, read_parquet_bytes};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};

/// The progress bars of a run's instances under way, on a terminal unless
/// the run is quiet.
pub(super) fn progress_bars(verbosity: Verbosity) -> Option<MultiProgress> {
    (verbosity != Verbosity::Quiet && std::io::stderr().is_terminal()).then(MultiProgress::new)
}

/// The progress of computing `stage`: a bar among `bars`, if any.
pub(super) fn progress_for(stage: &dyn Stage, bars: Option<&MultiProgress>) -> Progress {
    let Some(bars) = bars else {
        return Progress::hidden();
    };
    let bar = bars.add(ProgressBar::new(stage.work_units()));
    let style =
        ProgressStyle::with_template("{prefix:<24} [{bar:30}] {pos}/{len} {elapsed} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    bar.set_prefix(stage.id().to_string());
    Progress { bar: Some(bar) }
}

/// Tables decoded during one run, by the SHA-256 of their file's bytes: a
/// table that several stages read (a potential's events feed its kernel and
/// moments at every `u'` and density) is hashed and decoded once. The most
/// recently read are kept, up to [`DECODED_BUDGET`] bytes in all. Only bytes
/// that matched their manifest's hash are decoded, so a hit is such bytes.
/// Instances computed at once take turns: one that waits while another
/// decodes the table it reads finds it decoded.
#[derive(Default)]
pub(super) struct DecodedTables {
    recent: Mutex<VecDeque<(String, RecordBatch)>>,
}

/// Memory the decoded tables of a run may keep: a few event sets of the
/// default study (~300 MB each).
const DECODED_BUDGET: usize = 1 << 30;

impl DecodedTables {
    /// The table of `file` in `dir`: kept, or read, checked and decoded.
    fn get(
        &self,
        id: &InstanceId,
        dir: &Path,
        file: &FileRecord,
    ) -> Result<RecordBatch, ExecError> {
        // A thread that panicked while holding the list left it whole (each
        // change is one push, remove or retain).
        let mut recent = self
            .recent
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(at) = recent.iter().position(|(sha, _)| sha == &file.sha256) {
            let entry = recent.remove(at).expect("position is inside");
            recent.push_front(entry.clone());
            return Ok(entry.1);
        }
        let bytes = read_checked(id, dir, file)?;
        let (batch, _) =
            read_parquet_bytes(&file.name, bytes).map_err(|source| ExecError::Input {
                id: id.clone(),
                source,
            })?;
        recent.push_front((file.sha256.clone(), batch.clone()));
        let mut kept = 0;
        recent.retain(|(_, table)| {
            kept += table.get_array_memory_size();
            kept <= DECODED_BUDGET
        });
        Ok(batch)
    }
}

/// Reads the input tables of `stage`, hashing each file's bytes against its
/// manifest before decoding them: nothing damaged since it was checked is used.
pub(super) fn load_inputs(
    store: &Store,
    stage: &dyn Stage,
    resolved: &BTreeMap<InstanceId, Manifest>,
    decoded: &DecodedTables,
) -> Result<Vec<Input>, ExecError> {
    let id = stage.id();
    stage
        .inputs()
        .into_iter()
        .map(|input| {
            let manifest = &resolved[&input];
            let dir = store.artifact_dir(&input.stage, &manifest.key);
            let mut tables = BTreeMap::new();
            for file in manifest.files.iter().filter(|f| is_table_file(&f.name)) {
                let batch = decoded.get(&id, &dir, file)?;
                tables.insert(file.name.trim_end_matches(".parquet").to_string(), batch);
            }
            Ok(Input { id: input, tables })
        })
        .collect()
}

/// The bytes of `file` in `dir`, hashed against the manifest's record: an
/// input damaged since it was checked is refused.
fn read_checked(id: &InstanceId, dir: &Path, file: &FileRecord) -> Result<Vec<u8>, ExecError> {
    let path = dir.join(&file.name);
    let damaged = |detail: String| ExecError::DamagedInput {
        id: id.clone(),
        file: path.display().to_string(),
        detail,
    };
    let bytes = std::fs::read(&path).map_err(|error| damaged(error.to_string()))?;
    let sha = sha256_hex(&bytes);
    if sha != file.sha256 {
        return Err(damaged(format!("sha256 {sha}, recorded {}", file.sha256)));
    }
    Ok(bytes)
}

fn stage_failure(id: &InstanceId) -> impl Fn(TableError) -> ExecError + '_ {
    move |source| ExecError::Stage {
        id: id.clone(),
        source: source.into(),
    }
}

/// The shard of `stage`'s artifact `whole` over `units`.
pub(super) fn stored_shard(
    store: &Store,
    stage: &dyn Stage,
    whole: &InstanceRef,
    units: &Range<u32>,
) -> Stored {
    let shard = shards::shard_entry(stage, whole, units);
    let stage_name = shards::shard_stage(&stage.id().stage);
    inspected(
        store,
        &stage_name,
        &shard.key,
        &table_files(stage.shard_tables()),
    )
}

/// One instance to compute: the store, the stage, its resolved inputs.
pub(super) struct Job<'a> {
    pub(super) store: &'a Store,
    pub(super) stage: &'a dyn Stage,
    pub(super) resolved: &'a BTreeMap<InstanceId, Manifest>,
    pub(super) options: &'a RunOptions,
    pub(super) decoded: &'a DecodedTables,
    /// The run's progress bars, if shown.
    pub(super) bars: Option<&'a MultiProgress>,
    /// The instance's share of the process's CPU time.
    pub(super) cpu: &'a CpuAccount<'a>,
}

impl Job<'_> {
    /// Computes and commits the whole artifact of `entry`: directly, or for a
    /// sharded run from its shards (computing those still missing, then
    /// concatenating them in order). `replace` moves a damaged or forced
    /// artifact of the key aside.
    pub(super) fn compute(
        &self,
        entry: &InstanceRef,
        replace: bool,
    ) -> Result<(Manifest, f64), ExecError> {
        let id = self.stage.id();
        let started = Stopwatch::start(self.cpu);
        let mut staging = self.store.begin(&id.stage, &entry.key)?;
        let shards = shards::ranges(self.stage.shard_units(), self.options.sharding.shards);
        let tables = if shards.len() > 1 {
            let mut parts = Vec::new();
            for (_, units) in &shards {
                parts.push(self.shard_tables(entry, units)?);
            }
            self.stage.merge(parts).map_err(|source| ExecError::Stage {
                id: id.clone(),
                source,
            })?
        } else {
            let loaded = load_inputs(self.store, self.stage, self.resolved, self.decoded)?;
            self.produce(self.stage.tables(), |progress| {
                self.stage.run(&loaded, progress)
            })?
        };
        let files = self.rendered(&tables)?;
        for (name, bytes) in &files {
            let content = sha256_hex(bytes);
            staging.write_file(name, bytes, 0, content)?;
        }
        let manifest = self.write(&mut staging, &id, entry, &tables, started)?;
        let manifest = staging.commit(manifest, replace)?;
        self.store.write_ref(&id.stage, &id.instance, entry)?;
        Ok((manifest, started.wall_seconds()))
    }

    /// Every file of `entry`'s artifact, computed from the stored inputs in
    /// memory (unsharded: a merge of shards must give the same bytes).
    pub(super) fn recomputed_files(
        &self,
        entry: &InstanceRef,
    ) -> Result<Vec<(String, Vec<u8>)>, ExecError> {
        let id = self.stage.id();
        let loaded = load_inputs(self.store, self.stage, self.resolved, self.decoded)?;
        let tables = self.produce(self.stage.tables(), |progress| {
            self.stage.run(&loaded, progress)
        })?;
        let mut files = self.rendered(&tables)?;
        for table in encoded_tables(&id, entry, &tables).map_err(stage_failure(&id))? {
            files.push((table.file, table.bytes));
        }
        Ok(files)
    }

    /// The stage's files drawn from `tables`, checked against the declared names.
    fn rendered(&self, tables: &[Table]) -> Result<Vec<(String, Vec<u8>)>, ExecError> {
        let id = self.stage.id();
        let files = self
            .stage
            .render(tables)
            .map_err(|source| ExecError::Stage {
                id: id.clone(),
                source,
            })?;
        let written: Vec<&str> = files.iter().map(|(name, _)| name.as_str()).collect();
        let declared = self.stage.files();
        let declared: Vec<&str> = declared.iter().map(String::as_str).collect();
        as_declared("drew files", written, declared)
            .map_err(|source| ExecError::Stage { id, source })?;
        Ok(files)
    }

    /// A shard task: computes and commits shard `index` of `entry` when it is
    /// missing; its wall time, or `None` when it was there (or is empty).
    pub(super) fn shard(&self, entry: &InstanceRef, index: u32) -> Result<Option<f64>, ExecError> {
        let sharding = self.options.sharding;
        let units = shards::range(self.stage.shard_units(), sharding.shards, index);
        if units.is_empty() || matches!(self.stored_shard(entry, &units), Stored::Intact(_)) {
            return Ok(None);
        }
        let started = Stopwatch::start(self.cpu);
        self.compute_shard(entry, &units)?;
        Ok(Some(started.wall_seconds()))
    }

    /// The shard of `entry` over `units`.
    fn stored_shard(&self, entry: &InstanceRef, units: &Range<u32>) -> Stored {
        stored_shard(self.store, self.stage, entry, units)
    }

    /// Computes and commits the shard of `entry` over `units`.
    fn compute_shard(
        &self,
        entry: &InstanceRef,
        units: &Range<u32>,
    ) -> Result<Manifest, ExecError> {
        let id = self.stage.id();
        let shard = shards::shard_entry(self.stage, entry, units);
        let shard_id = InstanceId::new(
            &shards::shard_stage(&id.stage),
            &shards::shard_instance(&id.instance, units),
        );
        let started = Stopwatch::start(self.cpu);
        let mut staging = self.store.begin(&shard_id.stage, &shard.key)?;
        let loaded = load_inputs(self.store, self.stage, self.resolved, self.decoded)?;
        let tables = self.produce(self.stage.shard_tables(), |progress| {
            self.stage.run_shard(&loaded, units.clone(), progress)
        })?;
        let manifest = self.write(&mut staging, &shard_id, &shard, &tables, started)?;
        let replace = self
            .store
            .artifact_dir(&shard_id.stage, &shard.key)
            .is_dir();
        Ok(staging.commit(manifest, replace)?)
    }

    /// The tables of the shard of `entry` over `units`, computed first when missing.
    fn shard_tables(
        &self,
        entry: &InstanceRef,
        units: &Range<u32>,
    ) -> Result<Vec<Table>, ExecError> {
        let manifest = match self.stored_shard(entry, units).intact() {
            Some(manifest) => manifest,
            None => self.compute_shard(entry, units)?,
        };
        let dir = self.store.artifact_dir(&manifest.stage, &manifest.key);
        manifest
            .files
            .iter()
            .map(|file| {
                let bytes = read_checked(&self.stage.id(), &dir, file)?;
                Table::from_parquet(&file.name, bytes).map_err(stage_failure(&self.stage.id()))
            })
            .collect()
    }

    /// Runs `compute` with a progress bar and checks it wrote the `declared` tables.
    fn produce(
        &self,
        declared: &[&str],
        compute: impl FnOnce(&Progress) -> Result<Vec<Table>, StageError>,
    ) -> Result<Vec<Table>, ExecError> {
        let id = self.stage.id();
        let progress = progress_for(self.stage, self.bars);
        let tables = compute(&progress).map_err(|source| ExecError::Stage {
            id: id.clone(),
            source,
        })?;
        if let Some(bar) = progress.bar {
            bar.finish_and_clear();
        }
        let written: Vec<&str> = tables.iter().map(|t| t.name.as_str()).collect();
        as_declared("wrote tables", written, declared.to_vec())
            .map_err(|source| ExecError::Stage { id, source })?;
        Ok(tables)
    }

    /// Writes `tables`, encoded with their provenance, into `staging` and
    /// returns the manifest of the artifact `id` under `entry`'s key.
    fn write(
        &self,
        staging: &mut Staging,
        id: &InstanceId,
        entry: &InstanceRef,
        tables: &[Table],
        started: Stopwatch<'_>,
    ) -> Result<Manifest, ExecError> {
        for table in encoded_tables(id, entry, tables).map_err(stage_failure(id))? {
            staging.write_file(&table.file, &table.bytes, table.rows, table.content_sha256)?;
        }
        Ok(Manifest {
            key: entry.key.clone(),
            stage: id.stage.clone(),
            code: entry.code.clone(),
            instance: id.instance.clone(),
            params: entry.params.clone(),
            inputs: entry.inputs.clone(),
            files: staging.files().to_vec(),
            tool: tool_version(),
            wall_seconds: started.wall_seconds(),
            cpu_seconds: started.cpu_seconds(),
            manifest_sha256: None,
        })
    }
}
