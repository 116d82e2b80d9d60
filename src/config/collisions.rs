//! `[collisions]`: how kernel scenes are sampled (numerics.md "Sampling scenes").

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, potential_named};
use crate::physics::offset_quadrature::OffsetRule;
use crate::physics::potential::Potential;
use crate::physics::sampling::{LaunchProposal, OffsetIntegration, OffsetProposal, SamplingPlan};
use crate::physics::scene::EngineSettings;

/// `[collisions]`: how kernel scenes are sampled (numerics.md "Sampling scenes").
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct CollisionsConfig {
    /// How the arrival offset of each launch pair is integrated.
    pub method: OffsetMethod,
    /// Seed of every randomization.
    pub seed: u64,
    /// Independent randomizations (replicates); standard errors come from their spread.
    pub randomizations: u32,
    /// Points per randomization (both strata together); each stratum's share is
    /// rounded to the nearest power of two. A point is one scene when offsets
    /// are sampled, one launch pair (`quadrature.halvings` sets its scenes, 49 by default) with `method = "quadrature"`.
    pub points: u32,
    /// Fraction of the scenes drawn in the same-side stratum when no pilot runs.
    pub same_side_fraction: f64,
    /// Pilot scenes per stratum that set the strata allocation (Neyman); 0 disables.
    pub pilot_points: u32,
    /// Scrambled Sobol' points (default) or plain Monte Carlo points.
    pub quasi_random: bool,
    /// `u'` the launch-speed proposal is tuned for.
    pub launch_shift: f64,
    /// Side components of the launch proposal at `launch_shift +- launch_spread` (0: none).
    pub launch_spread: f64,
    /// Share of each launch coordinate in the slow stratum (speeds uniform
    /// below `slow_launch_speed`: bounded weights for pairs with a slow
    /// launch, whose bath part feeds the far kernel); 0 or a power of 1/2
    /// from 1/2 to 1/1024.
    pub slow_launch_share: f64,
    /// Upper end of the slow stratum's speeds, `v_th`, in (0, 1].
    pub slow_launch_speed: f64,
    /// Mixture proposal of the arrival offset (`[collisions.proposal]`, sampled offsets).
    pub proposal: OffsetProposal,
    /// The nested offset rule (`[collisions.quadrature]`, `method = "quadrature"`).
    pub quadrature: OffsetRule,
    /// Per-potential replacements of `points`, keyed by potential id
    /// (`[collisions.points_per_potential]`, e.g. `"lj-0.1" = 8192`).
    pub points_per_potential: BTreeMap<String, u32>,
    /// Per-potential replacements of `method`, keyed by potential id
    /// (`[collisions.method_per_potential]`, e.g. `"lj-0.1" = "sampled"`).
    pub method_per_potential: BTreeMap<String, OffsetMethod>,
    /// Per-potential strata of the main set (the launch pairs at the kernel's
    /// `u'` that `a_n` comes from, and the convergence study's
    /// re-integrations of them), keyed by potential id
    /// (`[collisions.strata_per_potential]`, e.g. `"ipp-6" = { opposite =
    /// 4096, same_side = 2048 }`): the split the randomized quasi-Monte
    /// Carlo errors ask for, in place of the pilot's, whose plain Monte
    /// Carlo spreads do not see how fast each stratum's error falls. The
    /// potential's other sets (the sweep's, those tuned to one `u'`) keep
    /// the pilot.
    pub strata_per_potential: BTreeMap<String, StrataPoints>,
    /// Per-potential slow strata of the main set, keyed by potential id
    /// (`[collisions.slow_launch_per_potential]`, e.g. `"lj-1" = { share =
    /// 0.25, speed = 0.5 }`), in place of `slow_launch_share` and
    /// `slow_launch_speed`: where a potential's far kernel comes from pairs
    /// whose slower launch is below `speed` (a well's bound and orbiting
    /// pairs), a wider stratum bounds their weights. The potential's other
    /// sets keep the global stratum.
    pub slow_launch_per_potential: BTreeMap<String, SlowLaunch>,
}

