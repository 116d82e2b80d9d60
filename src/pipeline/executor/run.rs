//! `ternary run`: resolves every instance in order, computing the stale
//! ones it is asked to.

use std::collections::BTreeMap;
use std::io::ErrorKind;

use super::decide::{Candidate, Decision, decide};
use super::job::{DecodedTables, Job};
use super::*;
use crate::pipeline::store::{InstanceRef, Manifest, Store, StoreError, StoreLock};
use crate::pipeline::{InstanceId, Stage};

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
/// the same key. Each instance is reported to `on_event` as it is dealt
/// with (as the verbosity asks).
pub fn run(
    store: &Store,
    stages: &[Box<dyn Stage>],
    options: &RunOptions,
    on_event: &mut dyn FnMut(Event<'_>),
) -> Result<Vec<InstanceReport>, ExecError> {
    check_plan(
        stages,
        &[options.only.clone(), options.force.clone()].concat(),
    )?;
    let access = Access::acquire(store)?;
    let writable = match &access {
        Access::Locked { .. } => Ok(()),
        Access::ReadOnly(reason) => Err(reason.as_str()),
    };
    let mut resolved: BTreeMap<InstanceId, Manifest> = BTreeMap::new();
    let mut reports = Vec::new();
    let decoded = DecodedTables::default();
    let width = id_width(stages);
    for stage in stages {
        let id = stage.id();
        let decision = decide(
            candidate(stage.as_ref(), options, &resolved),
            store,
            writable,
        )?;
        let job = Job {
            store,
            stage: stage.as_ref(),
            resolved: &resolved,
            options,
            decoded: &decoded,
        };
        let Some((key, action, manifest)) = carry_out(decision, &job, writable.is_ok())? else {
            reports.push(InstanceReport {
                id,
                key: None,
                action: Action::Skipped,
            });
            continue;
        };
        if let Some(manifest) = manifest {
            resolved.insert(id.clone(), manifest);
        }
        if shown(options.verbosity, &action) {
            on_event(Event::Ran {
                id: &id,
                key: &key,
                action: &action,
                width,
            });
        }
        reports.push(InstanceReport {
            id,
            key: Some(key),
            action,
        });
    }
    Ok(reports)
}

/// Whether a run at `verbosity` reports an instance it dealt with so.
fn shown(verbosity: Verbosity, action: &Action) -> bool {
    match verbosity {
        Verbosity::Quiet => false,
        Verbosity::Normal => *action != Action::Fresh,
        Verbosity::Detailed => true,
    }
}

/// `stage` as [`decide`] sees it under `options`, with the inputs `resolved`
/// so far.
fn candidate<'a>(
    stage: &'a dyn Stage,
    options: &RunOptions,
    resolved: &BTreeMap<InstanceId, Manifest>,
) -> Candidate<'a> {
    let name = stage.id().stage;
    let shard_task = options.sharding.task;
    Candidate {
        stage,
        inputs: input_records(stage, resolved),
        selected: (options.only.is_empty() || options.only.contains(&name))
            && (shard_task.is_none() || stage.shard_units() > 0 || stage.shard_prerequisite()),
        forced: options.force.contains(&name),
        shard_task,
    }
}

/// Carries out `decision` for `job`'s instance: its key, what was done and
/// the manifest it resolves to (when its artifact is in the store after
/// it); `None` for an instance without a key. A fresh instance's ref is
/// healed when the store is `writable`.
fn carry_out(
    decision: Decision,
    job: &Job<'_>,
    writable: bool,
) -> Result<Option<(String, Action, Option<Manifest>)>, ExecError> {
    let id = job.stage.id();
    Ok(Some(match decision {
        Decision::Unkeyed => return Ok(None),
        Decision::Skipped(entry) => (entry.key, Action::Skipped, None),
        Decision::Fresh(entry, manifest) => {
            if writable {
                heal_ref(job.store, &id, &entry)?;
            }
            (entry.key, Action::Fresh, Some(*manifest))
        }
        Decision::Shard { entry, index } => {
            let seconds = job.shard(&entry, index)?;
            (entry.key, Action::Shard { index, seconds }, None)
        }
        Decision::Compute {
            entry,
            replace,
            repaired,
            foreign,
        } => {
            let set_aside = if foreign.is_empty() {
                None
            } else {
                let aside = job.store.set_aside(&id.stage, &entry.key)?;
                Some(format!(
                    "moved it to {} with {}, which ternary did not write",
                    aside.display(),
                    foreign.join(", ")
                ))
            };
            let (manifest, seconds) = job.compute(&entry, replace)?;
            let action = Action::Computed {
                seconds,
                repaired,
                set_aside,
            };
            (entry.key, action, Some(manifest))
        }
    }))
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
pub(super) fn report_line(id: &InstanceId, width: usize, key: &str, action: &Action) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::code::Code;
    use crate::pipeline::shards::Sharding;
    use crate::pipeline::{Column, Input, Progress, StageError, Table};
    use serde_json::json;

    static TEST_CODE: Code = Code {
        root: "src/pipeline/executor/run.rs",
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
                .downcast_ref::<arrow_array::Float64Array>()
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
        run(store, stages, &options, &mut |_| {})
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
            .downcast_ref::<arrow_array::Float64Array>()
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
        let error = run(&store, &plan("x", 1.0), &options, &mut |_| {}).unwrap_err();
        assert!(
            error.to_string().contains("unknown stage `sorce`"),
            "{error}"
        );
    }
}
