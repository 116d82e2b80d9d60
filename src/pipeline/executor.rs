//! Runs the stale part of a DAG of stage instances, and explains what is
//! fresh, stale or missing (`status`).
//!
//! Instances are given in topological order. An instance's key is computed from
//! its stage name, code fingerprint, parameters and the file hashes of its inputs; if the
//! store holds an intact artifact under that key (checked down to its file
//! hashes) it is fresh, otherwise it is computed and committed atomically.

use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::io::{ErrorKind, IsTerminal, Write};
use std::ops::Range;
use std::path::Path;
use std::time::Instant;

use arrow::array::RecordBatch;
use indicatif::{ProgressBar, ProgressStyle};

use super::code::CodeRecord;
use super::key::{InputRecord, changed_params, sha256_hex, stage_key};
use super::shards::{self, Sharding};
use super::store::{
    Depth, FileRecord, InstanceRef, Manifest, Staging, Store, StoreError, StoreLock,
    content_hashes, table_files,
};
use super::table::{PROVENANCE_KEYS, TableError, is_table_file, read_parquet_bytes};
use super::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};

/// A run could not proceed.
#[derive(Debug, thiserror::Error)]
pub enum ExecError {
    /// The store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A stage failed.
    #[error("{id}")]
    Stage {
        /// The instance.
        id: InstanceId,
        /// The cause.
        source: StageError,
    },
    /// An input artifact could not be read.
    #[error("{id}: reading input")]
    Input {
        /// The instance.
        id: InstanceId,
        /// The cause.
        source: TableError,
    },
    /// An input file changed after it was checked.
    #[error(
        "{id}: input {file} no longer hashes to its manifest ({detail}); run again to repair it"
    )]
    DamagedInput {
        /// The instance.
        id: InstanceId,
        /// The input file.
        file: String,
        /// What differs.
        detail: String,
    },
    /// The store cannot be written and an instance needs computing.
    #[error("{id} needs computing, but the store cannot be written ({reason})")]
    ReadOnly {
        /// The instance.
        id: InstanceId,
        /// Why the store is read-only.
        reason: String,
    },
    /// The DAG or the options are inconsistent.
    #[error("{0}")]
    Plan(String),
}

/// How a run reports progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verbosity {
    /// Progress bars on a terminal, and a line per instance that was not
    /// already fresh (computed, skipped, a shard).
    Normal,
    /// As [`Verbosity::Normal`], with a line for every fresh instance too.
    Detailed,
    /// Only errors.
    Quiet,
}

/// Options of `ternary run`.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Run only instances of these stages (all when empty).
    pub only: Vec<String>,
    /// Recompute instances of these stages even when fresh.
    pub force: Vec<String>,
    /// Reporting.
    pub verbosity: Verbosity,
    /// How shardable stages are split.
    pub sharding: Sharding,
}

/// What the executor did with one instance.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// An intact artifact with the current key existed.
    Fresh,
    /// Computed and committed.
    Computed {
        /// Wall time, seconds.
        seconds: f64,
        /// The problems of a damaged artifact under the same key that it replaced.
        repaired: Option<String>,
        /// Where the artifact it replaced went, with the entries in it that
        /// ternary did not write (kept, never deleted).
        set_aside: Option<String>,
    },
    /// Not selected by `--only` (or not shardable in a shard task) and not fresh.
    Skipped,
    /// A shard task's shard of this instance: computed (seconds) or already
    /// there (`None`).
    Shard {
        /// The shard's index.
        index: u32,
        /// Wall time when computed now.
        seconds: Option<f64>,
    },
}

impl Action {
    /// `true` when the instance's artifact is in the store after the run.
    pub fn has_artifact(&self) -> bool {
        matches!(self, Action::Fresh | Action::Computed { .. })
    }
}

/// One line of a run report.
#[derive(Clone, Debug)]
pub struct InstanceReport {
    /// The instance.
    pub id: InstanceId,
    /// Its key, when its inputs were available.
    pub key: Option<String>,
    /// What happened.
    pub action: Action,
}

/// Freshness of one instance, as `status` reports it.
#[derive(Clone, Debug, PartialEq)]
pub enum Freshness {
    /// Up to date.
    Fresh,
    /// Computed before, but something it depends on changed.
    Stale(Vec<String>),
    /// Its artifact exists under the current key but fails its checks.
    Damaged(Vec<String>),
    /// Never computed, or its artifact is gone.
    Missing(String),
}

impl Freshness {
    /// `fresh`, `stale`, `damaged` or `missing`.
    pub fn name(&self) -> &'static str {
        match self {
            Freshness::Fresh => "fresh",
            Freshness::Stale(_) => "stale",
            Freshness::Damaged(_) => "damaged",
            Freshness::Missing(_) => "missing",
        }
    }
}

