//! Importance-sampled, stratified, randomized quasi-Monte Carlo scenes for the
//! collision kernel (physics.md §3, numerics.md "Sampling scenes").
//!
//! In the frame of the special particle (at rest at the origin), a scene is the
//! pair of thermal launch velocities `(u2, u3)` and the free-flight arrival
//! offset `tau = t3 - t2` at the origin. In the dilute limit the kernel is
//!
//! `G(u' -> u) du = 1/2 int du2 du3 dtau  w(u2) w(u3) Dhist(u2, u3, tau)`,
//! `w(u) = f0(u + u') |u|`,
//!
//! (units of `rho^2 l v_th`; the 1/2 undoes counting each physical configuration
//! under both labellings of the two thermal particles). The sign patterns of
//! `(u2, u3)` split it into strata: `Opposite` (`u2 > 0 > u3`, which with the
//! relabelled `u2 < 0 < u3` cancels the 1/2) and `SameSide` (`u2, u3 > 0`,
//! whose exact mirror image supplies `u2, u3 < 0`, together cancelling the 1/2).
//! Every scene of either stratum is used with its mirror image at half weight
//! each (see `kernel::contributions`). Speeds are drawn with the exact inverse CDF of the `u' = 0`
//! launch density `|u| exp(-u^2/2)`, the offset from a mixture of a Gaussian
//! core and a Cauchy tail on the collision time `T = 1/|u2| + 1/|u3|` and a
//! defensive uniform component; the weight is target over the whole mixture
//! density (balance heuristic). Coordinates come from Owen-scrambled Sobol'
//! points, one independent randomization per replicate.

use std::collections::HashMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::launch::{
    shifted_launch_speed_above, shifted_speed_density, shifted_speed_density_above,
    thermal_launch_speed,
};
use super::offset_quadrature::OffsetRule;
use super::potential::Potential;
use super::quasi_random::{ScrambledSobol, standard_normal_quantile};
use super::scan::LaunchPair;
use super::scene::{Collision, EngineSettings, collide};

/// Sign pattern of the two thermal launches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stratum {
    /// `u2 > 0 > u3`: arrivals from both sides.
    Opposite,
    /// `u2, u3 > 0`; the mirror image stands for `u2, u3 < 0`.
    SameSide,
    /// The literal algorithm of physics.md §3 (any signs, exponential launch
    /// delay at a finite density), kept to validate the others.
    Literal,
}

impl Stratum {
    /// Every stratum, in table order.
    pub const ALL: [Stratum; 3] = [Stratum::Opposite, Stratum::SameSide, Stratum::Literal];

    /// The strata of the importance sampler.
    pub const IMPORTANCE: [Stratum; 2] = [Stratum::Opposite, Stratum::SameSide];

    /// Index used in tables (0 opposite, 1 same side, 2 literal).
    pub fn index(self) -> u32 {
        match self {
            Stratum::Opposite => 0,
            Stratum::SameSide => 1,
            Stratum::Literal => 2,
        }
    }

    /// Inverse of [`Stratum::index`].
    pub fn from_index(index: u32) -> Option<Stratum> {
        Stratum::ALL.into_iter().find(|s| s.index() == index)
    }
}

/// Mixture proposal for the arrival offset, in units of the collision time `T`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OffsetProposal {
    /// Weight of the Gaussian core.
    pub core_weight: f64,
    /// Standard deviation of the core, in `T`.
    pub core_width: f64,
    /// Weight of the Cauchy tail.
    pub tail_weight: f64,
    /// Half-width at half-maximum of the Cauchy tail, in `T`.
    pub tail_width: f64,
    /// Weight of the uniform component (the rest).
    pub uniform_weight: f64,
    /// Half-range of the uniform component, in `T`.
    pub uniform_range: f64,
}

impl Default for OffsetProposal {
    /// The compromise of numerics.md: near bins kept, `a_n` gain ~x60.
    fn default() -> Self {
        OffsetProposal {
            core_weight: 0.5,
            core_width: 0.7,
            tail_weight: 0.45,
            tail_width: 1.0,
            uniform_weight: 0.05,
            uniform_range: 40.0,
        }
    }
}

