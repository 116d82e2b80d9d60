//! The generic staged DAG: stage instances, content keys, the artifact store,
//! Parquet tables and the executor. This module knows nothing of physics: a
//! stage is a pure function from its parameters and input tables to output
//! tables, and the executor owns caching, keys, progress, atomic writes and
//! logging (stages never touch the store).

pub mod clock;
pub mod code;
pub mod executor;
pub mod key;
pub mod path_names;
pub mod shards;
pub mod store;
pub mod table;

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;

use arrow_array::RecordBatch;
use indicatif::ProgressBar;
use serde_json::Value;

pub use table::{Column, Table, TableError};

/// Names one stage instance, e.g. `scan[ipp-6]`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct InstanceId {
    /// Stage name.
    pub stage: String,
    /// Instance name within the stage.
    pub instance: String,
}

impl InstanceId {
    /// Builds an id.
    pub fn new(stage: &str, instance: &str) -> InstanceId {
        InstanceId {
            stage: stage.to_string(),
            instance: instance.to_string(),
        }
    }
}

impl fmt::Display for InstanceId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}[{}]", self.stage, self.instance)
    }
}

/// The output tables of an upstream instance, handed to a stage by the executor.
pub struct Input {
    /// The upstream instance.
    pub id: InstanceId,
    /// Its tables by name.
    pub tables: BTreeMap<String, RecordBatch>,
}

/// A stage failed to compute its outputs.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    /// A table could not be built.
    #[error(transparent)]
    Table(#[from] TableError),
    /// An input lacked what the stage needs.
    #[error("{0}")]
    Input(String),
    /// A stage or its wiring broke an invariant of the pipeline (wrote tables
    /// it does not declare, read an input it does not declare): a bug, not
    /// bad input.
    #[error("internal error (a bug, not bad input): {0}")]
    Invariant(String),
}

/// Progress of a running stage, in the units of [`Stage::work_units`].
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// Progress that reports nowhere (tests, quiet runs).
    pub fn hidden() -> Progress {
        Progress { bar: None }
    }

    /// Corrects the total amount of work once the stage knows it exactly.
    pub fn set_total(&self, units: u64) {
        if let Some(bar) = &self.bar {
            bar.set_length(units);
        }
    }

    /// Records `units` more of finished work.
    pub fn advance(&self, units: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(units);
        }
    }
}

/// What computing one stage instance is expected to cost, from its
/// parameters and its inputs' costs: an order of magnitude, for refusing a
/// study too large to be meant and for `status`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cost {
    /// CPU time, seconds (all threads together).
    pub cpu_seconds: f64,
    /// Bytes of the artifact.
    pub bytes: f64,
    /// Rows of its tables, which consumers read.
    pub rows: f64,
}

impl Cost {
    /// The cost of a stage that reads `inputs` at `cpu_per_row` seconds per
    /// input row and writes `rows` rows of `bytes_per_row` bytes.
    pub fn reading(inputs: &[Cost], cpu_per_row: f64, rows: f64, bytes_per_row: f64) -> Cost {
        let read: f64 = inputs.iter().map(|input| input.rows).sum();
        Cost {
            cpu_seconds: cpu_per_row * read,
            bytes: rows * bytes_per_row,
            rows,
        }
    }
}

/// CPU seconds per input row of a stage that reads tables, the default
/// [`Stage::cost`] (measured on the default study, 2026-12-01: moments 0.34
/// us, paper and figures 0.37, compare 2.2, fit and convergence 3.3-3.7;
/// the sweep and evolve set their own).
pub const CPU_PER_INPUT_ROW: f64 = 1e-6;

/// One instance of a stage: its identity, everything its output depends on,
/// and the computation.
pub trait Stage: Sync {
    /// Stage and instance name.
    fn id(&self) -> InstanceId;
    /// The code the stage runs, fingerprinted at build time: for a stage of
    /// the library `code::of(file!())` in a constant (see [`code`]).
    fn code(&self) -> &'static code::Code;
    /// Resolved parameters: everything besides the inputs that the output depends on.
    fn params(&self) -> Value;
    /// Names of the tables it writes (`<name>.parquet`), always all of them.
    fn tables(&self) -> &'static [&'static str];
    /// Names of the other files it writes (figures: `<name>.svg`, `<name>.png`),
    /// always all of them; none by default.
    fn files(&self) -> Vec<String> {
        Vec::new()
    }
    /// Upstream instances whose tables this stage reads.
    fn inputs(&self) -> Vec<InstanceId>;
    /// Amount of work, in the units the stage reports through [`Progress`].
    fn work_units(&self) -> u64;
    /// The expected cost, given the costs of [`Stage::inputs`] in order. By
    /// default a small table from reading the inputs.
    fn cost(&self, inputs: &[Cost]) -> Cost {
        Cost::reading(inputs, CPU_PER_INPUT_ROW, 1e3, 100.0)
    }
    /// Computes the output tables. Must be deterministic: the same parameters and
    /// inputs give the same tables whatever the thread count.
    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError>;

    /// The files ([`Stage::files`]) drawn from the tables `run` returned, as
    /// `(name, bytes)`; deterministic like the tables.
    fn render(&self, _tables: &[Table]) -> Result<Vec<(String, Vec<u8>)>, StageError> {
        Ok(Vec::new())
    }

    /// `true` for a cheap stage that shardable stages read: a shard task
    /// computes it too when it is missing (tasks that race write the same
    /// bytes; the store keeps one copy).
    fn shard_prerequisite(&self) -> bool {
        false
    }

    /// Independent units of work (randomizations, runs) the stage can be
    /// split into for sharded runs; 0 (the default) when it cannot be split.
    fn shard_units(&self) -> u32 {
        0
    }

    /// The tables of units `units` only ([`Stage::shard_tables`]), which
    /// [`Stage::merge`] turns into [`Stage::run`]'s tables; by default the
    /// rows those units contribute, in order. Only called when
    /// [`Stage::shard_units`] is positive.
    fn run_shard(
        &self,
        _inputs: &[Input],
        _units: Range<u32>,
        _progress: &Progress,
    ) -> Result<Vec<Table>, StageError> {
        Err(StageError::Invariant("this stage cannot be sharded".into()))
    }

    /// Names of the tables a shard writes (default: the stage's own).
    fn shard_tables(&self) -> &'static [&'static str] {
        self.tables()
    }

    /// The stage's tables from its shards' tables, in unit order; must equal
    /// [`Stage::run`]'s, byte for byte. Default: each table's rows concatenated.
    fn merge(&self, shards: Vec<Vec<Table>>) -> Result<Vec<Table>, StageError> {
        Ok(shards::concatenate(self.tables(), shards)?)
    }
}
