//! `collisions`: the three-body scenes of one potential's launch pairs (the
//! `launches` stage), integrated by the engine at a sampled arrival offset or
//! at every node of the offset rule (physics.md §3). For inverse power laws
//! the events do not depend on `rho`, `T` or `u'`: the `kernel` and `moments`
//! stages reweight them.
//!
//! Work is split into chunks of consecutive launch points
//! ([`SamplingPlan::integrate_launches`](crate::physics::sampling::SamplingPlan));
//! chunks run in parallel and are written in order, so the bytes do not depend
//! on the thread count or on the shard split.

use std::ops::Range;

use serde_json::Value;

use crate::config::CollisionsParams;
use crate::contract::instances;
use crate::contract::readers::read_launches;
use crate::contract::{self, Rows};
use crate::kernel::bound_pair_energy;
use crate::physics::sampling::{OffsetIntegration, SceneRecord, leading_share};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};

/// The `collisions` stage for one potential.
pub struct CollisionsStage {
    params: CollisionsParams,
    instance: String,
    launches: String,
}

impl CollisionsStage {
    /// The collisions named `instance` (a potential id, or a variant's name,
    /// e.g. another tolerance) of the launch set named `launches`.
    pub fn new(params: CollisionsParams, instance: String, launches: String) -> CollisionsStage {
        CollisionsStage {
            params,
            instance,
            launches,
        }
    }
}

/// CPU seconds per integrated scene of an inverse power law at the engine
/// tolerance [`SCENE_TOLERANCE`]: 13.8-16.9 us in the default study's sets of 1.6
/// to 3.2 million scenes, four integrated at a time (2026-12-03, the 2-core VM,
/// `ternary status --costs`; 19-22 us one at a time, 2026-12-01).
const CPU_PER_SCENE: f64 = 1.47e-5;

/// The tolerance [`CPU_PER_SCENE`] holds at. The order-12 integrator takes
/// `tolerance^(-1/12)` steps: 1.47x at 1e-12 (measured 1.46x), 0.83x at 1e-9
/// (measured 0.91x).
const SCENE_TOLERANCE: f64 = 1e-10;

/// A well of depth `D` (in kT) makes a scene `1 + WELL_COST D^(1/4)` times
/// dearer (bound and orbiting pairs): the default study's Lennard-Jones main
/// sets at 15.1, 17.0, 22.5 and 35.9 us per scene for theta = 100, 20, 1 and
/// 0.05 (`D = 1/(4 theta)`; 2026-12-03), the model 17.6, 19.1, 24.1 and 34.5.
const WELL_COST: f64 = 0.9;

/// Bytes of one scene's row in the events table (the same study: 52.6).
const BYTES_PER_SCENE: f64 = 53.0;

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for CollisionsStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::collisions::STAGE, &self.instance)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::collisions::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![instances::launches(&self.launches)]
    }

    /// The configured split's total; the launches' pilot may change it.
    fn work_units(&self) -> u64 {
        self.params.sampling.total()
    }

    /// Scenes (launch points, times the rule's nodes under the quadrature)
    /// at `CPU_PER_SCENE`, scaled to the potential's well and the engine's
    /// tolerance; one events row of `BYTES_PER_SCENE` each.
    fn cost(&self, _inputs: &[Cost]) -> Cost {
        let nodes = match self.params.sampling.offsets {
            OffsetIntegration::Quadrature(rule) => f64::from(rule.nodes()),
            OffsetIntegration::Sampled => 1.0,
        };
        let share = self.params.launch_share.unwrap_or(1.0);
        let scenes = self.params.sampling.total() as f64 * nodes * share;
        let well = 1.0 + WELL_COST * libm::pow(self.params.potential.well_depth(), 0.25);
        let steps = libm::pow(self.params.engine.tolerance / SCENE_TOLERANCE, -1.0 / 12.0);
        Cost {
            cpu_seconds: scenes * CPU_PER_SCENE * well * steps,
            bytes: scenes * BYTES_PER_SCENE,
            rows: scenes,
        }
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
        inputs: &[Input],
        randomizations: Range<u32>,
        progress: &Progress,
    ) -> Result<Vec<Table>, StageError> {
        let mut launches = read_launches(&inputs[0], randomizations)?;
        if let Some(share) = self.params.launch_share {
            launches = leading_share(launches, share);
        }
        progress.set_total(launches.len() as u64);
        let rows = self.params.sampling.integrate_launches(
            &launches,
            &self.params.potential,
            &self.params.engine,
            |count| progress.advance(count as u64),
        );
        Ok(vec![events_table(&rows)?])
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
        .optional(BINDING_ENERGY, |r| bound_pair_energy(&r.collision))
        .with(ENERGY_ERROR, |r| r.collision.energy_error)
        .with(FORCE_EVALUATIONS, |r| r.collision.evaluations)
        .table(&TABLE)?)
}
