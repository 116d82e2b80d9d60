//! Runs the stale part of a DAG of stage instances, and explains what is
//! fresh, stale or missing (`status`).
//!
//! Instances are given in topological order. An instance's key is computed from
//! its stage name, code fingerprint, parameters and the file hashes of its inputs; if the
//! store holds an intact artifact under that key (checked down to its file
//! hashes) it is fresh, otherwise it is computed and committed atomically.
//!
//! One concern per file: checking and estimating a plan (`plan`), what a run
//! does with each instance (`decide`), carrying it out (`run`), computing one
//! instance (`job`), the `verify --recompute` audit
//! (`recompute`) and `status`; this file holds the types they share.

mod decide;
mod job;
mod plan;
mod recompute;
mod run;
mod schedule;
mod status;

pub use plan::{check_plan, check_stage_names, estimate};
pub use recompute::{Audit, recompute};
pub use run::run;
pub use status::{Freshness, ShardProgress, StatusLine, status};

use std::collections::BTreeMap;

use crate::pipeline::key::{InputRecord, stage_key};
use crate::pipeline::shards::Sharding;
use crate::pipeline::store::{
    Depth, InstanceRef, Manifest, Store, StoreError, content_hashes, table_files,
};
use crate::pipeline::table::{PROVENANCE_KEYS, TableError};
use crate::pipeline::{InstanceId, Stage, StageError, Table};

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
    /// Instances computed at once, at most (each with the whole thread pool).
    pub jobs: usize,
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

/// What [`run`] and [`recompute`] report as they go, one instance at a time,
/// for the caller to show (the command line prints [`Event::line`] on
/// stdout); which instances are reported follows the [`Verbosity`].
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// `run` dealt with an instance.
    Ran {
        /// The instance.
        id: &'a InstanceId,
        /// Its key.
        key: &'a str,
        /// What was done.
        action: &'a Action,
        /// Width of the run's id column: its longest instance id.
        width: usize,
    },
    /// `recompute` audited an instance.
    Audited {
        /// The instance.
        id: &'a InstanceId,
        /// What the audit found.
        audit: &'a Audit,
    },
}

impl Event<'_> {
    /// The event as one line of the console.
    pub fn line(&self) -> String {
        match *self {
            Event::Ran {
                id,
                key,
                action,
                width,
            } => run::report_line(id, width, key, action),
            Event::Audited { id, audit } => recompute::audit_line(id, audit),
        }
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

/// `stage` with its key from `inputs`: what its artifact and ref record.
fn keyed(stage: &dyn Stage, inputs: Vec<InputRecord>) -> InstanceRef {
    InstanceRef {
        key: stage_key(
            &stage.id().stage,
            stage.code().fingerprint,
            &stage.params(),
            &inputs,
        ),
        code: stage.code().into(),
        params: stage.params(),
        inputs,
    }
}

/// What the store holds under a key, checked down to its file hashes.
#[derive(Debug)]
enum Stored {
    /// An intact artifact.
    Intact(Box<Manifest>),
    /// No artifact.
    Absent,
    /// An artifact that fails its checks, with its problems.
    Damaged(Vec<String>),
}

impl Stored {
    /// The manifest of an intact artifact.
    fn intact(self) -> Option<Manifest> {
        match self {
            Stored::Intact(manifest) => Some(*manifest),
            Stored::Absent | Stored::Damaged(_) => None,
        }
    }
}

/// The artifact of `stage` under `key`.
fn stored(store: &Store, stage: &dyn Stage, key: &str) -> Stored {
    inspected(store, &stage.id().stage, key, &output_files(stage))
}

/// The artifact of the stage named `stage` under `key`, which must hold
/// exactly `files`.
fn inspected(store: &Store, stage: &str, key: &str, files: &[String]) -> Stored {
    if !store.artifact_dir(stage, key).is_dir() {
        return Stored::Absent;
    }
    match store.inspect(stage, key, Some(files), Depth::Hashes) {
        Ok(manifest) => Stored::Intact(Box::new(manifest)),
        Err(problems) => Stored::Damaged(problems),
    }
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
    Err(StageError::Invariant(format!(
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

/// `ternary <crate version>`.
pub fn tool_version() -> String {
    format!("ternary {}", env!("CARGO_PKG_VERSION"))
}
