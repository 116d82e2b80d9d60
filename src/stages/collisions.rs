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
use crate::contract::{self, Rows};
use crate::kernel::{Event, Target, pilot_same_side_fraction};
use crate::physics::sampling::{SceneRecord, Stratum};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};

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
        InstanceId::new(contract::collisions::STAGE, name)
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
        InstanceId::new(contract::collisions::STAGE, &self.instance)
    }

    fn version(&self) -> u32 {
        3
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::collisions::TABLE.name]
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
    use contract::collisions::*;
    Ok(Rows::new(rows)
        .with(RANDOMIZATION, |r| r.randomization)
        .with(STRATUM, |r| r.scene.stratum.index())
        .with(POINT, |r| r.point)
        .with(NODE, |r| r.node)
        .with(QUADRATURE_ERROR, |r| r.quadrature_error)
        .with(U2, |r| r.scene.u2)
        .with(U3, |r| r.scene.u3)
        .with(ARRIVAL_OFFSET, |r| r.scene.offset)
        .with(PROPOSAL_DENSITY, |r| r.scene.proposal_density)
        .with(OUT_SLOW, |r| r.collision.outgoing[0])
        .with(OUT_MIDDLE, |r| r.collision.outgoing[1])
        .with(OUT_FAST, |r| r.collision.outgoing[2])
        .with(SELF_KICK, |r| r.collision.self_kick(0.0))
        .with(OUTCOME, |r| r.collision.outcome.name().to_string())
        .with(ENERGY_ERROR, |r| r.collision.energy_error)
        .with(FORCE_EVALUATIONS, |r| r.collision.evaluations)
        .table(&TABLE)?)
}

/// The events of a `collisions` artifact, for the kernel estimators.
pub fn read_events(input: &Input) -> Result<Vec<Event>, StageError> {
    use contract::collisions::*;
    let batch = TABLE.of(input)?;
    let randomization = RANDOMIZATION.read(batch)?;
    let stratum = STRATUM.read(batch)?;
    let node = NODE.read(batch)?;
    let (u2, u3) = (U2.read(batch)?, U3.read(batch)?);
    let offset = ARRIVAL_OFFSET.read(batch)?;
    let density = PROPOSAL_DENSITY.read(batch)?;
    let outgoing = [
        OUT_SLOW.read(batch)?,
        OUT_MIDDLE.read(batch)?,
        OUT_FAST.read(batch)?,
    ];
    let outcome = OUTCOME.read(batch)?;
    (0..batch.num_rows())
        .map(|k| {
            let stratum = Stratum::from_index(stratum[k]).ok_or_else(|| {
                StageError::Input(format!("row {k}: unknown stratum {}", stratum[k]))
            })?;
            let failed = outcome[k].starts_with("failed");
            Ok(Event {
                stratum,
                randomization: randomization[k],
                node: node[k],
                u2: u2[k],
                u3: u3[k],
                offset: offset[k],
                proposal_density: density[k],
                outgoing: (!failed).then(|| [outgoing[0][k], outgoing[1][k], outgoing[2][k]]),
            })
        })
        .collect()
}
