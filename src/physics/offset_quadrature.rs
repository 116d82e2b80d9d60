//! The arrival-offset integral of one launch pair by quadrature.
//!
//! For fixed launch velocities `(u2, u3)` (special frame) the outcome of a
//! scene is a smooth function of the arrival offset `tau`, and every velocity
//! change decays as a power of `|tau|` (about `|tau|^-(n+1)` for an inverse
//! power law). The map `tau = T sinh(s)`, with the collision time
//! `T = 1/|u2| + 1/|u3|`, turns those power-law tails into exponential decay
//! in `s`, where the trapezoid rule converges exponentially fast. Every pair
//! takes the same number of halvings of the coarse step (reusing every node);
//! the change of its self variance integral `int kick^2 dtau` (the `a_n`
//! integrand, `v_th^2 l / v_th`) at the last halving bounds its error. The
//! step is fixed, not chosen per pair from that change: the grid's random
//! move makes each rule unbiased, but a choice between two rules that looks
//! at their results is not (an early stop kept `a_12` 1.4e-4 high, eight of
//! its standard errors; docs/benchmarks.md). This is the inner integral of
//! the kernel's `int du2 du3 dtau` (`sampling`).
//!
//! With a well (Lennard-Jones) the kick is not smooth in `tau` where a pair
//! orbits or is left bound: the rule then converges like a stratified
//! sample, not exponentially, and the last change no longer bounds its
//! error. The moved grid keeps every sum unbiased all the same (jumps
//! included), and the errors the study reports are the randomizations'
//! spread, which holds either way (docs/benchmarks.md, "Lennard-Jones on the
//! offset quadrature").

use super::potential::Potential;
use super::scan::LaunchPair;
use super::scene::{Collision, EngineSettings, collide_all};
use crate::thresholds::DEFAULT_KICK_FLOOR;

/// Nested trapezoid rule on `tau = T sinh(s)`, `|s| <= half_range`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OffsetRule {
    /// Step in `s` of the coarsest rule.
    pub coarse_step: f64,
    /// Largest `|s|`: offsets reach `T sinh(half_range)`.
    pub half_range: f64,
    /// Halvings of `coarse_step` (every pair the same, at least one: the
    /// last one's change is the pair's error bound).
    pub halvings: u32,
    /// Largest kick left at the ends, `v_th`: while any of the three kicks at
    /// an end node exceeds it, the pair's range grows by one finest step at
    /// that end (at most another `half_range`), so that what lies beyond
    /// stays in the kernel's centre bin however slowly the potential decays.
    pub end_kick: f64,
}

impl Default for OffsetRule {
    /// Offsets to `T sinh(3.3) = 13.5 T` (the self variance integral beyond
    /// holds a fraction `~13.5^-(2n+1)` of it, 1e-10 for n = 4; the largest
    /// of a scene's three kicks at the ends is 8e-6 v_th for n = 4 and 9e-8
    /// for n = 6 (medians), inside the centre bin), 13 coarse nodes
    /// halved twice: 49 nodes. Against a rule with a third halving (97 nodes)
    /// on the same pairs, `a_n` moves by 1.6e-9 (n = 6) to 8e-7 (n = 12) of
    /// itself, within the paired error, while each launch pair costs half as
    /// much (docs/benchmarks.md, "Offset quadrature").
    fn default() -> Self {
        OffsetRule {
            coarse_step: 0.5,
            half_range: 3.3,
            halvings: 2,
            end_kick: DEFAULT_END_KICK,
        }
    }
}

/// One node of the rule: an integrated scene and its share of `dtau`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffsetNode {
    /// Arrival offset `tau`, `l / v_th`.
    pub offset: f64,
    /// Quadrature weight, `l / v_th` (step x `dtau/ds`).
    pub weight: f64,
    /// The integrated scene.
    pub collision: Collision,
}