/// The slow stratum of one potential's main set.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SlowLaunch {
    /// Share of each launch coordinate in the stratum: 0 or a power of 1/2
    /// from 1/2 to 1/1024.
    pub share: f64,
    /// Upper end of the stratum's speeds, `v_th`, in (0, 1].
    pub speed: f64,
}

/// Launch points per randomization of each stratum, both powers of two.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StrataPoints {
    /// Points with the launches on opposite sides.
    pub opposite: u32,
    /// Points with both launches on one side.
    pub same_side: u32,
}

impl Default for CollisionsConfig {
    fn default() -> Self {
        CollisionsConfig {
            method: OffsetMethod::Sampled,
            seed: 1,
            randomizations: 16,
            points: 4096,
            same_side_fraction: 0.15,
            pilot_points: 1024,
            quasi_random: true,
            launch_shift: 0.0,
            launch_spread: 0.0,
            slow_launch_share: 0.0625,
            slow_launch_speed: 0.1,
            proposal: OffsetProposal::default(),
            quadrature: OffsetRule::default(),
            points_per_potential: BTreeMap::new(),
            method_per_potential: BTreeMap::new(),
            strata_per_potential: BTreeMap::new(),
            slow_launch_per_potential: BTreeMap::new(),
        }
    }
}

/// `collisions.method`: how each launch pair's arrival offset is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OffsetMethod {
    /// One offset per scene from the mixture proposal (three-dimensional
    /// randomized quasi-Monte Carlo).
    Sampled,
    /// The nested trapezoid rule on `tau = T sinh(s)` per launch pair, the
    /// launch pairs by two-dimensional randomized quasi-Monte Carlo.
    Quadrature,
}

impl StrataPoints {
    /// Points per randomization, both strata.
    pub fn total(&self) -> u32 {
        self.opposite + self.same_side
    }
}

/// Resolved parameters of a `collisions` instance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CollisionsParams {
    /// The potential.
    pub potential: Potential,
    /// Engine settings.
    pub engine: EngineSettings,
    /// What to draw (strata split by `same_side_fraction` unless a pilot decides).
    pub sampling: SamplingPlan,
    /// Scenes per randomization, both strata.
    pub points: u32,
    /// Pilot scenes per stratum for the Neyman allocation (0: keep the fraction).
    pub pilot_points: u32,
    /// Integrate only this share of every randomization's and stratum's
    /// launch pairs, the leading ones
    /// ([`leading_share`](crate::physics::sampling::leading_share)); `None`: all.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub launch_share: Option<f64>,
}

/// Resolved parameters of a `launches` instance: everything that decides the
/// launch points, and nothing of the engine that integrates them (the pilot
/// runs with its own fixed engine), so re-integrations share one launch set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LaunchesParams {
    /// The potential (the pilot's strata split depends on it).
    pub potential: Potential,
    /// What to draw (strata split by `same_side_fraction` unless a pilot decides).
    pub sampling: SamplingPlan,
    /// Points per randomization, both strata.
    pub points: u32,
    /// Pilot points per stratum for the Neyman allocation (0: keep the fraction).
    pub pilot_points: u32,
}

impl CollisionsParams {
    /// The parameters of the launch points these collisions integrate.
    pub fn launches(&self) -> LaunchesParams {
        LaunchesParams {
            potential: self.potential,
            sampling: self.sampling,
            points: self.points,
            pilot_points: self.pilot_points,
        }
    }
}

/// Largest number of randomizations (replicates) of a collisions instance.
pub const MAX_RANDOMIZATIONS: u32 = 1024;

/// Largest pilot scenes per stratum.
pub const MAX_PILOT_POINTS: u32 = 1 << 20;

/// Largest scenes of one collisions instance (randomizations x points): each
/// event takes ~120 bytes in memory before it is encoded, so 2^25 events take
/// ~4 GB (the publication study draws 2^19).
pub const MAX_SCENES: u64 = 1 << 25;