impl OffsetProposal {
    /// Maps a uniform coordinate in `[0, 1)` to an offset (piecewise inverse CDF:
    /// the coordinate first selects the component, then its rescaled remainder
    /// is inverted within it, which keeps low discrepancy inside each piece).
    pub fn offset(&self, coordinate: f64, collision_time: f64) -> f64 {
        let total = self.core_weight + self.tail_weight + self.uniform_weight;
        let x = coordinate * total;
        if x < self.core_weight {
            let p = (x / self.core_weight).clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON);
            self.core_width * collision_time * standard_normal_quantile(p)
        } else if x < self.core_weight + self.tail_weight {
            let p = (x - self.core_weight) / self.tail_weight;
            self.tail_width * collision_time * libm::tan(std::f64::consts::PI * (p - 0.5))
        } else {
            let p = (x - self.core_weight - self.tail_weight) / self.uniform_weight;
            self.uniform_range * collision_time * (2.0 * p - 1.0)
        }
    }

    /// Mixture density of `offset` (per unit scaled time).
    pub fn density(&self, offset: f64, collision_time: f64) -> f64 {
        let total = self.core_weight + self.tail_weight + self.uniform_weight;
        let core = {
            let sigma = self.core_width * collision_time;
            libm::exp(-0.5 * (offset / sigma).powi(2))
                / (sigma * (2.0 * std::f64::consts::PI).sqrt())
        };
        let tail = {
            let gamma = self.tail_width * collision_time;
            gamma / (std::f64::consts::PI * (offset * offset + gamma * gamma))
        };
        let half = self.uniform_range * collision_time;
        let uniform = if offset.abs() <= half {
            0.5 / half
        } else {
            0.0
        };
        (self.core_weight * core + self.tail_weight * tail + self.uniform_weight * uniform) / total
    }
}

/// One sampled scene with its proposal density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledScene {
    /// Stratum it was drawn in.
    pub stratum: Stratum,
    /// Launch velocity of the first arrival, `v_th`, special frame.
    pub u2: f64,
    /// Launch velocity of the second arrival.
    pub u3: f64,
    /// Arrival offset `tau`, `l / v_th`.
    pub offset: f64,
    /// Joint proposal density of `(|u2|, |u3|, tau)` within the stratum.
    pub proposal_density: f64,
}

/// Launch-speed proposal: the launch density of a special particle moving with
/// `shift`, or, with `spread > 0`, an equal mixture of those for `shift - spread`,
/// `shift` and `shift + spread` (defensive: reweighting to any `u'` within reach
/// of one component stays efficient; the density is the whole mixture's).
/// With `slow_share > 0`, the coordinates below `slow_share` form a stratum
/// of their own: speeds uniform in `[0, slow_speed)`; the rest map through the
/// mixture truncated to speeds above `slow_speed`. A launch pair with a slow
/// launch (speed `v`) has an offset integral growing like `1 / v` (the slow
/// particle lingers near the special one for a time `~ l / v`): under the
/// launch density alone (`~ v` near 0) its weight has unbounded variance,
/// which the far kernel's bath part inherits; in the slow stratum the weight
/// falls like `v` and the product stays bounded, while every weight stays
/// smooth within its stratum (the strata meet at a dyadic coordinate, so
/// each holds whole elementary intervals of the Sobol' points).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaunchProposal {
    /// `u'` of the central component, `v_th`.
    pub shift: f64,
    /// Distance of the side components (0: a single component).
    pub spread: f64,
    /// Share of each launch coordinate, `[0, slow_share)`, in the slow stratum
    /// (0: none; absent from the serialized proposal then). A power of 1/2.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub slow_share: f64,
    /// Upper end of the slow stratum's speeds, `v_th` (in units of the
    /// widened speeds where a width applies).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub slow_speed: f64,
}

/// `true` for an exact 0 (serde's `skip_serializing_if`).
fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

impl LaunchProposal {
    /// The `u' = 0` launch density alone.
    pub const THERMAL: LaunchProposal = LaunchProposal {
        shift: 0.0,
        spread: 0.0,
        slow_share: 0.0,
        slow_speed: 0.0,
    };

    /// The same proposal without a slow stratum.
    pub fn without_slow_stratum(&self) -> LaunchProposal {
        LaunchProposal {
            slow_share: 0.0,
            slow_speed: 0.0,
            ..*self
        }
    }