/// The nodes of one launch pair and what the refinement measured.
#[derive(Clone, Debug, PartialEq)]
pub struct OffsetIntegral {
    /// Nodes in ascending offset, weighted for the finest rule reached.
    pub nodes: Vec<OffsetNode>,
    /// `int kick^2 dtau` of the special particle by the finest rule
    /// (failed scenes count as zero), `v_th^2 l / v_th`.
    pub self_variance: f64,
    /// Bound on the error of `self_variance`, `v_th^2 l / v_th`: the last
    /// change, which bounds the coarser rule's error and so, the rule
    /// converging exponentially (each error about the square of the one
    /// before), the finer one's with a wide margin; plus the tails beyond the
    /// range (`tail_estimate`). Without a well; with one, an indicator of
    /// the kick's roughness (see the module's note).
    pub error: f64,
}

/// Default largest kick at the ends of a pair's range, `v_th`: a fifth of the
/// default kernel bin (5e-5), so beyond the range every kick stays in the
/// centre bin. For n = 4 the fixed range `|s| <= 3.3` left kicks up to 2.4e-4
/// at its ends (99th percentile 4e-5; docs/benchmarks.md).
pub const DEFAULT_END_KICK: f64 = 1e-5;

/// Velocity changes below this (`v_th`) are the engine's error floor: an
/// integral made only of them is zero.
const KICK_FLOOR: f64 = DEFAULT_KICK_FLOOR;

impl OffsetRule {
    /// Nodes (scenes) of one launch pair within the range (a pair whose kicks
    /// at the ends exceed [`OffsetRule::end_kick`] takes more).
    pub fn nodes(&self) -> u32 {
        let coarse_intervals = 2 * (self.half_range / self.coarse_step).floor() as u32;
        (coarse_intervals << self.halvings) + 1
    }

    /// Coarse nodes in `s` for the grid coordinate `shift` in `[0, 1)`: the
    /// symmetric grid `k coarse_step`, `|k coarse_step| <= half_range`, moved
    /// by `(shift - 1/2) coarse_step` (0.5: unmoved). Halvings keep the move.
    /// With `shift` uniform, the trapezoid sum of any integrand over the
    /// nodes at step `h` is an unbiased estimate of its integral over the
    /// covered range, also for an integrand that jumps between nodes (the
    /// indicator of a kernel bin or of a truncation `|kick| <= X`), where a
    /// fixed grid is biased; smooth integrands keep the rule's exponential
    /// accuracy.
    pub fn coarse_nodes(&self, shift: f64) -> Vec<f64> {
        let coarse = (self.half_range / self.coarse_step).floor() as i64;
        let moved = (shift - 0.5) * self.coarse_step;
        (-coarse..=coarse)
            .map(|k| k as f64 * self.coarse_step + moved)
            .collect()
    }

    /// Integrates the scenes of `launch` at the rule's nodes (grid coordinate
    /// `shift`, [`OffsetRule::coarse_nodes`]): the coarse step halved
    /// `halvings` times.
    pub fn integrate(
        &self,
        potential: &Potential,
        engine: &EngineSettings,
        launch: LaunchPair,
        shift: f64,
    ) -> OffsetIntegral {
        let time = launch.collision_time();
        let scenes_at = |nodes: &[f64]| {
            let lines: Vec<_> = nodes
                .iter()
                .map(|&s| launch.lines(time * libm::sinh(s)))
                .collect();
            let collisions = collide_all(potential, engine, &lines);
            nodes.iter().copied().zip(collisions).collect::<Vec<_>>()
        };
        let (nodes, step) = self.finest_nodes(shift);
        let scenes = scenes_at(&nodes);
        let error = self.last_change(&scenes, step, time);
        let scenes = self.extend(scenes, step, scenes_at);
        let integral = self.sum(&scenes, step, time);
        let at = |node: &(f64, Collision)| integrand(node, time);
        let ends = scenes.len().saturating_sub(2);
        let tails = tail_estimate(at(&scenes[1]), at(&scenes[0]), step, self.half_range)
            + tail_estimate(
                at(&scenes[ends]),
                at(&scenes[ends + 1]),
                step,
                self.half_range,
            );
        OffsetIntegral {
            nodes: scenes
                .into_iter()
                .map(|(s, collision)| OffsetNode {
                    offset: time * libm::sinh(s),
                    weight: step * time * libm::cosh(s),
                    collision,
                })
                .collect(),
            self_variance: integral,
            error: error + tails,
        }
    }