/// Checks the scenes per randomization `points` (under `key`) and the
/// instance's total against [`MAX_SCENES`].
fn check_scenes(
    sampling: &CollisionsConfig,
    method: OffsetMethod,
    points: u32,
    key: &str,
) -> Result<(), Invalid> {
    check(points >= 2, key, "must be at least 2")?;
    let per_point = match method {
        OffsetMethod::Sampled => 1,
        OffsetMethod::Quadrature => u64::from(sampling.quadrature.nodes()),
    };
    let total = u64::from(sampling.randomizations) * u64::from(points) * per_point;
    check(
        total <= MAX_SCENES,
        key,
        format!(
            "{points} points x {per_point} scenes x {} randomizations = {total} exceeds {MAX_SCENES} (~4 GB of events in memory): use fewer points",
            sampling.randomizations
        ),
    )
}

/// `slow` is a stratum the Sobol' points resolve: a dyadic share
/// (`share_key`) and a speed in (0, 1] (`speed_key`).
fn check_slow_launch(slow: SlowLaunch, share_key: &str, speed_key: &str) -> Result<(), Invalid> {
    check(
        is_dyadic_share(slow.share),
        share_key,
        format!(
            "{} must be 0 or a power of 1/2 from 1/2 to 1/1024 (whole elementary intervals of the Sobol' points)",
            slow.share
        ),
    )?;
    check(
        slow.speed > 0.0 && slow.speed <= 1.0,
        speed_key,
        format!("{} is outside (0, 1]", slow.speed),
    )
}

/// `true` for 0 and `2^-k`, `k = 1..=10`.
fn is_dyadic_share(share: f64) -> bool {
    share == 0.0 || (1..=10).any(|k| share == libm::pow(0.5, f64::from(k)))
}

/// Largest `|u' - launch_shift|` that reweighting covers: beyond it the launch
/// speeds that matter lie past the largest speed the point set can draw (6.8
/// v_th), biasing the kernel by > 0.5%, and the weights' variance explodes.
pub(super) const REWEIGHTING_REACH: f64 = 3.0;

/// `true` when `u'` lies within reach of a component of the launch proposal.
pub(super) fn within_reach(launch: &LaunchProposal, u_prime: f64) -> bool {
    (u_prime - launch.shift).abs() <= REWEIGHTING_REACH + launch.spread
}

