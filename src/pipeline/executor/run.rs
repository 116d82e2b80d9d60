//! `ternary run`: resolves every instance, computing the stale ones it is
//! asked to, several at once when they do not read each other.

use std::collections::BTreeMap;
use std::io::ErrorKind;
use std::panic::AssertUnwindSafe;
use std::sync::mpsc;

use indicatif::MultiProgress;

use super::decide::{Candidate, Decision, decide};
use super::job::{DecodedTables, Job, progress_bars};
use super::schedule::Schedule;
use super::*;
use crate::pipeline::clock::CpuLedger;
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

/// Executes the stale instances, up to `options.jobs` at once (each on a
/// thread of its own; one at a time on the caller's), each once all its
/// inputs have been dealt with (the first such in plan order first).
/// Every artifact is checked down to its file hashes before it is trusted; a
/// damaged one is recomputed under the same key. Each instance is reported to
/// `on_event` as it is dealt with (as the verbosity asks). After a failure no
/// instance is started; those under way are finished and the first failure
/// is returned.
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
    let shared = Shared {
        store,
        options,
        writable,
        decoded: DecodedTables::default(),
        bars: progress_bars(options.verbosity),
        ledger: CpuLedger::default(),
    };
    let mut dispatch = Dispatch {
        schedule: Schedule::new(stages),
        resolved: BTreeMap::new(),
        reports: vec![None; stages.len()],
        failure: None,
        width: id_width(stages),
        verbosity: options.verbosity,
    };
    dispatch.deal_with_all(stages, &shared, &mut |event| {
        let mut show = || on_event(event);
        match &shared.bars {
            Some(bars) => bars.suspend(show),
            None => show(),
        }
    });
    dispatch.finish()
}

/// What every job of a run shares.
struct Shared<'a> {
    store: &'a Store,
    options: &'a RunOptions,
    /// Why the store cannot be written, if it cannot.
    writable: Result<(), &'a str>,
    decoded: DecodedTables,
    bars: Option<MultiProgress>,
    ledger: CpuLedger,
}

/// An instance dealt with: its key, what was done and the manifest it
/// resolves to; `None` for an instance without a key.
type Outcome = Option<(String, Action, Option<Manifest>)>;

impl Shared<'_> {
    /// Decides what to do with `stage` and does it, with its `inputs`' manifests.
    fn deal_with(
        &self,
        stage: &dyn Stage,
        candidate: Candidate<'_>,
        inputs: &BTreeMap<InstanceId, Manifest>,
    ) -> Result<Outcome, ExecError> {
        let decision = decide(candidate, self.store, self.writable)?;
        let cpu = self.ledger.open();
        let job = Job {
            store: self.store,
            stage,
            resolved: inputs,
            options: self.options,
            decoded: &self.decoded,
            bars: self.bars.as_ref(),
            cpu: &cpu,
        };
        carry_out(decision, &job, self.writable.is_ok())
    }
}

/// The run's bookkeeping, kept by the thread that starts the jobs.
struct Dispatch {
    schedule: Schedule,
    /// The manifest of every instance whose artifact is in the store.
    resolved: BTreeMap<InstanceId, Manifest>,
    /// What was done with each instance of the plan, by its index.
    reports: Vec<Option<InstanceReport>>,
    /// The first failure.
    failure: Option<ExecError>,
    /// Width of the id column of the run's lines.
    width: usize,
    /// Which instances are reported.
    verbosity: Verbosity,
}