    /// The nodes in `s` of the finest rule, ascending, and its step: the coarse nodes
    /// ([`OffsetRule::coarse_nodes`]) with the midpoints of each halving between them.
    fn finest_nodes(&self, shift: f64) -> (Vec<f64>, f64) {
        let mut nodes = self.coarse_nodes(shift);
        let mut step = self.coarse_step;
        for _ in 0..self.halvings {
            let midpoints = nodes[1..].iter().map(|&s| s - 0.5 * step).collect();
            nodes = interleave(nodes, midpoints);
            step *= 0.5;
        }
        (nodes, step)
    }

    /// The change of the trapezoid sum at the last halving, between the finest rule's
    /// `scenes` (`step` apart) and every other one of them (infinite without a halving).
    fn last_change(&self, scenes: &[(f64, Collision)], step: f64, time: f64) -> f64 {
        if self.halvings == 0 {
            return f64::INFINITY;
        }
        let coarser: Vec<(f64, Collision)> = scenes.iter().step_by(2).copied().collect();
        (self.sum(scenes, step, time) - self.sum(&coarser, 2.0 * step, time)).abs()
    }

    /// `scenes` (ascending in `s`, `step` apart) grown at each end by one
    /// `step` at a time while a kick at that end exceeds `end_kick`, by at
    /// most `half_range` in `s` per end. The range then depends on the pair,
    /// but only through its own outer kicks: what stays beyond is below
    /// `end_kick` (the trapezoid sum over the grown nodes keeps the grid's move).
    /// `scenes_at(nodes)` integrates the scenes at `nodes`: both ends' next ones together.
    fn extend(
        &self,
        scenes: Vec<(f64, Collision)>,
        step: f64,
        scenes_at: impl Fn(&[f64]) -> Vec<(f64, Collision)>,
    ) -> Vec<(f64, Collision)> {
        let limit = (self.half_range / step).round() as usize;
        let (Some(&first), Some(&last)) = (scenes.first(), scenes.last()) else {
            return scenes;
        };
        // Each end: its outermost scene, its direction in `s` and the scenes added beyond.
        let mut ends = [(first, -1.0, Vec::new()), (last, 1.0, Vec::new())];
        loop {
            let growing: Vec<usize> = (0..ends.len())
                .filter(|&k| ends[k].2.len() < limit && largest_kick(&ends[k].0.1) > self.end_kick)
                .collect();
            if growing.is_empty() {
                break;
            }
            let nodes: Vec<f64> = growing
                .iter()
                .map(|&k| ends[k].0.0 + ends[k].1 * step)
                .collect();
            for (&k, scene) in growing.iter().zip(scenes_at(&nodes)) {
                ends[k].0 = scene;
                ends[k].2.push(scene);
            }
        }
        let [(_, _, mut below), (_, _, above)] = ends;
        below.reverse();
        below.extend(scenes);
        below.extend(above);
        below
    }

    /// Trapezoid sum of `kick^2 dtau/ds` over `scenes` with step `step`.
    fn sum(&self, scenes: &[(f64, Collision)], step: f64, time: f64) -> f64 {
        step * scenes.iter().map(|node| integrand(node, time)).sum::<f64>()
    }
}

/// The integrand `kick^2 dtau/ds = kick^2 T cosh(s)` at the node `(s, scene)`.
fn integrand((s, collision): &(f64, Collision), time: f64) -> f64 {
    time * libm::cosh(*s) * squared_self_kick(collision)
}

/// The integral beyond the last node, from the integrand `kick^2 dtau/ds` at
/// the last node (`outer`) and the one before (`inner`), `step` apart in `s`:
/// in `s` the tails of a power law decay exponentially, so the geometric
/// continuation `step outer r / (1 - r)`, `r = outer / inner`. An end that
/// does not decay is charged as if flat over another `half_range`.
fn tail_estimate(inner: f64, outer: f64, step: f64, half_range: f64) -> f64 {
    if outer == 0.0 {
        return 0.0;
    }
    let ratio = outer / inner;
    if ratio < 1.0 {
        step * outer * ratio / (1.0 - ratio)
    } else {
        half_range * outer
    }
}