/// Checks that ids are unique, inputs precede their consumers, and stage names
/// in `names` exist.
pub fn check_plan(stages: &[Box<dyn Stage>], names: &[String]) -> Result<(), ExecError> {
    let mut seen: BTreeSet<InstanceId> = BTreeSet::new();
    for stage in stages {
        let id = stage.id();
        if seen.contains(&id) {
            return Err(ExecError::Plan(format!("{id} is defined twice")));
        }
        if let Some(input) = stage
            .inputs()
            .into_iter()
            .find(|input| !seen.contains(input))
        {
            return Err(ExecError::Plan(format!(
                "{id} reads {input}, which is not defined before it"
            )));
        }
        seen.insert(id);
    }
    check_stage_names(stages, names).map_err(ExecError::Plan)
}

/// Checks that every name in `names` is a stage of `stages`; otherwise says
/// which is not, listing the stages and suggesting the nearest.
pub fn check_stage_names(stages: &[Box<dyn Stage>], names: &[String]) -> Result<(), String> {
    let ids: Vec<InstanceId> = stages.iter().map(|stage| stage.id()).collect();
    match names
        .iter()
        .find(|name| !ids.iter().any(|id| &id.stage == *name))
    {
        Some(name) => Err(unknown_stage(name, &ids)),
        None => Ok(()),
    }
}

/// Why `name` names no stage of `ids`: each stage once, in order of first
/// appearance, and the nearest one when `name` looks like a typo of it.
fn unknown_stage(name: &str, ids: &[InstanceId]) -> String {
    let names = stage_names(ids);
    let hint =
        nearest(name, &names).map_or(String::new(), |near| format!("; did you mean `{near}`?"));
    format!(
        "unknown stage `{name}`{hint} (stages are: {})",
        names.join(", ")
    )
}

/// The stages of `ids`, each once, in order of first appearance.
fn stage_names(ids: &[InstanceId]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for id in ids {
        if !names.contains(&id.stage.as_str()) {
            names.push(&id.stage);
        }
    }
    names
}

/// The candidate closest to `typed` by edit distance, when at most a third
/// of the typed characters (at least one) must change to reach it: further
/// away, a suggestion is a guess.
fn nearest<'a>(typed: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let allowed = (typed.chars().count() / 3).max(1);
    candidates
        .iter()
        .map(|&candidate| (edit_distance(typed, candidate), candidate))
        .filter(|&(distance, _)| distance <= allowed)
        .min_by_key(|&(distance, _)| distance)
        .map(|(_, candidate)| candidate)
}