    /// The `u'` of each component, `v_th`: the shift, and with a spread the
    /// shift minus and plus it.
    pub fn component_shifts(&self) -> impl Iterator<Item = f64> + '_ {
        self.components()
            .iter()
            .map(|c| self.shift + c * self.spread)
    }

    fn components(&self) -> &'static [f64] {
        if self.spread == 0.0 {
            &[0.0]
        } else {
            &[-1.0, 0.0, 1.0]
        }
    }

    /// Speed of a particle arriving from side `side` (+1: moving right) for a
    /// uniform coordinate: below `slow_share` linear in the slow stratum, else
    /// the rest of the coordinate selects the component and its remainder is
    /// inverted within it (above `slow_speed`). `width` scales every speed (1:
    /// the launch densities themselves; see [`LaunchProposal::density`]).
    pub fn speed(&self, coordinate: f64, side: f64, width: f64) -> f64 {
        if coordinate < self.slow_share {
            return width * self.slow_speed * coordinate / self.slow_share;
        }
        let coordinate = (coordinate - self.slow_share) / (1.0 - self.slow_share);
        let components = self.components();
        let scaled = coordinate * components.len() as f64;
        let k = (scaled as usize).min(components.len() - 1);
        let shift = side * (self.shift + components[k] * self.spread) / width;
        // Without a stratum `slow_speed` is 0, below which nothing lies: the
        // launch density's own map, to the bit.
        width * shifted_launch_speed_above(scaled - k as f64, shift, self.slow_speed)
    }

    /// Density of `speed` on side `side` under the whole proposal, each
    /// component widened by `width`: `v exp(-(v + b)^2 / (2 width^2))`
    /// normalized, i.e. the launch density of a gas `width^2` times hotter,
    /// and with a slow stratum `slow_share / slow_speed` below `slow_speed`
    /// and the components truncated above it (`1 / v_th`).
    pub fn density(&self, speed: f64, side: f64, width: f64) -> f64 {
        let scaled = speed / width;
        if scaled < self.slow_speed {
            return self.slow_share / self.slow_speed / width;
        }
        let components = self.components();
        let launched = components
            .iter()
            .map(|c| {
                let shift = side * (self.shift + c * self.spread) / width;
                shifted_speed_density_above(scaled, shift, self.slow_speed)
            })
            .sum::<f64>()
            / components.len() as f64;
        (1.0 - self.slow_share) * launched / width
    }
}

/// Width of the same-side launch speeds, relative to the launch density's,
/// when launch pairs are integrated over the offset: a same-side pair's
/// offset integral is largest for one fast and one moderate launch (`u2 ~ 3.5,
/// u3 ~ 1`: four times the stratum's mean), which the launch density reaches
/// only at the edge of its coordinate; 25% wider speeds cut the stratum's
/// error 1.8x at 2048 pairs (n = 6, three seeds, docs/benchmarks.md), while
/// for the opposite-side stratum any width but 1 loses (0.9: x11, 1.25: x2.3).
pub const SAME_SIDE_QUADRATURE_WIDTH: f64 = 1.25;

/// The launch pair in `stratum` at the unit-square point `[x_first, x_second]`,
/// with its proposal density of `(|u2|, |u3|)` under `launch`. With
/// `fold_same_side`, a same-side point is first folded onto the half of the
/// square below its diagonal ([`folded_same_side`]) and its speeds widened
/// by [`SAME_SIDE_QUADRATURE_WIDTH`]: valid when the scene's
/// integrand is symmetric under exchanging the two launches, as a launch
/// pair's offset integral over a symmetric range is. The density is that
/// of the unordered pair: the fold's density on its half over 2, since each
/// folded point stands for both orderings. Launch pairs integrated over the offset
/// (`fold_same_side`) draw the slow stratum: a slow launch's offset integral
/// grows like `1/v`, so without it a pair with a slow launch has a weight of
/// unbounded variance (single same-side such pairs carried the far kernel's
/// spread at 24 x 16384 pairs: docs/benchmarks.md, "The same-side slow
/// stratum"); a launch mixture without it undercounted the sweep's
/// recombination rates, which slow same-side pairs carry: at `theta = 100`
/// the thermal rate fell 60% short of `3 K_b k_d`, and 4-9% at `theta <=
/// 20`, docs/lennard-jones.md). Every pair is folded so that the stratum's
/// edge stays straight ([`folded_same_side`]).
/// With sampled offsets the stratum doubled the error of `a` and is not
/// used.
pub fn sample_launch(
    point: [f64; 2],
    stratum: Stratum,
    launch: &LaunchProposal,
    fold_same_side: bool,
) -> (LaunchPair, f64) {
    let third_sign = if stratum == Stratum::Opposite {
        -1.0
    } else {
        1.0
    };
    let fold = fold_same_side && stratum == Stratum::SameSide;
    let launch = if fold_same_side {
        *launch
    } else {
        launch.without_slow_stratum()
    };
    // The unordered pair's density factor: a folded point stands for both
    // orderings, so its fold's density counts half.
    let ([x_first, x_second], fold_density, width) = if fold {
        let folded = folded_same_side(point, launch.slow_share);
        (
            folded.coordinates,
            0.5 * folded.density,
            SAME_SIDE_QUADRATURE_WIDTH,
        )
    } else {
        (point, 1.0, 1.0)
    };
    let first = launch.speed(x_first, 1.0, width);
    let second = launch.speed(x_second, third_sign, width);
    let pair = LaunchPair {
        u2: first,
        u3: third_sign * second,
    };
    let density = launch.density(first, 1.0, width)
        * launch.density(second, third_sign, width)
        * fold_density;
    (pair, density)
}

