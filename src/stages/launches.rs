//! `launches`: the launch pairs `(u2, u3)` of one potential's collision kernel
//! (physics.md §3, numerics.md "Sampling scenes"): scrambled Sobol' points in
//! the two sign strata, split between them by a Neyman pilot, each with its
//! proposal density and the point's third coordinate (the arrival offset's,
//! when offsets are sampled). The `collisions` stage integrates them, so a
//! changed engine or offset rule reuses the launches, and a shard of
//! collisions is a slice (randomizations) of this table.

use serde_json::Value;

use crate::config::LaunchesParams;
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::kernel::{PILOT_ENGINE, Target, pilot_same_side_fraction};
use crate::physics::sampling::{LaunchPoint, SamplingPlan};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};

/// The `launches` stage of one point set.
pub struct LaunchesStage {
    params: LaunchesParams,
    instance: String,
}

impl LaunchesStage {
    /// The launch set named `instance` (a potential id, or a variant's name).
    pub fn new(params: LaunchesParams, instance: String) -> LaunchesStage {
        LaunchesStage { params, instance }
    }

    /// The plan with the strata split the pilot chooses for the self
    /// variance rate at the `u'` of each component of the launch proposal
    /// (its shift alone, for the kernels' sets); without
    /// any contribution, as for n = 2, the configured split stays.
    fn allocated_plan(&self) -> SamplingPlan {
        let mut plan = self.params.sampling;
        if self.params.pilot_points > 0
            && let Some(fraction) = pilot_same_side_fraction(
                &plan,
                &self.params.potential,
                &PILOT_ENGINE,
                &plan
                    .launch
                    .component_shifts()
                    .map(Target::dilute)
                    .collect::<Vec<_>>(),
                self.params.pilot_points,
            )
        {
            plan.allocate(self.params.points, fraction);
        }
        plan
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for LaunchesStage {
    fn id(&self) -> InstanceId {
        instances::launches(&self.instance)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::launches::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        1
    }

    /// Collisions shards slice the launch table: every shard task draws it
    /// (a pilot of ~2 x 1024 scenes) when it is missing.
    fn shard_prerequisite(&self) -> bool {
        true
    }

    fn run(&self, _inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let plan = self.allocated_plan();
        let points = plan.launch_points(0..plan.randomizations);
        progress.advance(1);
        let allocation = format!(
            "opposite {} same-side {} per randomization",
            plan.opposite_points, plan.same_side_points
        );
        Ok(vec![
            launches_table(&points)?.with_metadata("ternary.strata_allocation", allocation),
        ])
    }
}

/// The launches table of `points`.
fn launches_table(points: &[LaunchPoint]) -> Result<Table, StageError> {
    use contract::launches::*;
    Ok(Rows::new(points)
        .with(RANDOMIZATION, |p| p.randomization)
        .with(STRATUM, |p| p.stratum.index())
        .with(POINT, |p| p.point)
        .with(U2, |p| p.launch.u2)
        .with(U3, |p| p.launch.u3)
        .with(LAUNCH_DENSITY, |p| p.density)
        .with(OFFSET_COORDINATE, |p| p.offset_coordinate)
        .table(&TABLE)?)
}