impl CollisionsConfig {
    /// Checks the sampling settings and the per-potential point counts.
    pub(super) fn validate(&self, potentials: &[Potential]) -> Result<(), Invalid> {
        let sampling = self;
        check(
            (2..=MAX_RANDOMIZATIONS).contains(&sampling.randomizations),
            "collisions.randomizations",
            format!(
                "{} is outside [2, {MAX_RANDOMIZATIONS}]: at least 2 are needed for a standard error",
                sampling.randomizations
            ),
        )?;
        self.validate_quadrature()?;
        for id in self.method_per_potential.keys() {
            potential_named(
                id,
                potentials,
                format!("collisions.method_per_potential.{id}"),
            )?;
        }
        for potential in potentials {
            let id = potential.id();
            if !self.points_per_potential.contains_key(&id) {
                check_scenes(
                    sampling,
                    self.method_of(potential),
                    sampling.points,
                    "collisions.points",
                )?;
            }
        }
        check(
            sampling.points >= 2,
            "collisions.points",
            "must be at least 2",
        )?;
        check(
            sampling.pilot_points == 0 || (16..=MAX_PILOT_POINTS).contains(&sampling.pilot_points),
            "collisions.pilot_points",
            format!(
                "{} must be 0 (no pilot) or in [16, {MAX_PILOT_POINTS}]: fewer pilot scenes cannot estimate a stratum's spread",
                sampling.pilot_points
            ),
        )?;
        check(
            sampling.same_side_fraction > 0.0 && sampling.same_side_fraction < 1.0,
            "collisions.same_side_fraction",
            format!(
                "{} must lie in (0, 1): both strata need scenes",
                sampling.same_side_fraction
            ),
        )?;
        check(
            sampling.launch_shift.is_finite() && sampling.launch_shift.abs() <= 3.0,
            "collisions.launch_shift",
            format!("{} is outside [-3, 3]", sampling.launch_shift),
        )?;
        check(
            sampling.launch_spread.is_finite() && (0.0..=3.0).contains(&sampling.launch_spread),
            "collisions.launch_spread",
            format!("{} is outside [0, 3]", sampling.launch_spread),
        )?;
        check_slow_launch(
            SlowLaunch {
                share: sampling.slow_launch_share,
                speed: sampling.slow_launch_speed,
            },
            "collisions.slow_launch_share",
            "collisions.slow_launch_speed",
        )?;
        for (id, &slow) in &self.slow_launch_per_potential {
            let key = format!("collisions.slow_launch_per_potential.{id}");
            potential_named(id, potentials, key.clone())?;
            check_slow_launch(slow, &format!("{key}.share"), &format!("{key}.speed"))?;
        }
        let proposal = &sampling.proposal;
        for (key, value) in [
            ("core_weight", proposal.core_weight),
            ("tail_weight", proposal.tail_weight),
            ("uniform_weight", proposal.uniform_weight),
        ] {
            check(
                value.is_finite() && value >= 0.0,
                format!("collisions.proposal.{key}"),
                format!("{value} must be a finite weight >= 0"),
            )?;
        }
        check(
            proposal.tail_weight > 0.0,
            "collisions.proposal.tail_weight",
            "must be > 0: only the Cauchy tail covers every offset, so no scene is left out",
        )?;
        for (key, value) in [
            ("core_width", proposal.core_width),
            ("tail_width", proposal.tail_width),
            ("uniform_range", proposal.uniform_range),
        ] {
            check(
                value.is_finite() && value > 0.0,
                format!("collisions.proposal.{key}"),
                format!("{value} must be a finite width > 0 (in collision times)"),
            )?;
        }
        for (id, &points) in &self.points_per_potential {
            let key = format!("collisions.points_per_potential.{id}");
            let potential = potential_named(id, potentials, key.clone())?;
            check_scenes(self, self.method_of(&potential), points, &key)?;
        }
        for (id, strata) in &self.strata_per_potential {
            let key = format!("collisions.strata_per_potential.{id}");
            let potential = potential_named(id, potentials, key.clone())?;
            for (stratum, points) in [
                ("opposite", strata.opposite),
                ("same_side", strata.same_side),
            ] {
                check(
                    points >= 2 && points.is_power_of_two(),
                    format!("{key}.{stratum}"),
                    format!("{points} must be a power of two >= 2 (complete Sobol' nets)"),
                )?;
            }
            check_scenes(self, self.method_of(&potential), strata.total(), &key)?;
        }
        Ok(())
    }

    /// Checks `[collisions.quadrature]`.
    fn validate_quadrature(&self) -> Result<(), Invalid> {
        let rule = &self.quadrature;
        check(
            rule.coarse_step.is_finite() && rule.coarse_step > 0.0 && rule.coarse_step <= 2.0,
            "collisions.quadrature.coarse_step",
            format!(
                "{} is outside (0, 2] (a step in s, tau = T sinh(s))",
                rule.coarse_step
            ),
        )?;
        check(
            rule.half_range.is_finite()
                && rule.half_range >= rule.coarse_step
                && rule.half_range <= 12.0,
            "collisions.quadrature.half_range",
            format!(
                "{} is outside [coarse_step, 12] (offsets reach T sinh(half_range))",
                rule.half_range
            ),
        )?;
        check(
            (1..=8).contains(&rule.halvings),
            "collisions.quadrature.halvings",
            format!(
                "{} is outside [1, 8] (the last halving's change is each pair's error bound; 8: 256x the coarse nodes)",
                rule.halvings
            ),
        )?;
        check(
            rule.end_kick.is_finite() && rule.end_kick > 0.0 && rule.end_kick <= 1e-3,
            "collisions.quadrature.end_kick",
            format!(
                "{} is outside (0, 1e-3] (the largest kick left at a pair's range ends, v_th; keep it below half the kernel's bin)",
                rule.end_kick
            ),
        )
    }

