//! `collisions`: importance-sampled, stratified, randomized quasi-Monte Carlo
//! three-body scenes of one potential, integrated by the engine (physics.md
//! §3). For inverse power laws the events do not depend on `rho`, `T` or `u'`:
//! the `kernel` and `moments` stages reweight them.
//!
//! Work is split into chunks of consecutive points of one randomization and
//! stratum ([`SamplingPlan::chunks`](crate::physics::sampling::SamplingPlan));
//! chunks run in parallel and are written in order, so the bytes do not depend
//! on the thread count.

use std::ops::Range;

use serde_json::Value;

use crate::config::CollisionsParams;
use crate::kernel::Event;
use crate::kernel::{Target, pilot_same_side_fraction};
use crate::physics::sampling::{SceneRecord, Stratum};
use crate::pipeline::table::{f64_values, text_values, u32_values};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

/// The `collisions` stage for one potential.
pub struct CollisionsStage {
    params: CollisionsParams,
    instance: String,
}

impl CollisionsStage {
    /// The collisions of a potential, named by the potential.
    pub fn new(params: CollisionsParams) -> CollisionsStage {
        let instance = params.potential.id();
        CollisionsStage { params, instance }
    }

    /// A variant (e.g. another tolerance) under its own instance name.
    pub fn variant(params: CollisionsParams, instance: String) -> CollisionsStage {
        CollisionsStage { params, instance }
    }

    /// Instance id of the collisions named `name` (a potential id, or a variant's name).
    pub fn instance(name: &str) -> InstanceId {
        InstanceId::new("collisions", name)
    }

    /// The instances of scene sets `main` and `other`, `other` left out when
    /// it is the same set (a stage then reads it once).
    pub fn instances(main: &str, other: &str) -> Vec<InstanceId> {
        let mut ids = vec![CollisionsStage::instance(main)];
        if other != main {
            ids.push(CollisionsStage::instance(other));
        }
        ids
    }
}