/// A same-side point folded onto the half of the unit square below its
/// diagonal: the launch coordinates `[c_first, c_second]` (`c_second <=
/// c_first`) and the fold's density there (2 for a uniform fold; the
/// half-square has area 1/2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Folded {
    /// `[c_first, c_second]`, the larger coordinate first.
    pub coordinates: [f64; 2],
    /// Density of the folded points on the half-square `c_second <= c_first`.
    pub density: f64,
}

/// Folds the unit square onto its half `c_second <= c_first`, in two
/// strata split at the dyadic `x_first = 2 slow`:
/// * the slow strip, `x_first < 2 slow`: the smaller coordinate linear in
///   `x_first`, `c_second = x_first / 2` (below `slow`), `c_first = c_second +
///   x_second (1 - c_second)`, density `2 / (1 - c_second)`;
/// * the rest, the triangle above `slow`: `c_first = slow + (1 - slow)
///   sqrt(u)` (the larger of two uniform coordinates, `u` the rest of
///   `x_first` rescaled to `[0, 1)`), `c_second = slow + x_second (c_first -
///   slow)`, density `2 (1 - 2 slow) / (1 - slow)^2`.
///
/// A same-side launch pair's offset integral vanishes along the diagonal
/// `u2 = u3` (no three-body encounter without a relative speed) with a kink
/// that runs obliquely through the square, which randomized quasi-Monte Carlo
/// integrates poorly; folded, the diagonal is the edge `x_second = 1` of the
/// rest and `x_second = 0` of the strip. The slow stratum of the smaller
/// speed (`c_second < slow`) is exactly the strip: a straight edge at a
/// dyadic coordinate, so each stratum holds whole elementary intervals of
/// the Sobol' points, and both maps are smooth where the integrand is not
/// small (the square root's edge, `u -> 0`, is where both speeds are at the
/// bottom of the rest: the smallest integrands). With `slow = 0` it is the
/// fold through the larger coordinate alone. A fold with uniform density
/// and a straight edge must take the smaller coordinate as `1 - sqrt(1 -
/// x_first)`, whose square root sits where both launches are fast and the
/// integrand is largest: that fold cost `a_6` 1.9x in error at 4096 launch
/// pairs (docs/benchmarks.md, "The same-side fold").
pub fn folded_same_side([x_first, x_second]: [f64; 2], slow: f64) -> Folded {
    let strip = 2.0 * slow;
    if x_first < strip {
        let smaller = 0.5 * x_first;
        Folded {
            coordinates: [smaller + x_second * (1.0 - smaller), smaller],
            density: 2.0 / (1.0 - smaller),
        }
    } else {
        let rest = (x_first - strip) / (1.0 - strip);
        let larger = slow + (1.0 - slow) * rest.sqrt();
        Folded {
            coordinates: [larger, slow + x_second * (larger - slow)],
            density: 2.0 * (1.0 - strip) / ((1.0 - slow) * (1.0 - slow)),
        }
    }
}