/// The largest of a scene's three velocity changes, `v_th` (0 for a failed
/// scene: its outgoing velocities mean nothing).
fn largest_kick(collision: &Collision) -> f64 {
    if collision.outcome.is_failure() {
        return 0.0;
    }
    (0..3)
        .map(|k| (collision.outgoing[k] - collision.incoming[k]).abs())
        .fold(0.0, f64::max)
}

/// `kick^2` of the special particle (zero for failed scenes and below the floor).
fn squared_self_kick(collision: &Collision) -> f64 {
    if collision.outcome.is_failure() {
        return 0.0;
    }
    let kick = collision.self_kick(0.0);
    if kick.abs() <= KICK_FLOOR {
        0.0
    } else {
        kick * kick
    }
}

/// `a0 b0 a1 b1 ... b_{n-1} a_n`: the midpoints `inner` (one fewer than
/// `outer`) between the old nodes, in ascending order.
fn interleave<T>(outer: Vec<T>, inner: Vec<T>) -> Vec<T> {
    let mut merged = Vec::with_capacity(outer.len() + inner.len());
    let mut inner = inner.into_iter();
    for node in outer {
        merged.push(node);
        merged.extend(inner.next());
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::scene::Method;

    fn engine() -> EngineSettings {
        EngineSettings::new(Method::Dprkn12, 1e-12, 100_000)
    }

    /// Nodes ascend and the weights are the finest rule's: they sum to the
    /// trapezoid rule of `int dtau = 2 T sinh(S)` over the range.
    #[test]
    fn nodes_cover_the_range_in_order() {
        let launch = LaunchPair { u2: 1.1, u3: -0.9 };
        let rule = OffsetRule {
            halvings: 2,
            ..OffsetRule::default()
        };
        let integral = rule.integrate(&Potential::inverse_power(6.0), &engine(), launch, 0.5);
        let offsets: Vec<f64> = integral.nodes.iter().map(|n| n.offset).collect();
        assert!(offsets.windows(2).all(|w| w[0] < w[1]));
        let coarse = (rule.half_range / rule.coarse_step).floor() as usize;
        assert_eq!(offsets.len(), 4 * 2 * coarse + 1);
        assert_eq!(offsets.len(), rule.nodes() as usize);
        let time = launch.collision_time();
        let last = coarse as f64 * rule.coarse_step;
        let step = rule.coarse_step / 4.0;
        let exact = 2.0 * time * libm::sinh(last);
        let total: f64 = integral.nodes.iter().map(|n| n.weight).sum();
        // Trapezoid with both end nodes at full weight: its error on cosh,
        // (h^2 / 12) (f'(S) - f'(-S)), plus the end nodes' second halves.
        let expected = exact * (1.0 + step * step / 12.0) + step * time * libm::cosh(last);
        assert!(
            (total - expected).abs() < 1e-5 * exact,
            "{total} vs {expected}"
        );
    }

    /// Averaged over uniform grid coordinates, the trapezoid sum of an
    /// interval's indicator is the interval's length at every level of
    /// halving, where the fixed grid is off by half a coarse step.
    #[test]
    fn moved_grids_are_unbiased_for_jumps() {
        let rule = OffsetRule::default();
        let (low, high) = (-0.83, 1.912);
        let indicator_sum = |shift: f64, halvings: u32| {
            let coarse = rule.coarse_nodes(shift);
            let step = rule.coarse_step / f64::from(1 << halvings);
            let nodes = ((coarse.len() - 1) << halvings) + 1;
            let inside = (0..nodes)
                .map(|i| coarse[0] + i as f64 * step)
                .filter(|s| (low..high).contains(s))
                .count();
            step * inside as f64
        };
        let shifts = 10_000;
        for halvings in 0..3 {
            let mean = (0..shifts)
                .map(|k| indicator_sum((f64::from(k) + 0.5) / f64::from(shifts), halvings))
                .sum::<f64>()
                / f64::from(shifts);
            assert!((mean - (high - low)).abs() < 1e-4, "{halvings}: {mean}");
        }
        assert!((indicator_sum(0.5, 0) - (high - low)).abs() > 0.2);
    }

    /// Beyond a pair's grown range no kick leaves the kernel's centre bin: n =
    /// 4 pairs whose kicks at `|s| = 3.3` exceed `end_kick` grow, and their
    /// nodes that kick by more than `end_kick` (the only ones a bin other than
    /// the centre one sees, for bins of 2e-5 and wider) are those of a range
    /// wider by one in `s`; the self variance integrals agree within their
    /// bounds. The fixed range (no growth) misses such nodes.
    #[test]
    fn the_range_follows_the_decay_of_the_kicks() {
        let potential = Potential::inverse_power(4.0);
        let rule = OffsetRule::default();
        let wide = OffsetRule {
            half_range: rule.half_range + 1.0,
            ..rule
        };
        let fixed = OffsetRule {
            end_kick: f64::INFINITY,
            ..rule
        };
        let kicked = |integral: &OffsetIntegral| -> Vec<(f64, f64)> {
            integral
                .nodes
                .iter()
                .filter(|n| largest_kick(&n.collision) > rule.end_kick)
                .map(|n| (n.offset, n.collision.self_kick(0.0)))
                .collect()
        };
        let same = |a: &[(f64, f64)], b: &[(f64, f64)]| {
            a.len() == b.len()
                && a.iter().zip(b).all(|(x, y)| {
                    (x.0 - y.0).abs() <= 1e-12 * x.0.abs().max(1.0)
                        && (x.1 - y.1).abs() <= 1e-9 * x.1.abs().max(1e-12)
                })
        };
        let mut grown = 0;
        for (u2, u3) in [
            (0.3, -0.2),
            (1.0, -1.0),
            (0.15, 2.0),
            (0.2, 0.5),
            (2.5, -0.1),
        ] {
            let launch = LaunchPair { u2, u3 };
            let [ours, wider, old] =
                [rule, wide, fixed].map(|r| r.integrate(&potential, &engine(), launch, 0.3));
            assert!(same(&kicked(&ours), &kicked(&wider)), "({u2}, {u3})");
            assert!(
                (ours.self_variance - wider.self_variance).abs() <= ours.error + wider.error,
                "({u2}, {u3}): {} vs {}",
                ours.self_variance,
                wider.self_variance
            );
            if !same(&kicked(&old), &kicked(&wider)) {
                grown += 1;
            }
        }
        assert!(grown >= 2, "{grown} of the pairs kick beyond |s| = 3.3");
    }

    /// The integrable n = 2: every kick is zero, and so are the integral and
    /// its error bound.
    #[test]
    fn integrable_pairs_integrate_to_zero() {
        let integral = OffsetRule::default().integrate(
            &Potential::inverse_power(2.0),
            &engine(),
            LaunchPair { u2: 0.7, u3: -1.3 },
            0.5,
        );
        assert_eq!(integral.self_variance, 0.0);
        assert_eq!(integral.error, 0.0);
    }

    /// The error bound holds: a much finer rule (3 more halvings) lies within
    /// the bound of the default rule's result, for a symmetric, an asymmetric
    /// and a same-side pair.
    #[test]
    fn the_error_bound_covers_a_finer_rule() {
        let potential = Potential::inverse_power(6.0);
        for (u2, u3) in [(1.0, -1.0), (2.4, -0.3), (0.4, 1.7)] {
            let launch = LaunchPair { u2, u3 };
            let rule = OffsetRule::default();
            let fine = OffsetRule {
                halvings: rule.halvings + 3,
                ..rule
            }
            .integrate(&potential, &engine(), launch, 0.3);
            let integral = rule.integrate(&potential, &engine(), launch, 0.3);
            assert!(integral.self_variance > 0.0);
            assert!(
                (integral.self_variance - fine.self_variance).abs() <= integral.error,
                "({u2}, {u3}): {} vs {} (bound {})",
                integral.self_variance,
                fine.self_variance,
                integral.error
            );
        }
    }
}