    /// The method of `potential`: its `method_per_potential` entry, else `method`.
    pub fn method_of(&self, potential: &Potential) -> OffsetMethod {
        self.method_per_potential
            .get(&potential.id())
            .copied()
            .unwrap_or(self.method)
    }

    /// How the plan of `potential` integrates offsets.
    fn offsets(&self, potential: &Potential) -> OffsetIntegration {
        match self.method_of(potential) {
            OffsetMethod::Sampled => OffsetIntegration::Sampled,
            OffsetMethod::Quadrature => OffsetIntegration::Quadrature(self.quadrature),
        }
    }

    /// The launch-speed proposal of the kernel's scenes.
    pub fn launch(&self) -> LaunchProposal {
        self.launch_with(SlowLaunch {
            share: self.slow_launch_share,
            speed: self.slow_launch_speed,
        })
    }

    /// The launch-speed proposal with the slow stratum `slow`.
    fn launch_with(&self, slow: SlowLaunch) -> LaunchProposal {
        LaunchProposal {
            shift: self.launch_shift,
            spread: self.launch_spread,
            slow_share: slow.share,
            slow_speed: if slow.share > 0.0 { slow.speed } else { 0.0 },
        }
    }

    /// Resolved parameters of collision scenes of `potential` that draw
    /// `share` (in (0, 1]) of its points per randomization, at least 2 (the
    /// whole set when `share` is 1), split by the pilot.
    pub fn params_with_share(
        &self,
        potential: Potential,
        engine: EngineSettings,
        share: f64,
    ) -> CollisionsParams {
        let mut params = self.piloted_params(potential, engine);
        if share < 1.0 {
            params.points = ((f64::from(params.points) * share).round() as u32).max(2);
            params
                .sampling
                .allocate(params.points, self.same_side_fraction);
        }
        params
    }

    /// Resolved parameters of the main set of `potential`: its
    /// `strata_per_potential` entry fixes the split, else the pilot's, and
    /// its `slow_launch_per_potential` entry the slow stratum.
    pub fn params(&self, potential: Potential, engine: EngineSettings) -> CollisionsParams {
        let mut params = self.piloted_params(potential, engine);
        if let Some(slow) = self.slow_launch_per_potential.get(&potential.id()) {
            params.sampling.launch = self.launch_with(*slow);
        }
        if let Some(strata) = self.strata_per_potential.get(&potential.id()) {
            params.sampling.opposite_points = strata.opposite;
            params.sampling.same_side_points = strata.same_side;
            params.points = strata.total();
            params.pilot_points = 0;
        }
        params
    }

    /// Resolved parameters of collision scenes of `potential` whose strata
    /// split the pilot decides (`collisions.pilot_points`; without a pilot,
    /// `same_side_fraction`).
    pub fn piloted_params(&self, potential: Potential, engine: EngineSettings) -> CollisionsParams {
        let mut plan = SamplingPlan {
            seed: self.seed,
            randomizations: self.randomizations,
            opposite_points: 0,
            same_side_points: 0,
            proposal: self.proposal,
            quasi_random: self.quasi_random,
            launch: self.launch(),
            offsets: self.offsets(&potential),
        };
        let points = self
            .points_per_potential
            .get(&potential.id())
            .copied()
            .unwrap_or(self.points);
        plan.allocate(points, self.same_side_fraction);
        CollisionsParams {
            potential,
            engine,
            sampling: plan,
            points,
            pilot_points: self.pilot_points,
            launch_share: None,
        }
    }
}
