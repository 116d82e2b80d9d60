//! The collision sets beyond each potential's main one: the wide set the
//! sweep and the evolution grid read, the sets tuned to one `u'` (the
//! paper's detailed-balance pair), and the launch sets they integrate.

use crate::config::{CollisionsParams, Study};
use crate::contract::{self, instances};
use crate::physics::potential::Potential;
use crate::physics::sampling::OffsetIntegration;
use crate::pipeline::Stage;
use crate::stages::{collisions::CollisionsStage, launches::LaunchesStage};

/// Registers the collisions named `name` after the launch set they
/// integrate: an already registered set with the same parameters (e.g. the
/// main set, for a re-integration at another tolerance), else a new one
/// named like them.
pub(super) fn push_collisions(
    stages: &mut Vec<Box<dyn Stage>>,
    params: CollisionsParams,
    name: String,
) {
    let launches = params.launches();
    let wanted = serde_json::to_value(&launches).unwrap_or_default();
    let existing = stages.iter().find_map(|stage| {
        let id = stage.id();
        (id.stage == contract::launches::STAGE && stage.params() == wanted)
            .then(|| id.instance.clone())
    });
    let launches_name = existing.unwrap_or_else(|| {
        stages.push(Box::new(LaunchesStage::new(launches, name.clone())));
        name.clone()
    });
    stages.push(Box::new(CollisionsStage::new(params, name, launches_name)));
}

/// The collisions instance that reaches every `u'` of the sweep and of the
/// evolution grid: its name and, when it is not the main set, its
/// parameters (the main set with the sweep's launch spread, share of
/// points and randomizations, and under the offset quadrature one halving
/// more: its balance bins lie in the collision's core, where the nodes
/// are point masses; at the kernel's step the pairs `a -> a + 0.02` at
/// `|a| >= 2` fell 3.5-4 errors short of `f0(b)/f0(a)` for n = 6, and
/// within 1.7 with one halving more; docs/benchmarks.md).
pub fn wide_collisions(study: &Study, potential: Potential) -> (String, Option<CollisionsParams>) {
    let sweep = &study.config.sweep;
    let name = instances::wide_collisions(&potential, sweep.launch_spread > 0.0);
    let params = (sweep.launch_spread > 0.0).then(|| {
        let mut params = study.config.collisions.params_with_share(
            potential,
            study.engine(potential),
            sweep.points_share,
        );
        params.sampling.launch.spread = sweep.launch_spread;
        if let Some(randomizations) = sweep.randomizations {
            params.sampling.randomizations = randomizations;
        }
        one_halving_finer(&mut params);
        params
    });
    (name, params)
}

/// The collisions of `potential` drawn for a special particle at `u'`
/// for the sweep's balance pairs: the kernel's plan with the launch
/// density of `u'` (no mixture), named `<id>_u<u'>`. Under the offset
/// quadrature each pair takes one halving more than the kernel's (at
/// most 8): the balance bins lie in the collision's core (`|du| = 0.04`),
/// where nodes are point masses and a finer step is what lowers their
/// error (n = 6: +-0.035 at two halvings in 25 s, +-0.0098 at three in
/// 51 s, +-0.022 at three with half the points; docs/benchmarks.md).
pub(super) fn tuned_collisions(
    study: &Study,
    potential: Potential,
    u_prime: f64,
) -> (String, CollisionsParams) {
    let mut params = study
        .config
        .collisions
        .piloted_params(potential, study.engine(potential));
    params.sampling.launch.shift = u_prime;
    params.sampling.launch.spread = 0.0;
    one_halving_finer(&mut params);
    (instances::tuned_collisions(&potential, u_prime), params)
}

/// Under the offset quadrature, one halving more than `params` have (at most 8).
fn one_halving_finer(params: &mut CollisionsParams) {
    if let OffsetIntegration::Quadrature(rule) = &mut params.sampling.offsets {
        rule.halvings = (rule.halvings + 1).min(8);
    }
}