/// Scene of the literal algorithm (physics.md §3) at `u' = 0` and density
/// `rho * l`: velocities of either sign from `P_launch(u) = |u| exp(-u^2/2) / 2`,
/// launch delay `dt` from `r exp(-r dt)` with `r = rho l sqrt(2/pi)`, entry at
/// `-sign(u) L/2`. Its proposal density `P(u2) P(u3) r exp(-r dt)` makes the
/// kernel weight `w w exp(-r dt) / density = r(0)^2 / r`, the literal estimator.
pub fn literal_scene(coordinates: [f64; 3], density: f64, launch_length: f64) -> SampledScene {
    let [x_delay, x_first, x_second] = coordinates;
    let velocity = |x: f64| {
        let speed = thermal_launch_speed((2.0 * x).fract());
        if x < 0.5 { speed } else { -speed }
    };
    let (u2, u3) = (velocity(x_first), velocity(x_second));
    let rate = density * (2.0 / std::f64::consts::PI).sqrt();
    let delay = -libm::log1p(-x_delay) / rate;
    let offset = delay + 0.5 * launch_length * (1.0 / u3.abs() - 1.0 / u2.abs());
    SampledScene {
        stratum: Stratum::Literal,
        u2,
        u3,
        offset,
        proposal_density: 0.25
            * shifted_speed_density(u2.abs(), 0.0)
            * shifted_speed_density(u3.abs(), 0.0)
            * rate
            * libm::exp(-rate * delay),
    }
}

/// How many scenes of which strata and randomizations to draw.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplingPlan {
    /// Seed of every randomization.
    pub seed: u64,
    /// Independent randomizations (replicates).
    pub randomizations: u32,
    /// Scenes per randomization in the opposite-side stratum.
    pub opposite_points: u32,
    /// Scenes per randomization in the same-side stratum.
    pub same_side_points: u32,
    /// Offset proposal.
    pub proposal: OffsetProposal,
    /// Scrambled Sobol' points (`true`) or independent uniform points (`false`,
    /// plain Monte Carlo: only for measuring what quasi-random points gain).
    pub quasi_random: bool,
    /// Launch-speed proposal.
    pub launch: LaunchProposal,
    /// How the arrival offset of each launch pair is integrated (absent from
    /// the serialized plan when sampled, so keys of sampled plans stay as
    /// they were).
    #[serde(default, skip_serializing_if = "OffsetIntegration::is_sampled")]
    pub offsets: OffsetIntegration,
}

/// How the arrival-offset dimension of the kernel integral is done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OffsetIntegration {
    /// One offset per launch pair from the plan's mixture proposal: every
    /// point of the three-dimensional point set is one scene.
    #[default]
    Sampled,
    /// Every launch pair (a two-dimensional point set) integrated over the
    /// offset by the nested rule: one scene per node.
    Quadrature(OffsetRule),
}

impl OffsetIntegration {
    /// `true` for [`OffsetIntegration::Sampled`].
    pub fn is_sampled(&self) -> bool {
        matches!(self, OffsetIntegration::Sampled)
    }
}

/// The leading `share` (in `(0, 1]`) of the launch points of every
/// randomization and stratum, at least one each, in their order. The leading
/// points of a scrambled Sobol' sequence are themselves a randomized
/// quasi-Monte Carlo set (and those of a plain one a Monte Carlo sample), so
/// estimates from the subset stay unbiased: a re-integration at other
/// settings can afford a share, paired with the same share of the full set.
pub fn leading_share(launches: Vec<LaunchPoint>, share: f64) -> Vec<LaunchPoint> {
    let mut counts: HashMap<(u32, u32), u32> = HashMap::new();
    for launch in &launches {
        *counts
            .entry((launch.randomization, launch.stratum.index()))
            .or_default() += 1;
    }
    let kept = |launch: &LaunchPoint| {
        let count = counts[&(launch.randomization, launch.stratum.index())];
        launch.point < ((f64::from(count) * share).ceil() as u32).max(1)
    };
    launches.into_iter().filter(kept).collect()
}

/// One sampled launch pair with its place in the point set: what the
/// `launches` stage draws and the `collisions` stage integrates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaunchPoint {
    /// Randomization.
    pub randomization: u32,
    /// Stratum.
    pub stratum: Stratum,
    /// Point index within the randomization and stratum.
    pub point: u32,
    /// The launch velocities, `v_th`, special frame.
    pub launch: LaunchPair,
    /// Proposal density of `(|u2|, |u3|)` within the stratum, `1 / v_th^2`.
    pub density: f64,
    /// The point's third coordinate in `(0, 1)`: the offset's when offsets are
    /// sampled, the node grid's move ([`OffsetRule::coarse_nodes`]) under the quadrature.
    pub offset_coordinate: f64,
}