impl Stage for CollisionsStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("collisions", &self.instance)
    }

    fn version(&self) -> u32 {
        2
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["events"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    /// The configured split's total; the pilot may change it (see `run`).
    fn work_units(&self) -> u64 {
        self.params.sampling.total()
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        self.run_shard(inputs, 0..self.params.sampling.randomizations, progress)
    }

    /// Randomizations are independent: a shard integrates some of them.
    fn shard_units(&self) -> u32 {
        self.params.sampling.randomizations
    }

    fn run_shard(
        &self,
        _inputs: &[Input],
        randomizations: Range<u32>,
        progress: &Progress,
    ) -> Result<Vec<Table>, StageError> {
        let mut plan = self.params.sampling;
        if self.params.pilot_points > 0 {
            let target = Target::dilute(0.0);
            // Without any contribution (n = 2) the configured split stays.
            if let Some(fraction) = pilot_same_side_fraction(
                &plan,
                &self.params.potential,
                &self.params.pilot_engine,
                &target,
                self.params.pilot_points,
            ) {
                plan.allocate(self.params.points, fraction);
            }
        }
        let per_randomization = plan.total() / u64::from(plan.randomizations.max(1));
        progress.set_total(per_randomization * u64::from(randomizations.len() as u32));
        let rows = plan.integrate_randomizations(
            &self.params.potential,
            &self.params.engine,
            randomizations,
            |count| progress.advance(count as u64),
        );
        let allocation = format!(
            "opposite {} same-side {} per randomization",
            plan.opposite_points, plan.same_side_points
        );
        Ok(vec![
            events_table(&rows)?.with_metadata("ternary.strata_allocation", allocation),
        ])
    }
}

/// The events table of integrated scenes.
pub fn events_table(rows: &[SceneRecord]) -> Result<Table, StageError> {
    let f64_of = |f: &dyn Fn(&SceneRecord) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let u32_of = |f: &dyn Fn(&SceneRecord) -> u32| rows.iter().map(f).collect::<Vec<u32>>();
    let columns = vec![
        Column::u32(
            "randomization",
            "1",
            "independent randomization (replicate) of the point set",
            u32_of(&|r| r.randomization),
        ),
        Column::u32(
            "stratum",
            "1",
            "sign pattern: 0 opposite sides (u2 > 0 > u3), 1 same side (u2, u3 > 0; mirror image stands for both < 0)",
            u32_of(&|r| r.scene.stratum.index()),
        ),
        Column::u32(
            "point",
            "1",
            "index of the scrambled Sobol' point",
            u32_of(&|r| r.point),
        ),
        Column::f64(
            "u2",
            "v_th",
            "launch velocity of the first arrival, special particle's frame",
            f64_of(&|r| r.scene.u2),
        ),
        Column::f64(
            "u3",
            "v_th",
            "launch velocity of the second arrival",
            f64_of(&|r| r.scene.u3),
        ),
        Column::f64(
            "arrival_offset",
            "l/v_th",
            "free-flight arrival time of particle 3 minus that of particle 2 at the special particle",
            f64_of(&|r| r.scene.offset),
        ),
        Column::f64(
            "proposal_density",
            "1/(v_th^2 l/v_th)",
            "joint sampling density of (|u2|, |u3|, arrival_offset) within the stratum",
            f64_of(&|r| r.scene.proposal_density),
        ),
        Column::f64(
            "out_slow",
            "v_th",
            "slowest outgoing velocity, special particle's frame",
            f64_of(&|r| r.collision.outgoing[0]),
        ),
        Column::f64(
            "out_middle",
            "v_th",
            "middle outgoing velocity",
            f64_of(&|r| r.collision.outgoing[1]),
        ),
        Column::f64(
            "out_fast",
            "v_th",
            "fastest outgoing velocity",
            f64_of(&|r| r.collision.outgoing[2]),
        ),
        Column::f64(
            "self_kick",
            "v_th",
            "velocity change of the special particle (sorted matching)",
            f64_of(&|r| r.collision.self_kick(0.0)),
        ),
        Column::text(
            "outcome",
            "scattered, recombined or failed_*",
            rows.iter()
                .map(|r| r.collision.outcome.name().to_string())
                .collect(),
        ),
        Column::f64(
            "energy_error",
            "1",
            "(E_out - E_in) / (E_in + well depth) of the relative motion",
            f64_of(&|r| r.collision.energy_error),
        ),
        Column::u32(
            "force_evaluations",
            "1",
            "evaluations of the three pair forces",
            u32_of(&|r| r.collision.evaluations),
        ),
    ];
    Ok(Table::new("events", columns)?.with_metadata(
        "ternary.description",
        "integrated three-body scenes for the collision kernel".into(),
    ))
}

/// The events of a `collisions` artifact, for the kernel estimators.
pub fn read_events(input: &Input) -> Result<Vec<Event>, StageError> {
    let batch = input
        .tables
        .get("events")
        .ok_or_else(|| StageError::Input(format!("{} has no events table", input.id)))?;
    let randomization = u32_values(batch, "randomization")?;
    let stratum = u32_values(batch, "stratum")?;
    let (u2, u3) = (f64_values(batch, "u2")?, f64_values(batch, "u3")?);
    let offset = f64_values(batch, "arrival_offset")?;
    let density = f64_values(batch, "proposal_density")?;
    let outgoing = [
        f64_values(batch, "out_slow")?,
        f64_values(batch, "out_middle")?,
        f64_values(batch, "out_fast")?,
    ];
    let outcome = text_values(batch, "outcome")?;
    (0..batch.num_rows())
        .map(|k| {
            let stratum = Stratum::from_index(stratum[k]).ok_or_else(|| {
                StageError::Input(format!("row {k}: unknown stratum {}", stratum[k]))
            })?;
            let failed = outcome[k].starts_with("failed");
            Ok(Event {
                stratum,
                randomization: randomization[k],
                u2: u2[k],
                u3: u3[k],
                offset: offset[k],
                proposal_density: density[k],
                outgoing: (!failed).then(|| [outgoing[0][k], outgoing[1][k], outgoing[2][k]]),
            })
        })
        .collect()
}