/// Levenshtein distance: the fewest insertions, deletions and substitutions
/// of characters that turn `a` into `b`.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    // `row[j]`: distance from the prefix of `a` read so far to `b[..j]`.
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, a_char) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &b_char) in b.iter().enumerate() {
            let substitution = diagonal + usize::from(a_char != b_char);
            diagonal = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

/// Input records of `stage` from the manifests resolved so far; `None` while an
/// input is unavailable.
fn input_records(
    stage: &dyn Stage,
    resolved: &BTreeMap<InstanceId, Manifest>,
) -> Option<Vec<InputRecord>> {
    stage
        .inputs()
        .iter()
        .map(|input| {
            let manifest = resolved.get(input)?;
            Some(InputRecord {
                stage: input.stage.clone(),
                instance: input.instance.clone(),
                key: manifest.key.clone(),
                files: content_hashes(manifest),
            })
        })
        .collect()
}

/// The artifact of `stage` under `key`, checked to file hashes: its manifest
/// when intact, otherwise its problems (`None` when there is no artifact).
fn checked(store: &Store, stage: &dyn Stage, key: &str) -> Result<Manifest, Option<Vec<String>>> {
    let id = stage.id();
    if !store.artifact_dir(&id.stage, key).is_dir() {
        return Err(None);
    }
    store
        .inspect(&id.stage, key, Some(&output_files(stage)), Depth::Hashes)
        .map_err(Some)
}

/// Whether a stage `did` (wrote or drew) exactly the names it declares.
fn as_declared(
    did: &str,
    mut written: Vec<&str>,
    mut declared: Vec<&str>,
) -> Result<(), StageError> {
    written.sort_unstable();
    declared.sort_unstable();
    if written == declared {
        return Ok(());
    }
    Err(StageError::Input(format!(
        "{did} [{}] but declares [{}]",
        written.join(", "),
        declared.join(", ")
    )))
}

/// Every file name an artifact of `stage` holds: its tables' and its other files.
pub fn output_files(stage: &dyn Stage) -> Vec<String> {
    let mut files = table_files(stage.tables());
    files.extend(stage.files());
    files
}

/// Write access of a run: the writers' lock (shared among runs, exclusive of
/// `gc`), or why the store cannot be written.
enum Access {
    /// The lock, held until the run ends.
    Locked {
        _lock: StoreLock,
    },
    ReadOnly(String),
}

impl Access {
    /// Takes the writers' (shared) lock; a store that cannot be written is
    /// still read (everything may be fresh).
    fn acquire(store: &Store) -> Result<Access, ExecError> {
        match store.lock_for_writing() {
            Ok(lock) => Ok(Access::Locked { _lock: lock }),
            Err(StoreError::Io { path, source })
                if matches!(
                    source.kind(),
                    ErrorKind::PermissionDenied | ErrorKind::ReadOnlyFilesystem
                ) =>
            {
                Ok(Access::ReadOnly(format!("{}: {source}", path.display())))
            }
            Err(error) => Err(error.into()),
        }
    }
}

/// Executes the stale instances in order. Every artifact is checked down to
/// its file hashes before it is trusted; a damaged one is recomputed under
/// the same key.
pub fn run(
    store: &Store,
    stages: &[Box<dyn Stage>],
    options: &RunOptions,
) -> Result<Vec<InstanceReport>, ExecError> {
    check_plan(
        stages,
        &[options.only.clone(), options.force.clone()].concat(),
    )?;
    let access = Access::acquire(store)?;
    let mut resolved: BTreeMap<InstanceId, Manifest> = BTreeMap::new();
    let mut reports = Vec::new();
    let sharding = options.sharding;
    let decoded = DecodedTables::default();
    let width = id_width(stages);
    for stage in stages {
        let id = stage.id();
        let shardable = stage.shard_units() > 0;
        let selected = (options.only.is_empty() || options.only.contains(&id.stage))
            && (sharding.task.is_none() || shardable || stage.shard_prerequisite());
        let Some(inputs) = input_records(stage.as_ref(), &resolved) else {
            if selected && sharding.task.is_none() {
                return Err(ExecError::Plan(format!(
                    "{id}: an input is not available; run its upstream stages first (without --only)"
                )));
            }
            reports.push(InstanceReport {
                id,
                key: None,
                action: Action::Skipped,
            });
            continue;
        };
        let key = stage_key(
            &id.stage,
            stage.code().fingerprint,
            &stage.params(),
            &inputs,
        );
        let forced = options.force.contains(&id.stage);
        let entry = InstanceRef {
            key: key.clone(),
            code: stage.code().into(),
            params: stage.params(),
            inputs,
        };
        let action = match checked(store, stage.as_ref(), &key) {
            Ok(manifest) if !(forced && selected) => {
                if let Access::Locked { .. } = access {
                    heal_ref(store, &id, &entry)?;
                }
                resolved.insert(id.clone(), manifest);
                Action::Fresh
            }
            _ if !selected => Action::Skipped,
            existing => {
                if let Access::ReadOnly(reason) = &access {
                    return Err(ExecError::ReadOnly {
                        id,
                        reason: reason.clone(),
                    });
                }
                let mut replace = !matches!(existing, Err(None));
                let repaired = existing.err().flatten().map(|problems| problems.join("; "));
                let foreign = if replace {
                    store.foreign_in_artifact(&id.stage, &key, &output_files(stage.as_ref()))
                } else {
                    Vec::new()
                };
                let mut set_aside = None;
                if !foreign.is_empty() && sharding.task.is_none() {
                    let aside = store.set_aside(&id.stage, &key)?;
                    set_aside = Some(format!(
                        "moved it to {} with {}, which ternary did not write",
                        aside.display(),
                        foreign.join(", ")
                    ));
                    replace = false;
                }
                let job = Job {
                    store,
                    stage: stage.as_ref(),
                    resolved: &resolved,
                    options,
                    decoded: &decoded,
                };
                match sharding.task.filter(|_| shardable) {
                    Some(index) => Action::Shard {
                        index,
                        seconds: job.shard(&entry, index)?,
                    },
                    None => {
                        let (manifest, seconds) = job.compute(&entry, replace)?;
                        resolved.insert(id.clone(), manifest);
                        Action::Computed {
                            seconds,
                            repaired,
                            set_aside,
                        }
                    }
                }
            }
        };
        let shown = match options.verbosity {
            Verbosity::Quiet => false,
            Verbosity::Normal => action != Action::Fresh,
            Verbosity::Detailed => true,
        };
        if shown {
            // A closed stdout must not abort a run: the line is only a log.
            let _ = writeln!(
                std::io::stdout().lock(),
                "{}",
                report_line(&id, width, &key, &action)
            );
        }
        reports.push(InstanceReport {
            id,
            key: Some(key),
            action,
        });
    }
    Ok(reports)
}

/// Rewrites a missing or outdated ref of a fresh instance (a run killed
/// between committing an artifact and writing its ref leaves one).
fn heal_ref(store: &Store, id: &InstanceId, entry: &InstanceRef) -> Result<(), ExecError> {
    if store.read_ref(&id.stage, &id.instance).as_ref() != Some(entry) {
        store.write_ref(&id.stage, &id.instance, entry)?;
    }
    Ok(())
}

/// Characters of the longest instance id of `stages`: the width of the id
/// column of a run's lines.
fn id_width(stages: &[Box<dyn Stage>]) -> usize {
    stages
        .iter()
        .map(|stage| stage.id().to_string().chars().count())
        .max()
        .unwrap_or(0)
}

/// One line of a run: the instance (padded to `width`), what was done, the key.
fn report_line(id: &InstanceId, width: usize, key: &str, action: &Action) -> String {
    let what = match action {
        Action::Fresh => "fresh".to_string(),
        Action::Computed {
            seconds,
            repaired,
            set_aside,
        } => {
            let notes: Vec<String> = [
                repaired
                    .as_ref()
                    .map(|problems| format!("replaced a damaged artifact: {problems}")),
                set_aside.clone(),
            ]
            .into_iter()
            .flatten()
            .collect();
            if notes.is_empty() {
                format!("computed in {seconds:.2} s")
            } else {
                format!("computed in {seconds:.2} s ({})", notes.join("; "))
            }
        }
        Action::Skipped => "skipped (not selected, not fresh)".to_string(),
        Action::Shard {
            index,
            seconds: Some(seconds),
        } => format!("shard {index} computed in {seconds:.2} s"),
        Action::Shard {
            index,
            seconds: None,
        } => format!("shard {index} present"),
    };
    format!("{:<width$}  {what}  key {}", id.to_string(), &key[..12])
}

fn progress_for(stage: &dyn Stage, verbosity: Verbosity) -> Progress {
    if verbosity == Verbosity::Quiet || !std::io::stderr().is_terminal() {
        return Progress::hidden();
    }
    let bar = ProgressBar::new(stage.work_units());
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
#[derive(Default)]
struct DecodedTables {
    recent: RefCell<VecDeque<(String, RecordBatch)>>,
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
        let mut recent = self.recent.borrow_mut();
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
fn load_inputs(
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

/// The intact shard of `stage`'s artifact `whole` over `units`, or why there
/// is none (`None`: no shard artifact).
fn shard_manifest(
    store: &Store,
    stage: &dyn Stage,
    whole: &InstanceRef,
    units: &Range<u32>,
) -> Result<Manifest, Option<Vec<String>>> {
    let shard = shards::shard_entry(stage, whole, units);
    let stage_name = shards::shard_stage(&stage.id().stage);
    if !store.artifact_dir(&stage_name, &shard.key).is_dir() {
        return Err(None);
    }
    store
        .inspect(
            &stage_name,
            &shard.key,
            Some(&table_files(stage.shard_tables())),
            Depth::Hashes,
        )
        .map_err(Some)
}

/// One instance to compute: the store, the stage, its resolved inputs.
struct Job<'a> {
    store: &'a Store,
    stage: &'a dyn Stage,
    resolved: &'a BTreeMap<InstanceId, Manifest>,
    options: &'a RunOptions,
    decoded: &'a DecodedTables,
}

impl Job<'_> {
    /// Computes and commits the whole artifact of `entry`: directly, or for a
    /// sharded run from its shards (computing those still missing, then
    /// concatenating them in order). `replace` moves a damaged or forced
    /// artifact of the key aside.
    fn compute(&self, entry: &InstanceRef, replace: bool) -> Result<(Manifest, f64), ExecError> {
        let id = self.stage.id();
        let started = Instant::now();
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
        Ok((manifest, started.elapsed().as_secs_f64()))
    }

    /// Every file of `entry`'s artifact, computed from the stored inputs in
    /// memory (unsharded: a merge of shards must give the same bytes).
    fn recomputed_files(&self, entry: &InstanceRef) -> Result<Vec<(String, Vec<u8>)>, ExecError> {
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
    fn shard(&self, entry: &InstanceRef, index: u32) -> Result<Option<f64>, ExecError> {
        let sharding = self.options.sharding;
        let units = shards::range(self.stage.shard_units(), sharding.shards, index);
        if units.is_empty() || self.shard_manifest(entry, &units).is_ok() {
            return Ok(None);
        }
        let started = Instant::now();
        self.compute_shard(entry, &units)?;
        Ok(Some(started.elapsed().as_secs_f64()))
    }

    /// The intact shard of `entry` over `units`, or why there is none.
    fn shard_manifest(
        &self,
        entry: &InstanceRef,
        units: &Range<u32>,
    ) -> Result<Manifest, Option<Vec<String>>> {
        shard_manifest(self.store, self.stage, entry, units)
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
        let started = Instant::now();
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
        let manifest = match self.shard_manifest(entry, units) {
            Ok(manifest) => manifest,
            Err(_) => self.compute_shard(entry, units)?,
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
        let progress = progress_for(self.stage, self.options.verbosity);
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
        started: Instant,
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
            wall_seconds: started.elapsed().as_secs_f64(),
            manifest_sha256: None,
        })
    }
}

/// One table as it is written: file name, Parquet bytes, rows and the
/// content hash downstream keys take.
struct EncodedTable {
    file: String,
    bytes: Vec<u8>,
    rows: u64,
    content_sha256: String,
}

/// The files of `tables` of the artifact `id` under `entry`'s key: Parquet
/// with the executor's provenance metadata. Part of every stage's code
/// fingerprint (the build script's shared root): what it does to a table
/// is in every artifact's bytes.
fn encoded_tables(
    id: &InstanceId,
    entry: &InstanceRef,
    tables: &[Table],
) -> Result<Vec<EncodedTable>, TableError> {
    let values = [
        id.stage.clone(),
        entry.code.fingerprint.clone(),
        entry.key.clone(),
        super::key::canonical_json(&entry.params),
        super::key::embedded_inputs(&entry.inputs),
        tool_version(),
    ];
    let provenance: BTreeMap<String, String> = PROVENANCE_KEYS
        .iter()
        .map(ToString::to_string)
        .zip(values)
        .collect();
    tables
        .iter()
        .map(|table| {
            Ok(EncodedTable {
                file: format!("{}.parquet", table.name),
                bytes: table.to_parquet(&provenance)?,
                rows: table.rows(),
                content_sha256: table.content_sha256()?,
            })
        })
        .collect()
}

/// The expected cost of every instance of `stages` (in topological order),
/// each from its inputs' costs.
pub fn estimate(stages: &[Box<dyn Stage>]) -> Vec<(InstanceId, Cost)> {
    let mut costs: BTreeMap<InstanceId, Cost> = BTreeMap::new();
    let mut out = Vec::with_capacity(stages.len());
    for stage in stages {
        let inputs: Vec<Cost> = stage
            .inputs()
            .iter()
            .map(|id| costs.get(id).copied().unwrap_or_default())
            .collect();
        let cost = stage.cost(&inputs);
        costs.insert(stage.id(), cost);
        out.push((stage.id(), cost));
    }
    out
}

/// What `verify --recompute` found for one instance.
#[derive(Clone, Debug, PartialEq)]
pub enum Audit {
    /// Recomputed: every file has the stored bytes.
    Same {
        /// Wall time of the recomputation, seconds.
        seconds: f64,
    },
    /// Recomputed under the same key, some files with other bytes:
    /// `(file, stored SHA-256, recomputed SHA-256)` (`-` for a file one side lacks).
    Differs(Vec<(String, String, String)>),
    /// Not recomputed, and why: no intact artifact under the current key.
    NotFresh(String),
}

/// Recomputes the fresh instances of the stages in `only` (all when empty)
/// from their stored inputs, in memory, and compares every file's bytes with
/// the stored artifact under the same key: the audit that a key means its
/// bytes (`ternary verify --recompute`), one line per selected instance as
/// it is checked. Instances not selected are only resolved; nothing is written.
pub fn recompute(
    store: &Store,
    stages: &[Box<dyn Stage>],
    only: &[String],
    verbosity: Verbosity,
) -> Result<Vec<(InstanceId, Audit)>, ExecError> {
    check_plan(stages, only)?;
    let options = RunOptions {
        only: only.to_vec(),
        force: Vec::new(),
        verbosity,
        sharding: Sharding::default(),
    };
    let decoded = DecodedTables::default();
    let mut resolved: BTreeMap<InstanceId, Manifest> = BTreeMap::new();
    let mut audits = Vec::new();
    for stage in stages {
        let id = stage.id();
        let selected = only.is_empty() || only.contains(&id.stage);
        let inputs = input_records(stage.as_ref(), &resolved);
        let entry = inputs.map(|inputs| InstanceRef {
            key: stage_key(
                &id.stage,
                stage.code().fingerprint,
                &stage.params(),
                &inputs,
            ),
            code: stage.code().into(),
            params: stage.params(),
            inputs,
        });
        let checked = entry
            .as_ref()
            .map(|entry| checked(store, stage.as_ref(), &entry.key));
        let (Some(entry), Some(Ok(manifest))) = (entry, &checked) else {
            if selected {
                let reason = match checked {
                    Some(Err(Some(problems))) => format!("damaged ({})", problems.join("; ")),
                    Some(_) => "no artifact under the current key".to_string(),
                    None => "an input is not fresh".to_string(),
                };
                let audit = Audit::NotFresh(reason);
                if verbosity != Verbosity::Quiet {
                    let _ = writeln!(std::io::stdout().lock(), "{}", audit_line(&id, &audit));
                }
                audits.push((id, audit));
            }
            continue;
        };
        if selected {
            let job = Job {
                store,
                stage: stage.as_ref(),
                resolved: &resolved,
                options: &options,
                decoded: &decoded,
            };
            let started = Instant::now();
            let files = job.recomputed_files(&entry)?;
            let audit = compare_files(manifest, files, started.elapsed().as_secs_f64());
            if verbosity != Verbosity::Quiet {
                let _ = writeln!(std::io::stdout().lock(), "{}", audit_line(&id, &audit));
            }
            audits.push((id.clone(), audit));
        }
        resolved.insert(id, manifest.clone());
    }
    Ok(audits)
}

/// The stored files of `manifest` against recomputed `(name, bytes)`.
fn compare_files(manifest: &Manifest, files: Vec<(String, Vec<u8>)>, seconds: f64) -> Audit {
    let recomputed: BTreeMap<String, String> = files
        .into_iter()
        .map(|(name, bytes)| (name, sha256_hex(&bytes)))
        .collect();
    let stored: BTreeMap<String, String> = manifest
        .files
        .iter()
        .map(|file| (file.name.clone(), file.sha256.clone()))
        .collect();
    let mut names: Vec<&String> = stored.keys().chain(recomputed.keys()).collect();
    names.sort();
    names.dedup();
    let differing: Vec<(String, String, String)> = names
        .into_iter()
        .filter(|name| stored.get(*name) != recomputed.get(*name))
        .map(|name| {
            let side =
                |map: &BTreeMap<String, String>| map.get(name).cloned().unwrap_or("-".into());
            (name.clone(), side(&stored), side(&recomputed))
        })
        .collect();
    if differing.is_empty() {
        Audit::Same { seconds }
    } else {
        Audit::Differs(differing)
    }
}

/// One line of `verify --recompute`.
pub fn audit_line(id: &InstanceId, audit: &Audit) -> String {
    let what = match audit {
        Audit::Same { seconds } => format!("same bytes (recomputed in {seconds:.2} s)"),
        Audit::Differs(files) => format!(
            "SAME KEY, DIFFERENT BYTES: {}",
            files
                .iter()
                .map(|(name, stored, now)| format!(
                    "{name} (stored {}, recomputed {})",
                    &stored[..stored.len().min(12)],
                    &now[..now.len().min(12)]
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        Audit::NotFresh(reason) => format!("not checked: {reason}; run first"),
    };
    format!("{:<24} {what}", id.to_string())
}

/// `ternary <crate version>`.
pub fn tool_version() -> String {
    format!("ternary {}", env!("CARGO_PKG_VERSION"))
}

/// One line of `status`.
#[derive(Clone, Debug)]
pub struct StatusLine {
    /// The instance.
    pub id: InstanceId,
    /// Its current key, when its inputs are available.
    pub key: Option<String>,
    /// Fresh, stale or missing, and why.
    pub freshness: Freshness,
    /// For a shardable instance that is not fresh, in a sharded status: the
    /// shard indices present and missing.
    pub shards: Option<ShardProgress>,
}

/// Shards of one instance present and missing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShardProgress {
    /// Indices of intact shards (empty shards count as done).
    pub done: Vec<u32>,
    /// Indices still to compute.
    pub missing: Vec<u32>,
}

/// Freshness of every instance, with reasons, without computing anything.
/// Artifacts are checked as `run` checks them (down to file hashes). With
/// `shards > 1`, a shardable instance that is not fresh also reports which of
/// its shards are done.
pub fn status(
    store: &Store,
    stages: &[Box<dyn Stage>],
    shards: u32,
) -> Result<Vec<StatusLine>, ExecError> {
    check_plan(stages, &[])?;
    let mut resolved: BTreeMap<InstanceId, Manifest> = BTreeMap::new();
    let mut lines = Vec::new();
    for stage in stages {
        let id = stage.id();
        let previous = store.read_ref(&id.stage, &id.instance).or_else(|| {
            store
                .latest_manifest_of(&id.stage, &id.instance)
                .map(|manifest| InstanceRef::from(&manifest))
        });
        let mut key = None;
        let mut progress = None;
        let freshness = match input_records(stage.as_ref(), &resolved) {
            None => {
                let waiting: Vec<String> = stage
                    .inputs()
                    .iter()
                    .filter(|input| !resolved.contains_key(input))
                    .map(ToString::to_string)
                    .collect();
                let reason = format!("waiting on {}", waiting.join(", "));
                if stage.shard_units() > 0 && shards > 1 {
                    // No shard of an instance whose key is not known yet
                    // exists: every non-empty one is still to compute (its
                    // task first computes the missing prerequisites).
                    progress = Some(shard_progress_with(stage.as_ref(), shards, |_| false));
                }
                match previous {
                    Some(_) => Freshness::Stale(vec![reason]),
                    None => Freshness::Missing(reason),
                }
            }
            Some(inputs) => {
                let current = stage_key(
                    &id.stage,
                    stage.code().fingerprint,
                    &stage.params(),
                    &inputs,
                );
                let freshness = match checked(store, stage.as_ref(), &current) {
                    Ok(manifest) => {
                        resolved.insert(id.clone(), manifest);
                        Freshness::Fresh
                    }
                    Err(Some(problems)) => Freshness::Damaged(problems),
                    Err(None) => explain(stage.as_ref(), &current, &inputs, previous),
                };
                if freshness != Freshness::Fresh && stage.shard_units() > 0 && shards > 1 {
                    let whole = InstanceRef {
                        key: current.clone(),
                        code: stage.code().into(),
                        params: stage.params(),
                        inputs,
                    };
                    progress = Some(shard_progress(store, stage.as_ref(), &whole, shards));
                }
                key = Some(current);
                freshness
            }
        };
        lines.push(StatusLine {
            id,
            key,
            freshness,
            shards: progress,
        });
    }
    Ok(lines)
}

/// Which of the `shards` shards of `whole` are present.
fn shard_progress(
    store: &Store,
    stage: &dyn Stage,
    whole: &InstanceRef,
    shards: u32,
) -> ShardProgress {
    shard_progress_with(stage, shards, |units| {
        shard_manifest(store, stage, whole, units).is_ok()
    })
}

/// Which of the `shards` shards of `stage` are done, by `present` (empty
/// shards count as done).
fn shard_progress_with(
    stage: &dyn Stage,
    shards: u32,
    present: impl Fn(&Range<u32>) -> bool,
) -> ShardProgress {
    let mut progress = ShardProgress::default();
    for index in 0..shards {
        let units = shards::range(stage.shard_units(), shards, index);
        if units.is_empty() || present(&units) {
            progress.done.push(index);
        } else {
            progress.missing.push(index);
        }
    }
    progress
}

fn explain(
    stage: &dyn Stage,
    key: &str,
    inputs: &[InputRecord],
    previous: Option<InstanceRef>,
) -> Freshness {
    let Some(previous) = previous else {
        return Freshness::Missing("never computed".to_string());
    };
    if previous.key == key {
        return Freshness::Missing("its artifact was removed".to_string());
    }
    let mut reasons = Vec::new();
    let code = CodeRecord::from(stage.code());
    if previous.code.fingerprint.is_empty() {
        reasons.push("code changed (computed before keys followed the code)".to_string());
    } else if previous.code.fingerprint != code.fingerprint {
        reasons.push(format!(
            "code changed ({})",
            previous.code.changed_parts(&code).join(", ")
        ));
    }
    reasons.extend(
        changed_params(&previous.params, &stage.params())
            .into_iter()
            .map(|c| format!("parameter {c}")),
    );
    for input in inputs {
        let before = previous
            .inputs
            .iter()
            .find(|p| p.stage == input.stage && p.instance == input.instance);
        if before.map(|p| &p.files) != Some(&input.files) {
            reasons.push(format!("input {}[{}] changed", input.stage, input.instance));
        }
    }
    if reasons.is_empty() {
        reasons.push("key changed".to_string());
    }
    Freshness::Stale(reasons)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::code::Code;
    use crate::pipeline::{Column, Table};
    use serde_json::json;

    static TEST_CODE: Code = Code {
        root: "src/pipeline/executor.rs",
        fingerprint: "test",
        parts: &[],
    };

    /// A source whose `label` does not change its output bytes.
    struct Source {
        label: &'static str,
        value: f64,
    }

    /// Doubles the source's value.
    struct Double;

    impl Stage for Source {
        fn id(&self) -> InstanceId {
            InstanceId::new("source", "a")
        }
        fn code(&self) -> &'static Code {
            &TEST_CODE
        }
        fn params(&self) -> serde_json::Value {
            json!({ "label": self.label, "value": self.value })
        }
        fn tables(&self) -> &'static [&'static str] {
            &["value"]
        }
        fn inputs(&self) -> Vec<InstanceId> {
            Vec::new()
        }
        fn work_units(&self) -> u64 {
            1
        }
        fn run(&self, _: &[Input], _: &Progress) -> Result<Vec<Table>, StageError> {
            Ok(vec![Table::new(
                "value",
                vec![Column::f64("x", "1", "value", None, vec![self.value])],
            )?])
        }
    }

    impl Stage for Double {
        fn id(&self) -> InstanceId {
            InstanceId::new("double", "a")
        }
        fn code(&self) -> &'static Code {
            &TEST_CODE
        }
        fn params(&self) -> serde_json::Value {
            json!({})
        }
        fn tables(&self) -> &'static [&'static str] {
            &["value"]
        }
        fn inputs(&self) -> Vec<InstanceId> {
            vec![InstanceId::new("source", "a")]
        }
        fn work_units(&self) -> u64 {
            1
        }
        fn run(&self, inputs: &[Input], _: &Progress) -> Result<Vec<Table>, StageError> {
            let column = inputs[0].tables["value"].column(0).clone();
            let values = column
                .as_any()
                .downcast_ref::<arrow::array::Float64Array>()
                .ok_or_else(|| StageError::Input("x is not float64".into()))?;
            let doubled = values.iter().map(|v| v.map(|v| 2.0 * v)).collect();
            Ok(vec![Table::new(
                "value",
                vec![Column::optional_f64("x", "1", "doubled", None, doubled)],
            )?])
        }
    }

    fn plan(label: &'static str, value: f64) -> Vec<Box<dyn Stage>> {
        vec![Box::new(Source { label, value }), Box::new(Double)]
    }

    fn computed(store: &Store, stages: &[Box<dyn Stage>], force: &[&str]) -> Vec<String> {
        let options = RunOptions {
            only: Vec::new(),
            force: force.iter().map(ToString::to_string).collect(),
            verbosity: Verbosity::Quiet,
            sharding: Sharding::default(),
        };
        run(store, stages, &options)
            .unwrap()
            .into_iter()
            .filter(|r| matches!(r.action, Action::Computed { .. }))
            .map(|r| r.id.stage)
            .collect()
    }

    fn temporary_store(name: &str) -> Store {
        let root =
            std::env::temp_dir().join(format!("ternary-executor-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        Store::open(&root).unwrap()
    }

    #[test]
    fn identical_input_bytes_cut_off_downstream_recomputation() {
        let store = temporary_store("cutoff");
        assert_eq!(
            computed(&store, &plan("first", 1.5), &[]),
            ["source", "double"]
        );
        // A parameter that leaves the source's bytes unchanged: only the source reruns.
        assert_eq!(computed(&store, &plan("second", 1.5), &[]), ["source"]);
        assert_eq!(
            computed(&store, &plan("second", 1.5), &["source"]),
            ["source"]
        );
        // A real change propagates, and the reason is reported before the run.
        let lines = status(&store, &plan("second", 2.5), 1).unwrap();
        assert_eq!(
            lines[0].freshness,
            Freshness::Stale(vec!["parameter value: 1.5 -> 2.5".into()])
        );
        assert_eq!(
            lines[1].freshness,
            Freshness::Stale(vec!["waiting on source[a]".into()])
        );
        assert_eq!(
            computed(&store, &plan("second", 2.5), &[]),
            ["source", "double"]
        );
        assert!(computed(&store, &plan("second", 2.5), &[]).is_empty());
    }

    #[test]
    fn downstream_reads_upstream_tables() {
        let store = temporary_store("read");
        computed(&store, &plan("x", 3.0), &[]);
        let lines = status(&store, &plan("x", 3.0), 1).unwrap();
        let key = lines[1].key.clone().unwrap();
        let (batch, metadata) = crate::pipeline::table::read_parquet(
            &store.artifact_dir("double", &key).join("value.parquet"),
        )
        .unwrap();
        let values = batch
            .column(0)
            .as_any()
            .downcast_ref::<arrow::array::Float64Array>()
            .unwrap();
        assert_eq!(values.value(0), 6.0);
        assert_eq!(metadata["ternary.key"], key);
    }

    #[test]
    fn unknown_stage_in_only_is_rejected() {
        let store = temporary_store("unknown");
        let options = RunOptions {
            only: vec!["sorce".into()],
            force: Vec::new(),
            verbosity: Verbosity::Quiet,
            sharding: Sharding::default(),
        };
        let error = run(&store, &plan("x", 1.0), &options).unwrap_err();
        assert!(
            error.to_string().contains("unknown stage `sorce`"),
            "{error}"
        );
    }

    /// An unknown stage's error names each stage once, in the plan's order,
    /// however many instances it has.
    #[test]
    fn stage_names_are_listed_once() {
        let ids = [
            InstanceId::new("scan", "ipp-6"),
            InstanceId::new("kernel", "a"),
            InstanceId::new("scan", "ipp-8"),
            InstanceId::new("kernel", "b"),
        ];
        assert_eq!(stage_names(&ids), ["scan", "kernel"]);
    }

    /// A typo one or two characters off a stage name is answered with that
    /// name; a word far from every stage gets no guess.
    #[test]
    fn a_mistyped_stage_gets_the_nearest_name() {
        let ids = [
            InstanceId::new("collisions", "ipp-6"),
            InstanceId::new("kernel", "ipp-6"),
            InstanceId::new("figures", "ipp-6_kernels"),
        ];
        assert_eq!(edit_distance("kernl", "kernel"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(
            unknown_stage("kernl", &ids),
            "unknown stage `kernl`; did you mean `kernel`? (stages are: collisions, kernel, figures)"
        );
        assert!(unknown_stage("colisons", &ids).contains("did you mean `collisions`?"));
        assert!(!unknown_stage("paper", &ids).contains("did you mean"));
    }
}