/// One integrated scene with its place in the point set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneRecord {
    /// Randomization.
    pub randomization: u32,
    /// Point index.
    pub point: u32,
    /// Node of the offset rule within the point's launch pair (0 for sampled offsets).
    pub node: u32,
    /// Error bound of the launch pair's offset rule on `int kick^2 dtau`,
    /// `v_th^2 l / v_th` (0 for sampled offsets, whose error is statistical).
    pub quadrature_error: f64,
    /// The sampled scene.
    pub scene: SampledScene,
    /// Its integration.
    pub collision: Collision,
}

/// Launch points per chunk of parallel work when each is one scene.
const CHUNK_SCENES: usize = 512;

/// Launch points per chunk when each is integrated by quadrature (49 scenes each by default).
const CHUNK_PAIRS: usize = 8;

/// The power of two nearest to `count` (at least 2) in the logarithm: scrambled
/// Sobol' points converge fastest as complete nets of `2^m` points.
pub fn nearest_power_of_two(count: f64) -> u32 {
    2u32.pow(libm::log2(count.max(2.0)).round().clamp(1.0, 31.0) as u32)
}

impl SamplingPlan {
    /// Splits `points` per randomization between the strata, a fraction
    /// `same_side` to the same-side stratum, each rounded to a power of two.
    pub fn allocate(&mut self, points: u32, same_side: f64) {
        let same = f64::from(points) * same_side;
        self.opposite_points = nearest_power_of_two(f64::from(points) - same);
        self.same_side_points = nearest_power_of_two(same);
    }

    /// Scenes per randomization of a stratum.
    pub fn points(&self, stratum: Stratum) -> u32 {
        match stratum {
            Stratum::Opposite => self.opposite_points,
            Stratum::SameSide => self.same_side_points,
            Stratum::Literal => 0,
        }
    }

    /// Total number of scenes.
    pub fn total(&self) -> u64 {
        u64::from(self.randomizations) * u64::from(self.opposite_points + self.same_side_points)
    }

    /// Unit-cube point `index` of one randomization and stratum. Each
    /// (randomization, stratum) has its own Owen-scrambled Sobol' set; plain Monte
    /// Carlo takes the first point of a separately scrambled set per index, which
    /// is uniformly distributed and independent of all others.
    pub fn coordinates(&self, randomization: u32, stratum: Stratum, index: u32) -> [f64; 3] {
        let stream = 3 * u64::from(randomization) + u64::from(stratum.index());
        if self.quasi_random {
            ScrambledSobol::new(self.seed, stream).point(index)
        } else {
            ScrambledSobol::new(!self.seed, (stream << 32) | u64::from(index)).point(0)
        }
    }

    /// The launch points of the randomizations in `randomizations`, in table
    /// order (randomization, stratum, point).
    pub fn launch_points(&self, randomizations: std::ops::Range<u32>) -> Vec<LaunchPoint> {
        let mut points = Vec::new();
        for randomization in randomizations {
            for stratum in Stratum::IMPORTANCE {
                points.extend((0..self.points(stratum)).map(|point| {
                    let [offset_coordinate, x_first, x_second] =
                        self.coordinates(randomization, stratum, point);
                    let (launch, density) = sample_launch(
                        [x_first, x_second],
                        stratum,
                        &self.launch,
                        !self.offsets.is_sampled(),
                    );
                    LaunchPoint {
                        randomization,
                        stratum,
                        point,
                        launch,
                        density,
                        offset_coordinate,
                    }
                }));
            }
        }
        points
    }

    /// Samples and integrates every scene (see [`SamplingPlan::integrate_launches`]).
    pub fn integrate_all(
        &self,
        potential: &Potential,
        engine: &EngineSettings,
        done: impl Fn(usize) + Sync,
    ) -> Vec<SceneRecord> {
        let launches = self.launch_points(0..self.randomizations);
        self.integrate_launches(&launches, potential, engine, done)
    }

