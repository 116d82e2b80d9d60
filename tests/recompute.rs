//! The recompute audit (`ternary verify --recompute`): current artifacts are
//! recomputed from their stored inputs and compared byte for byte under the
//! same key. A planted non-determinism (a stage whose table holds the clock)
//! is caught; the deterministic study passes.

mod common;

use std::time::{SystemTime, UNIX_EPOCH};

use common::{small_study, stdout, ternary, workspace, write_config};
use ternary::pipeline::code::Code;
use ternary::pipeline::executor::{self, Audit, RunOptions, Verbosity};
use ternary::pipeline::shards::Sharding;
use ternary::pipeline::store::Store;
use ternary::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

static TEST_CODE: Code = Code {
    root: "tests/recompute.rs",
    fingerprint: "test",
    parts: &[],
};

/// A test-only stage: one value, either fixed or the clock's nanoseconds
/// (the planted non-determinism).
struct Value {
    clock: bool,
}

impl Stage for Value {
    fn id(&self) -> InstanceId {
        InstanceId::new(if self.clock { "clock" } else { "fixed" }, "a")
    }
    fn code(&self) -> &'static Code {
        &TEST_CODE
    }
    fn params(&self) -> serde_json::Value {
        serde_json::json!({})
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
        let value = if self.clock {
            let now = SystemTime::now().duration_since(UNIX_EPOCH).unwrap();
            f64::from(now.subsec_nanos()) + 1e9 * now.as_secs() as f64
        } else {
            1.5
        };
        Ok(vec![Table::new(
            "value",
            vec![Column::f64("x", "1", "a value", None, vec![value])],
        )?])
    }
}

#[test]
fn a_clock_dependent_stage_is_caught_by_the_recompute_audit() {
    let dir = workspace("recompute-clock");
    let store = Store::open(&dir.join("data")).unwrap();
    let plan: Vec<Box<dyn Stage>> = vec![
        Box::new(Value { clock: false }),
        Box::new(Value { clock: true }),
    ];
    let options = RunOptions {
        only: Vec::new(),
        force: Vec::new(),
        verbosity: Verbosity::Quiet,
        sharding: Sharding::default(),
        jobs: 1,
    };
    executor::run(&store, &plan, &options, &mut |_| {}).unwrap();
    let audits = executor::recompute(&store, &plan, &[], Verbosity::Quiet, &mut |_| {}).unwrap();
    assert_eq!(audits.len(), 2);
    assert!(matches!(audits[0].1, Audit::Same { .. }), "{:?}", audits[0]);
    let Audit::Differs(files) = &audits[1].1 else {
        panic!("the clock went unnoticed: {:?}", audits[1]);
    };
    assert_eq!(files.len(), 1);
    assert_eq!(files[0].0, "value.parquet");
    assert_ne!(files[0].1, files[0].2);
    // `--only` selects stages; the others are only resolved.
    let only = executor::recompute(
        &store,
        &plan,
        &["fixed".into()],
        Verbosity::Quiet,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(only.len(), 1);
    assert_eq!(only[0].0, InstanceId::new("fixed", "a"));
}

#[test]
fn the_study_recomputes_to_its_stored_bytes_and_unfresh_instances_fail_the_audit() {
    let dir = workspace("recompute-study");
    let config = write_config(&dir, &small_study("data"));
    assert!(ternary(&config, &["run", "--quiet"]).status.success());
    let audit = ternary(&config, &["verify", "--recompute"]);
    let text = stdout(&audit);
    assert!(audit.status.success(), "{text}");
    assert!(
        text.contains("0 same key with different bytes, 0 not checked"),
        "{text}"
    );
    assert!(
        text.contains("kernel[ipp-6_u0_rho0]") && text.contains("same bytes"),
        "{text}"
    );
    let kernel = ternary(&config, &["verify", "--recompute", "--only", "kernel"]);
    let lines = stdout(&kernel);
    assert!(kernel.status.success(), "{lines}");
    assert!(!lines.contains("scan["), "{lines}");
    // A stale study cannot be vouched for: the audit says so and fails.
    let stale = small_study("data").replace("points = 7", "points = 9");
    let config = write_config(&dir, &stale);
    let audit = ternary(&config, &["verify", "--recompute", "--only", "scan"]);
    let text = stdout(&audit);
    assert!(!audit.status.success(), "{text}");
    assert!(
        text.contains("not checked: no artifact under the current key; run first"),
        "{text}"
    );
}
