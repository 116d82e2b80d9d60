//! What a run does with one instance, decided from the plan, the options and
//! the store before anything is written ([`decide`]); `run` carries the
//! decision out.

use super::*;

/// One instance as a run sees it.
pub(super) struct Candidate<'a> {
    /// The stage instance.
    pub(super) stage: &'a dyn Stage,
    /// Its inputs' records, `None` while one is not available.
    pub(super) inputs: Option<Vec<InputRecord>>,
    /// Selected: its stage is in `--only` (or there is none), and in a shard
    /// task it is shardable or a prerequisite of the shards.
    pub(super) selected: bool,
    /// `--force` names its stage.
    pub(super) forced: bool,
    /// The shard task's index, when the run is one.
    pub(super) shard_task: Option<u32>,
}

/// What a run does with one instance.
#[derive(Debug)]
pub(super) enum Decision {
    /// Nothing: an input is not available (and the instance is not selected,
    /// or the run is a shard task), so it has no key.
    Unkeyed,
    /// Nothing: not selected, and not fresh.
    Skipped(InstanceRef),
    /// Use the intact artifact under its key.
    Fresh(InstanceRef, Box<Manifest>),
    /// Compute and commit the whole artifact.
    Compute {
        /// The instance with its key.
        entry: InstanceRef,
        /// An artifact is under the key (damaged, or forced): replace it.
        replace: bool,
        /// The problems of the damaged artifact it replaces.
        repaired: Option<String>,
        /// Entries ternary did not write in the artifact under the key: it is
        /// set aside (kept, never deleted) and a new one written.
        foreign: Vec<String>,
    },
    /// In a shard task: compute the instance's shard `index` unless present.
    Shard {
        /// The whole instance with its key.
        entry: InstanceRef,
        /// The shard.
        index: u32,
    },
}