    /// Integrates the scenes of `launches` in chunks in parallel, records in
    /// launch order (the same bytes for any thread count or split of the
    /// launches). `done` hears the launch points of every finished chunk.
    pub fn integrate_launches(
        &self,
        launches: &[LaunchPoint],
        potential: &Potential,
        engine: &EngineSettings,
        done: impl Fn(usize) + Sync,
    ) -> Vec<SceneRecord> {
        let size = match self.offsets {
            OffsetIntegration::Sampled => CHUNK_SCENES,
            OffsetIntegration::Quadrature(_) => CHUNK_PAIRS,
        };
        launches
            .par_chunks(size)
            .map(|chunk| {
                let records: Vec<SceneRecord> = chunk
                    .iter()
                    .flat_map(|launch| self.integrate(launch, potential, engine))
                    .collect();
                done(chunk.len());
                records
            })
            .collect::<Vec<_>>()
            .concat()
    }

    /// The scenes of one launch point: one at its sampled offset, or one per
    /// node of the offset rule. A node's proposal density is the pair's over
    /// its weight, so that summing a pair's nodes gives its offset integral
    /// over its density.
    pub fn integrate(
        &self,
        point: &LaunchPoint,
        potential: &Potential,
        engine: &EngineSettings,
    ) -> Vec<SceneRecord> {
        let scene = |offset: f64, density: f64| SampledScene {
            stratum: point.stratum,
            u2: point.launch.u2,
            u3: point.launch.u3,
            offset,
            proposal_density: density,
        };
        match &self.offsets {
            OffsetIntegration::Sampled => {
                let time = point.launch.collision_time();
                let offset = self.proposal.offset(point.offset_coordinate, time);
                vec![SceneRecord {
                    randomization: point.randomization,
                    point: point.point,
                    node: 0,
                    quadrature_error: 0.0,
                    scene: scene(offset, point.density * self.proposal.density(offset, time)),
                    collision: collide(potential, engine, point.launch.lines(offset)),
                }]
            }
            OffsetIntegration::Quadrature(rule) => {
                let integral =
                    rule.integrate(potential, engine, point.launch, point.offset_coordinate);
                integral
                    .nodes
                    .iter()
                    .zip(0..)
                    .map(|(node, index)| SceneRecord {
                        randomization: point.randomization,
                        point: point.point,
                        node: index,
                        quadrature_error: integral.error,
                        scene: scene(node.offset, point.density / node.weight),
                        collision: node.collision,
                    })
                    .collect()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offsets drawn from uniform coordinates follow the mixture density: the
    /// fraction of a fine coordinate grid mapped below `c` equals the
    /// integral of the density up to `c`.
    #[test]
    fn offsets_follow_the_mixture_density() {
        let proposal = OffsetProposal::default();
        let time = 2.3;
        let grid = 1_000_000;
        let offsets: Vec<f64> = (0..grid)
            .map(|k| proposal.offset((f64::from(k) + 0.5) / f64::from(grid), time))
            .collect();
        for c in [-50.0, -3.0, -1.0, 0.0, 0.4, 2.0, 30.0] {
            let fraction = offsets.iter().filter(|&&t| t <= c).count() as f64 / f64::from(grid);
            let (low, steps) = (-1e5, 2_000_000);
            let h = (c - low) / f64::from(steps);
            let integral: f64 = (0..steps)
                .map(|k| proposal.density(low + h * (f64::from(k) + 0.5), time))
                .sum::<f64>()
                * h;
            let tail_below = proposal.tail_weight
                * (0.5 + (libm::atan(low / (proposal.tail_width * time))) / std::f64::consts::PI);
            assert!(
                (fraction - integral - tail_below).abs() < 2e-5,
                "c = {c}: {fraction} vs {}",
                integral + tail_below
            );
        }
    }

    /// Speeds drawn through the launch mixture follow its density: the fraction
    /// of a fine coordinate grid mapped below `v` equals the integral of the
    /// density up to `v`, on both sides, for the launch densities and for
    /// the widened same-side speeds of the quadrature, without and with the
    /// slow component.
    #[test]
    fn launch_mixture_speeds_follow_its_density() {
        for (slow_share, slow_speed) in [(0.0, 0.0), (1.0 / 32.0, 0.1)] {
            let launch = LaunchProposal {
                shift: 0.5,
                spread: 2.0,
                slow_share,
                slow_speed,
            };
            speeds_follow_the_density(&launch);
        }
    }

    /// The check of [`launch_mixture_speeds_follow_its_density`] for one proposal.
    fn speeds_follow_the_density(launch: &LaunchProposal) {
        let grid = 200_000;
        for (side, width) in [(1.0, 1.0), (-1.0, 1.0), (1.0, SAME_SIDE_QUADRATURE_WIDTH)] {
            let speeds: Vec<f64> = (0..grid)
                .map(|k| launch.speed((f64::from(k) + 0.5) / f64::from(grid), side, width))
                .collect();
            for v in [0.02, 0.3, 1.0, 2.0, 3.5] {
                let fraction = speeds.iter().filter(|&&s| s <= v).count() as f64 / f64::from(grid);
                let h = 1e-5;
                let steps = (v / h) as u32;
                let integral: f64 = (0..steps)
                    .map(|k| launch.density(h * (f64::from(k) + 0.5), side, width))
                    .sum::<f64>()
                    * h;
                assert!(
                    (fraction - integral).abs() < 2e-5,
                    "side {side} width {width} v {v}: {fraction} vs {integral}"
                );
            }
        }
    }

    /// The fold maps the unit square onto the half below its diagonal with
    /// the density it states: weighted by `1 / density`, the folded points
    /// measure every region `{larger <= a, smaller <= b}` as its area, with
    /// and without a slow strip; the strip is exactly `smaller < slow`, and
    /// the smaller coordinate is continuous across its edge `x_first = 2
    /// slow` (the larger is not: the strata are mapped apart).
    #[test]
    fn folding_covers_the_half_square_with_its_density() {
        let grid = 400;
        let cell = |i: u32| (f64::from(i) + 0.5) / f64::from(grid);
        for slow in [0.0, 1.0 / 16.0, 1.0 / 64.0] {
            let folded: Vec<Folded> = (0..grid * grid)
                .map(|k| folded_same_side([cell(k / grid), cell(k % grid)], slow))
                .collect();
            assert!(folded.iter().all(|f| f.coordinates[1] <= f.coordinates[0]));
            for a in [0.1, 0.5, 0.9] {
                for b in [0.03, 0.05, 0.3, 0.8] {
                    let measured = folded
                        .iter()
                        .filter(|f| f.coordinates[0] <= a && f.coordinates[1] <= b)
                        .map(|f| 1.0 / f.density)
                        .sum::<f64>()
                        / folded.len() as f64;
                    let lower = b.min(a);
                    let area = 0.5 * lower * lower + (a - lower) * b;
                    assert!(
                        (measured - area).abs() < 2.5e-3,
                        "slow {slow}, {a} {b}: {measured} vs {area}"
                    );
                }
            }
            for x_first in [0.0, 0.5 * slow, 2.0 * slow - 1e-12, 2.0 * slow, 0.3, 0.999] {
                let smaller = folded_same_side([x_first, 0.4], slow).coordinates[1];
                assert_eq!(smaller < slow, x_first < 2.0 * slow, "{slow} {x_first}");
            }
            let below = folded_same_side([2.0 * slow - 1e-13, 0.7], slow).coordinates;
            let above = folded_same_side([2.0 * slow, 0.7], slow).coordinates;
            assert!((below[1] - above[1]).abs() < 1e-12, "{below:?} {above:?}");
        }
        // Without a strip: the larger of two uniform coordinates, `sqrt(x)`.
        let plain = folded_same_side([0.25, 0.5], 0.0);
        assert_eq!(plain.coordinates, [0.5, 0.25]);
        assert_eq!(plain.density, 2.0);
    }

    /// The mixture density integrates to one (trapezoid on a wide grid plus
    /// the analytic Cauchy tails beyond it).
    #[test]
    fn mixture_density_is_normalized() {
        let proposal = OffsetProposal::default();
        let time = 1.7;
        let edge = 2000.0 * time;
        let steps = 4_000_000;
        let h = 2.0 * edge / f64::from(steps);
        let inside: f64 = (0..=steps)
            .map(|k| {
                let weight = if k == 0 || k == steps { 0.5 } else { 1.0 };
                weight * proposal.density(-edge + h * f64::from(k), time)
            })
            .sum::<f64>()
            * h;
        let gamma = proposal.tail_width * time;
        let outside =
            proposal.tail_weight * 2.0 * (0.5 - libm::atan(edge / gamma) / std::f64::consts::PI);
        assert!(
            (inside + outside - 1.0).abs() < 1e-6,
            "{}",
            inside + outside
        );
    }
}