impl Dispatch {
    /// `stage` as [`decide`] sees it, and the manifests of its inputs.
    fn candidate<'a>(
        &self,
        stage: &'a dyn Stage,
        options: &RunOptions,
    ) -> (Candidate<'a>, BTreeMap<InstanceId, Manifest>) {
        let inputs = stage
            .inputs()
            .into_iter()
            .filter_map(|input| Some((input.clone(), self.resolved.get(&input)?.clone())))
            .collect();
        (candidate(stage, options, &self.resolved), inputs)
    }

    /// Deals with every instance of `stages`, up to the run's jobs at once,
    /// until all are done or one failed (then those under way are finished).
    fn deal_with_all(
        &mut self,
        stages: &[Box<dyn Stage>],
        shared: &Shared<'_>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) {
        let jobs = shared.options.jobs.max(1);
        std::thread::scope(|scope| {
            let (sender, receiver) = mpsc::channel();
            let mut running = 0;
            loop {
                while self.failure.is_none() && running < jobs {
                    let Some(at) = self.schedule.next() else {
                        break;
                    };
                    let stage = stages[at].as_ref();
                    let (candidate, inputs) = self.candidate(stage, shared.options);
                    let sender = sender.clone();
                    let job = move || {
                        let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| {
                            shared.deal_with(stage, candidate, &inputs)
                        }));
                        // The receiver outlives every job.
                        let _ = sender.send((at, outcome));
                    };
                    // One at a time, on this thread (as a traced run expects).
                    if jobs > 1 {
                        scope.spawn(job);
                    } else {
                        job();
                    }
                    running += 1;
                }
                if running == 0 {
                    break;
                }
                let (at, outcome) = receiver.recv().expect("a job is under way");
                running -= 1;
                let outcome = outcome.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
                self.record(&stages[at].id(), at, outcome, on_event);
            }
        });
    }

    /// Records the `outcome` of instance `id` (plan index `at`), reporting it
    /// to `on_event` as the verbosity asks.
    fn record(
        &mut self,
        id: &InstanceId,
        at: usize,
        outcome: Result<Outcome, ExecError>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) {
        self.schedule.done(at);
        let (key, action) = match outcome {
            Err(error) => {
                self.failure.get_or_insert(error);
                return;
            }
            Ok(None) => (None, Action::Skipped),
            Ok(Some((key, action, manifest))) => {
                if let Some(manifest) = manifest {
                    self.resolved.insert(id.clone(), manifest);
                }
                if shown(self.verbosity, &action) {
                    on_event(Event::Ran {
                        id,
                        key: &key,
                        action: &action,
                        width: self.width,
                    });
                }
                (Some(key), action)
            }
        };
        self.reports[at] = Some(InstanceReport {
            id: id.clone(),
            key,
            action,
        });
    }

    /// Every instance's report in plan order, or the first failure.
    fn finish(self) -> Result<Vec<InstanceReport>, ExecError> {
        match self.failure {
            Some(error) => Err(error),
            None => Ok(self.reports.into_iter().flatten().collect()),
        }
    }
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
        instance: &'static str,
        label: &'static str,
        value: f64,
    }

    /// Doubles the value of the source of the same instance name.
    struct Double {
        instance: &'static str,
    }

    impl Stage for Source {
        fn id(&self) -> InstanceId {
            InstanceId::new("source", self.instance)
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
            InstanceId::new("double", self.instance)
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
            vec![InstanceId::new("source", self.instance)]
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
        let instance = "a";
        vec![
            Box::new(Source {
                instance,
                label,
                value,
            }),
            Box::new(Double { instance }),
        ]
    }

    fn options(force: &[&str], jobs: usize) -> RunOptions {
        RunOptions {
            only: Vec::new(),
            force: force.iter().map(ToString::to_string).collect(),
            verbosity: Verbosity::Quiet,
            sharding: Sharding::default(),
            jobs,
        }
    }

    fn computed(store: &Store, stages: &[Box<dyn Stage>], force: &[&str]) -> Vec<String> {
        let options = options(force, 2);
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
    fn instances_computed_at_once_are_the_instances_computed_one_by_one() {
        let instances = ["a", "b", "c", "d"];
        let mut stages: Vec<Box<dyn Stage>> = Vec::new();
        for (instance, value) in instances.into_iter().zip([1.0, 2.0, 3.0, 4.0]) {
            stages.push(Box::new(Source {
                instance,
                label: "x",
                value,
            }));
        }
        for instance in instances {
            stages.push(Box::new(Double { instance }));
        }
        let outcome = |jobs: usize| {
            let store = temporary_store(&format!("jobs-{jobs}"));
            let mut lines = 0;
            let reports = run(&store, &stages, &options(&[], jobs), &mut |_| lines += 1).unwrap();
            let manifests: Vec<(String, Vec<String>)> = reports
                .iter()
                .map(|report| {
                    let id = &report.id;
                    let manifest = store.latest_manifest_of(&id.stage, &id.instance).unwrap();
                    assert_eq!(report.key.as_ref(), Some(&manifest.key));
                    let files = manifest.files.into_iter().map(|file| file.sha256);
                    (manifest.key, files.collect())
                })
                .collect();
            assert_eq!(lines, 0, "a quiet run reports nothing");
            let ids: Vec<String> = reports.iter().map(|r| r.id.to_string()).collect();
            (ids, manifests)
        };
        let (ids, one_by_one) = outcome(1);
        assert_eq!(ids.len(), 8);
        assert_eq!(ids[0], "source[a]", "reports come in plan order");
        assert_eq!(ids[7], "double[d]");
        assert_eq!(outcome(3), (ids, one_by_one));
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
            ..options(&[], 2)
        };
        let error = run(&store, &plan("x", 1.0), &options, &mut |_| {}).unwrap_err();
        assert!(
            error.to_string().contains("unknown stage `sorce`"),
            "{error}"
        );
    }
}