/// What to do with `candidate`, reading (never writing) `store`; `writable`
/// is why the store cannot be written, if it cannot. Fails when a selected
/// instance outside a shard task lacks an input, and when an instance needs
/// computing in a store that cannot be written.
pub(super) fn decide(
    candidate: Candidate<'_>,
    store: &Store,
    writable: Result<(), &str>,
) -> Result<Decision, ExecError> {
    let stage = candidate.stage;
    let id = stage.id();
    let Some(inputs) = candidate.inputs else {
        if candidate.selected && candidate.shard_task.is_none() {
            return Err(ExecError::Plan(format!(
                "{id}: an input is not available; run its upstream stages first (without --only)"
            )));
        }
        return Ok(Decision::Unkeyed);
    };
    let entry = keyed(stage, inputs);
    let existing = match stored(store, stage, &entry.key) {
        Stored::Intact(manifest) if !(candidate.forced && candidate.selected) => {
            return Ok(Decision::Fresh(entry, manifest));
        }
        _ if !candidate.selected => return Ok(Decision::Skipped(entry)),
        existing => existing,
    };
    if let Err(reason) = writable {
        return Err(ExecError::ReadOnly {
            id,
            reason: reason.to_string(),
        });
    }
    if let Some(index) = candidate.shard_task.filter(|_| stage.shard_units() > 0) {
        return Ok(Decision::Shard { entry, index });
    }
    let foreign = match (&existing, candidate.shard_task) {
        (Stored::Absent, _) | (_, Some(_)) => Vec::new(),
        _ => store.foreign_in_artifact(&id.stage, &entry.key, &output_files(stage)),
    };
    Ok(Decision::Compute {
        replace: !matches!(existing, Stored::Absent) && foreign.is_empty(),
        repaired: match existing {
            Stored::Damaged(problems) => Some(problems.join("; ")),
            Stored::Intact(_) | Stored::Absent => None,
        },
        foreign,
        entry,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::code::Code;
    use crate::pipeline::shards::Sharding;
    use crate::pipeline::{Column, Input, Progress, StageError, Table};

    static TEST_CODE: Code = Code {
        root: "src/pipeline/executor/decide.rs",
        fingerprint: "test",
        parts: &[],
    };

    /// A source stage of one value, shardable over `units` when not zero.
    struct Value {
        units: u32,
    }

    impl Stage for Value {
        fn id(&self) -> InstanceId {
            InstanceId::new("value", "a")
        }
        fn code(&self) -> &'static Code {
            &TEST_CODE
        }
        fn params(&self) -> serde_json::Value {
            serde_json::json!({ "value": 1.5 })
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
        fn shard_units(&self) -> u32 {
            self.units
        }
        fn run(&self, _: &[Input], _: &Progress) -> Result<Vec<Table>, StageError> {
            Ok(vec![Table::new(
                "value",
                vec![Column::f64("x", "1", "value", None, vec![1.5])],
            )?])
        }
    }

    const STAGE: Value = Value { units: 0 };

    /// A candidate for `STAGE` with its (empty) inputs, selected, not forced.
    fn candidate(stage: &dyn Stage) -> Candidate<'_> {
        Candidate {
            stage,
            inputs: Some(Vec::new()),
            selected: true,
            forced: false,
            shard_task: None,
        }
    }

    /// The candidate, forced.
    fn forced(stage: &dyn Stage) -> Candidate<'_> {
        Candidate {
            forced: true,
            ..candidate(stage)
        }
    }

    /// An empty store, or one where `STAGE` has been computed.
    fn store(name: &str, computed: bool) -> Store {
        let root =
            std::env::temp_dir().join(format!("ternary-decide-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let store = Store::open(&root).unwrap();
        if computed {
            let options = RunOptions {
                only: Vec::new(),
                force: Vec::new(),
                verbosity: Verbosity::Quiet,
                sharding: Sharding::default(),
                jobs: 1,
            };
            let stages: Vec<Box<dyn Stage>> = vec![Box::new(Value { units: 0 })];
            super::super::run(&store, &stages, &options, &mut |_| {}).unwrap();
        }
        store
    }

    /// The directory of `STAGE`'s artifact in `store`.
    fn artifact(store: &Store) -> std::path::PathBuf {
        let key = match decide(candidate(&STAGE), store, Ok(())).unwrap() {
            Decision::Fresh(entry, _) => entry.key,
            other => panic!("not fresh: {other:?}"),
        };
        store.artifact_dir("value", &key)
    }

    #[test]
    fn an_absent_artifact_is_computed_and_nothing_replaced() {
        let store = store("absent", false);
        let decision = decide(candidate(&STAGE), &store, Ok(())).unwrap();
        assert!(
            matches!(&decision, Decision::Compute { replace: false, repaired: None, foreign, .. } if foreign.is_empty()),
            "{decision:?}"
        );
    }

    #[test]
    fn an_intact_artifact_is_fresh_unless_forced_and_selected() {
        let store = store("intact", true);
        let fresh = decide(candidate(&STAGE), &store, Ok(())).unwrap();
        assert!(matches!(fresh, Decision::Fresh(..)), "{fresh:?}");
        let decision = decide(forced(&STAGE), &store, Ok(())).unwrap();
        assert!(
            matches!(
                decision,
                Decision::Compute {
                    replace: true,
                    repaired: None,
                    ..
                }
            ),
            "{decision:?}"
        );
        // Forced but not selected (`--force value --only other`): fresh.
        let unselected = Candidate {
            forced: true,
            selected: false,
            ..candidate(&STAGE)
        };
        let decision = decide(unselected, &store, Ok(())).unwrap();
        assert!(matches!(decision, Decision::Fresh(..)), "{decision:?}");
        // A fresh instance needs no write access.
        let decision = decide(candidate(&STAGE), &store, Err("read-only")).unwrap();
        assert!(matches!(decision, Decision::Fresh(..)), "{decision:?}");
    }

    #[test]
    fn a_damaged_artifact_is_replaced_with_its_problems_named() {
        let store = store("damaged", true);
        std::fs::write(artifact(&store).join("value.parquet"), b"not parquet").unwrap();
        let decision = decide(candidate(&STAGE), &store, Ok(())).unwrap();
        let Decision::Compute {
            replace: true,
            repaired: Some(problems),
            ..
        } = &decision
        else {
            panic!("{decision:?}");
        };
        assert!(problems.contains("value.parquet"), "{problems}");
    }

    #[test]
    fn an_artifact_with_foreign_files_is_set_aside_not_replaced() {
        let store = store("foreign", true);
        let dir = artifact(&store);
        std::fs::write(dir.join("notes.txt"), b"mine").unwrap();
        // Intact in what ternary wrote, so fresh; forced, it is moved aside whole.
        let fresh = decide(candidate(&STAGE), &store, Ok(())).unwrap();
        assert!(matches!(fresh, Decision::Fresh(..)), "{fresh:?}");
        let decision = decide(forced(&STAGE), &store, Ok(())).unwrap();
        assert!(
            matches!(&decision, Decision::Compute { replace: false, foreign, .. } if foreign == &["notes.txt".to_string()]),
            "{decision:?}"
        );
    }

    #[test]
    fn an_unselected_instance_is_skipped_and_a_missing_input_refused_when_selected() {
        let store = store("skipped", false);
        let unselected = Candidate {
            selected: false,
            ..candidate(&STAGE)
        };
        let decision = decide(unselected, &store, Ok(())).unwrap();
        assert!(matches!(decision, Decision::Skipped(_)), "{decision:?}");
        let waiting = Candidate {
            inputs: None,
            selected: false,
            ..candidate(&STAGE)
        };
        let decision = decide(waiting, &store, Ok(())).unwrap();
        assert!(matches!(decision, Decision::Unkeyed), "{decision:?}");
        let selected = Candidate {
            inputs: None,
            ..candidate(&STAGE)
        };
        let error = decide(selected, &store, Ok(())).unwrap_err();
        assert!(
            error.to_string().contains("an input is not available"),
            "{error}"
        );
        // In a shard task a missing input is the shard's to compute.
        let task = Candidate {
            inputs: None,
            shard_task: Some(0),
            ..candidate(&STAGE)
        };
        let decision = decide(task, &store, Ok(())).unwrap();
        assert!(matches!(decision, Decision::Unkeyed), "{decision:?}");
    }

    #[test]
    fn computing_in_a_read_only_store_is_refused_with_the_reason() {
        let store = store("readonly", false);
        let error = decide(candidate(&STAGE), &store, Err("permission denied")).unwrap_err();
        assert!(
            matches!(&error, ExecError::ReadOnly { reason, .. } if reason == "permission denied"),
            "{error}"
        );
    }

    #[test]
    fn a_shard_task_computes_its_shard_of_a_shardable_instance_only() {
        let store = store("shard", false);
        let shardable = Value { units: 4 };
        let task = Candidate {
            shard_task: Some(2),
            ..candidate(&shardable)
        };
        let decision = decide(task, &store, Ok(())).unwrap();
        assert!(
            matches!(decision, Decision::Shard { index: 2, .. }),
            "{decision:?}"
        );
        // A prerequisite of the shards is computed whole.
        let prerequisite = Candidate {
            shard_task: Some(2),
            ..candidate(&STAGE)
        };
        let decision = decide(prerequisite, &store, Ok(())).unwrap();
        assert!(matches!(decision, Decision::Compute { .. }), "{decision:?}");
    }
}
