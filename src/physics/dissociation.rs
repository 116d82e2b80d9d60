//! Collision-induced dissociation `A2 + A -> A + A + A`: a bound pair of a
//! dilute thermal gas hit by a thermal atom (the inverse of three-body
//! recombination; scaled units of physics.md §1).
//!
//! The gas's bound pairs are in equilibrium: gap `x` and gap rate `w` with
//! density `exp(-(w^2/4 + U(x)))` on `w^2/4 + U(x) < 0`, whose integral over
//! `w` is the integrand `exp(-U) erf(sqrt(-U))` of the bound-pair length
//! `K_b` ([`super::potential::Family::bound_pair_length`]; the ring MD's
//! thermal start draws the same density). An atom meets a pair at relative
//! velocity `s` (atom against the pair's centre of mass, `s ~ N(0, 3/2)`
//! for masses 1 and 2) with rate `rho |s|`, from either side; the mirror
//! image of an atom from the left is an atom from the right hitting a pair
//! of the same gap and gap rate, so both sides break pairs alike and the
//! atoms here come from the right with the flux-weighted speed
//! `|s| = sqrt(3/2) R`, `R` Rayleigh. A pair breaks at the rate
//! `rho v_th k_d` per pair with
//!
//! `k_d = <|s|> P(three free atoms leave) = sqrt(3/pi) P`,
//!
//! in the dilute limit. Detailed balance ties it to the recombination rate
//! `R_rec rho^2 l v_th` per atom (three atoms take part in each event):
//! `rho R_rec rho^2 l v_th / 3 = (K_b rho^2) (rho v_th k_d)`, i.e.
//! `3 K_b k_d = R_rec l`.

use super::launch::{thermal_density, thermal_launch_speed};
use rayon::prelude::*;

use super::potential::{PairPotential, Potential, PotentialVisitor, bound_weight};
use super::quasi_random::{ScrambledSobol, standard_normal_cdf, standard_normal_quantile};
use super::scene::{Collision, EngineSettings, Outcome, SceneState, collide_all_from};

/// Cells of the bound-gap proposal on the unit interval of `t` (gap
/// `x = x0 / (1 - t^2)`, `U(x0) = 0`).
const PROPOSAL_CELLS: usize = 2048;

/// `<|s|>` of the relative velocity `s ~ N(0, 3/2)` of an atom and a pair's
/// centre of mass, both sides together: `sqrt(3/pi)` (`v_th`).
pub fn meeting_speed() -> f64 {
    (3.0 / std::f64::consts::PI).sqrt()
}

/// The equilibrium density of bound pairs of a potential with a well, and a
/// proposal for drawing their gaps: piecewise constant in `t` on
/// `PROPOSAL_CELLS` cells, each cell's mass the density at its midpoint.
/// Draws carry the weight `density / proposal`, so averages are exact
/// whatever the proposal's shape.
pub struct BoundPairs<P> {
    potential: P,
    /// The separation where `U` changes sign, `l`.
    zero: f64,
    /// Cumulative proposal mass at the cells' right edges, ending at 1.
    cumulative: Vec<f64>,
}

/// One bound pair drawn from [`BoundPairs`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundPair {
    /// Gap, `l`.
    pub gap: f64,
    /// Gap rate `w`, `v_th`.
    pub rate: f64,
    /// Internal energy `w^2/4 + U(gap) < 0`, `kT`.
    pub internal_energy: f64,
    /// Importance weight: the equilibrium density over the normalized
    /// proposal density (its mean over draws is `K_b`, in `l`).
    pub weight: f64,
}

impl<P: PairPotential> BoundPairs<P> {
    /// The bound pairs of `potential`, `None` without a well.
    pub fn new(potential: P) -> Option<BoundPairs<P>> {
        if potential.well_depth() <= 0.0 {
            return None;
        }
        let zero = sign_change(|x| potential.energy(x), 1.0)?;
        let mut pairs = BoundPairs {
            potential,
            zero,
            cumulative: Vec::with_capacity(PROPOSAL_CELLS),
        };
        let width = 1.0 / PROPOSAL_CELLS as f64;
        let mut total = 0.0;
        for k in 0..PROPOSAL_CELLS {
            total += pairs.gap_density((k as f64 + 0.5) * width);
            pairs.cumulative.push(total);
        }
        for mass in &mut pairs.cumulative {
            *mass /= total;
        }
        Some(pairs)
    }

    /// Gap `x0 / (1 - t^2)` at `t` in `[0, 1)`.
    fn gap(&self, t: f64) -> f64 {
        self.zero / (1.0 - t * t)
    }

    /// Equilibrium density of bound gaps in `t`: `exp(-U) erf(sqrt(-U)) dx/dt`,
    /// `dx/dt = 2 t x0 / (1 - t^2)^2` (the integrand of `K_b`).
    fn gap_density(&self, t: f64) -> f64 {
        let binding = -self.potential.energy(self.gap(t));
        if binding <= 0.0 || t >= 1.0 {
            return 0.0;
        }
        let stretch = 1.0 - t * t;
        bound_weight(binding) * 2.0 * t * self.zero / (stretch * stretch)
    }

    /// The pair at uniform coordinates `(gap, rate)` in `(0, 1)`: `t` from the
    /// proposal, then `w / sqrt 2` standard normal truncated to
    /// `|w| < 2 sqrt(-U)` by its inverse distribution function.
    pub fn draw(&self, [gap_coordinate, rate_coordinate]: [f64; 2]) -> BoundPair {
        let cell = self
            .cumulative
            .partition_point(|&mass| mass < gap_coordinate)
            .min(PROPOSAL_CELLS - 1);
        let below = if cell == 0 {
            0.0
        } else {
            self.cumulative[cell - 1]
        };
        let mass = self.cumulative[cell] - below;
        let width = 1.0 / PROPOSAL_CELLS as f64;
        let t = (cell as f64 + ((gap_coordinate - below) / mass).clamp(0.0, 1.0)) * width;
        let gap = self.gap(t);
        let energy = self.potential.energy(gap);
        let rate = bound_rate(-energy, rate_coordinate);
        BoundPair {
            gap,
            rate,
            internal_energy: 0.25 * rate * rate + energy,
            weight: self.gap_density(t) * width / mass,
        }
    }

    /// The outer turning point of a pair at internal energy `energy < 0`
    /// that is now at `gap`: the first separation beyond it where `U = energy`.
    fn outer_turning_point(&self, gap: f64, energy: f64) -> f64 {
        let above = |x: f64| self.potential.energy(x) - energy;
        let mut high = 2.0 * gap;
        while above(high) <= 0.0 {
            high *= 2.0;
        }
        bisect(above, gap, high)
    }

    /// The scene of `pair` hit by an atom from the right at relative speed
    /// `speed` (`v_th`), the atom where neither pair member is felt above
    /// the engine's tail level `epsilon` (`|U| <= epsilon speed^2` at the
    /// pair's widest), total momentum zero.
    pub fn hit(&self, pair: &BoundPair, speed: f64, epsilon: f64) -> SceneState {
        let reach = self.outer_turning_point(pair.gap, pair.internal_energy);
        let distance = 0.5 * reach + self.potential.range(epsilon * speed * speed);
        SceneState {
            gaps: [pair.gap, distance - 0.5 * pair.gap],
            rates: [pair.rate, -speed - 0.5 * pair.rate],
            centre: 0.0,
        }
    }
}

/// Gap rate `w = sqrt 2 z` with `z` standard normal truncated to
/// `|z| < c = sqrt(2 B)` (`B` the binding `-U`, so that `w^2/4 < B`), from a
/// uniform coordinate: the lower half of the coordinate maps to `z < 0`,
/// the upper half mirrored to `z > 0`, so both tails use the lower-tail
/// quantile.
fn bound_rate(binding: f64, coordinate: f64) -> f64 {
    let cut = (2.0 * binding).sqrt();
    let tail = standard_normal_cdf(-cut);
    let (side, folded) = if coordinate < 0.5 {
        (-1.0, 2.0 * coordinate)
    } else {
        (1.0, 2.0 * (1.0 - coordinate))
    };
    let z = standard_normal_quantile(tail + folded * (0.5 - tail));
    -side * z * std::f64::consts::SQRT_2
}

/// The flux-weighted relative speed `|s|` of an atom meeting a pair from a
/// uniform coordinate: `sqrt(3/2)` times a Rayleigh deviate.
pub fn meeting_speed_draw(coordinate: f64) -> f64 {
    1.5_f64.sqrt() * thermal_launch_speed(coordinate)
}

/// A separation where `f` changes sign from positive (inside) to negative
/// (outside), searched outward and inward from `start`; `None` if `f` keeps
/// one sign.
fn sign_change(f: impl Fn(f64) -> f64, start: f64) -> Option<f64> {
    let (mut low, mut high) = (start, start);
    for _ in 0..200 {
        if f(low) > 0.0 && f(high) < 0.0 {
            return Some(bisect(|x| -f(x), low, high));
        }
        if f(low) <= 0.0 {
            low *= 0.5;
        }
        if f(high) >= 0.0 {
            high *= 2.0;
        }
    }
    None
}

/// Root of `f` on `[low, high]` with `f(low) <= 0 < f(high)`, to the last bit.
fn bisect(f: impl Fn(f64) -> f64, mut low: f64, mut high: f64) -> f64 {
    loop {
        let mid = 0.5 * (low + high);
        if mid <= low || mid >= high {
            return high;
        }
        if f(mid) <= 0.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
}

/// Whether a scene that began as a bound pair and an atom ended with three
/// free atoms (`None` for a failed scene).
pub fn dissociated(collision: &Collision) -> Option<bool> {
    match collision.outcome {
        Outcome::Scattered => Some(true),
        Outcome::Recombined => Some(false),
        _ => None,
    }
}

/// Per randomization, `k_d` (`rho v_th` per pair): `sqrt(3/pi)` times the
/// weighted share of scenes that dissociated, failed scenes left out.
pub fn dissociation_rate(hits: &[(BoundPair, Collision)]) -> f64 {
    let (mut broken, mut total) = (0.0, 0.0);
    for (pair, collision) in hits {
        if let Some(broke) = dissociated(collision) {
            total += pair.weight;
            if broke {
                broken += pair.weight;
            }
        }
    }
    meeting_speed() * broken / total
}

/// Per randomization, the recombination rate `R(u')` (`rho^2 l v_th` per
/// atom at `u'`) that detailed balance predicts at each of `u_primes`:
/// time reversal and the mirror turn an atom at `u'` taking part in a
/// recombination into an atom leaving a dissociation at `u'`, so
///
/// `f0(u') R(u') = K_b k_d <sum_i N(u'; v_i, 1/3)>_dissociating`,
///
/// `v_i` the three outgoing velocities in the centre-of-mass frame (the
/// scenes start at total momentum zero), each with its mirror image `-v_i`
/// at half weight (the atoms here all come from the right; those from the
/// left are the mirror images, whose outgoing velocities are reversed), and
/// `N(.; v, 1/3)` the normal
/// density of the centre-of-mass velocity `C ~ N(0, 1/3)` of a pair and an
/// atom that meet (independent of their relative velocity under the flux
/// weighting), integrated out exactly. Its thermal average is `3 K_b k_d`.
/// `bound_length` is `K_b` in `l`.
pub fn balanced_recombination(
    hits: &[(BoundPair, Collision)],
    bound_length: f64,
    u_primes: &[f64],
) -> Vec<f64> {
    let mut sums = vec![0.0; u_primes.len()];
    let mut total = 0.0;
    for (pair, collision) in hits {
        let Some(broke) = dissociated(collision) else {
            continue;
        };
        total += pair.weight;
        if !broke {
            continue;
        }
        for (sum, &u) in sums.iter_mut().zip(u_primes) {
            *sum += pair.weight
                * collision
                    .outgoing
                    .iter()
                    .map(|&v| 0.5 * (centre_density(u - v) + centre_density(u + v)))
                    .sum::<f64>();
        }
    }
    sums.iter()
        .zip(u_primes)
        .map(|(sum, &u)| bound_length * meeting_speed() * sum / total / thermal_density(u))
        .collect()
}

/// Density of the centre-of-mass velocity `C ~ N(0, 1/3)` of three unit
/// masses at `c`.
fn centre_density(c: f64) -> f64 {
    let variance = 1.0 / 3.0;
    libm::exp(-0.5 * c * c / variance) / (2.0 * std::f64::consts::PI * variance).sqrt()
}

/// The scenes of randomization `randomization` of the scrambled Sobol' net
/// of `points` points seeded `seed` ([`dissociation_scenes`]).
pub fn sobol_dissociation_scenes(
    potential: &Potential,
    settings: &EngineSettings,
    (seed, randomization, points): (u64, u32, u32),
    done: impl Fn() + Sync,
) -> Option<Vec<(BoundPair, Collision)>> {
    let sobol = ScrambledSobol::new(seed, u64::from(randomization));
    let points: Vec<[f64; 3]> = (0..points).map(|k| sobol.point(k)).collect();
    dissociation_scenes(potential, settings, &points, done)
}

/// The scenes of one randomization, one per uniform point `(gap, rate,
/// speed)`, in the order of `points` (`None` without a well). Scenes run in
/// parallel; `done` hears each finished one.
pub fn dissociation_scenes(
    potential: &Potential,
    settings: &EngineSettings,
    points: &[[f64; 3]],
    done: impl Fn() + Sync,
) -> Option<Vec<(BoundPair, Collision)>> {
    potential.visit(Scenes {
        settings,
        points,
        done,
    })
}

/// Scenes integrated together in one task ([`collide_all_from`] interleaves them): enough to
/// keep its lanes full, few enough to share the scenes of a randomization among the threads.
const SCENES_PER_TASK: usize = 16;

struct Scenes<'a, F> {
    settings: &'a EngineSettings,
    points: &'a [[f64; 3]],
    done: F,
}

impl<F: Fn() + Sync> PotentialVisitor for Scenes<'_, F> {
    type Output = Option<Vec<(BoundPair, Collision)>>;
    fn visit<P: PairPotential>(self, potential: P) -> Self::Output {
        let pairs = BoundPairs::new(potential)?;
        let epsilon = self.settings.tail_level();
        let scenes = self
            .points
            .par_chunks(SCENES_PER_TASK)
            .flat_map_iter(|chunk| {
                let (pairs, states): (Vec<BoundPair>, Vec<SceneState>) = chunk
                    .iter()
                    .map(|point| {
                        let pair = pairs.draw([point[0], point[1]]);
                        let state = pairs.hit(&pair, meeting_speed_draw(point[2]), epsilon);
                        (pair, state)
                    })
                    .unzip();
                let collisions = collide_all_from(potential, self.settings, &states);
                chunk.iter().for_each(|_| (self.done)());
                pairs.into_iter().zip(collisions)
            })
            .collect();
        Some(scenes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::potential::{Family, LennardJones};
    use crate::physics::quasi_random::ScrambledSobol;

    /// The gap rate's inverse distribution function is exact: the truncated
    /// normal's distribution function at the returned `w` gives back the
    /// coordinate, and `w^2/4` stays below the binding.
    #[test]
    fn bound_rates_invert_the_truncated_normal() {
        for binding in [1e-4_f64, 0.3, 2.0, 9.0] {
            let cut = (2.0 * binding).sqrt();
            let tail = standard_normal_cdf(-cut);
            for coordinate in [1e-9, 0.1, 0.4999, 0.5, 0.77, 1.0 - 1e-9] {
                let w = bound_rate(binding, coordinate);
                assert!(0.25 * w * w < binding, "{binding} {coordinate}: {w}");
                let z = w / std::f64::consts::SQRT_2;
                let cdf = (standard_normal_cdf(z) - tail) / (1.0 - 2.0 * tail);
                assert!(
                    (cdf - coordinate).abs() < 1e-9,
                    "{binding} {coordinate}: {cdf}"
                );
            }
        }
    }

    /// Weighted draws follow the equilibrium gap density: the weighted share
    /// of gaps below `x` equals `int_x0^x exp(-U) erf(sqrt(-U)) dx / K_b`
    /// (midpoint quadrature in `t`), within the statistical error of the
    /// draws, and the weights (density over the normalized proposal)
    /// average to `K_b`.
    #[test]
    fn bound_pairs_follow_the_equilibrium_density() {
        for theta in [0.1, 1.0, 10.0] {
            let potential = LennardJones::new(theta).unwrap();
            let pairs = BoundPairs::new(potential).unwrap();
            let bound_length = potential.bound_pair_length();
            let sobol = ScrambledSobol::new(3, 0);
            let draws: Vec<BoundPair> = (0..1 << 14)
                .map(|k| {
                    let p = sobol.point(k);
                    pairs.draw([p[0], p[1]])
                })
                .collect();
            assert!(draws.iter().all(|d| d.internal_energy < 0.0));
            let total: f64 = draws.iter().map(|d| d.weight).sum();
            let cells = 200_000;
            let step = 1.0 / f64::from(cells);
            let density = |k: u32| pairs.gap_density((f64::from(k) + 0.5) * step) * step;
            let quadrature: f64 = (0..cells).map(density).sum();
            assert!((quadrature / bound_length - 1.0).abs() < 1e-6, "{theta}");
            // Density over a normalized proposal: the weights average to K_b.
            let mean_weight = total / draws.len() as f64;
            assert!(
                (mean_weight / bound_length - 1.0).abs() < 1e-3,
                "{theta}: {mean_weight}"
            );
            for share in [0.1, 0.5, 0.9] {
                let t = share;
                let below: f64 = (0..(share * f64::from(cells)) as u32).map(density).sum();
                let expected = below / quadrature;
                let drawn: f64 = draws
                    .iter()
                    .filter(|d| d.gap < pairs.gap(t))
                    .map(|d| d.weight)
                    .sum::<f64>()
                    / total;
                // Binomial error of 2^14 draws: at most 0.004.
                assert!(
                    (drawn - expected).abs() < 0.016,
                    "{theta} {t}: {drawn} {expected}"
                );
            }
        }
    }

    /// No well, no bound pairs.
    #[test]
    fn repulsive_potentials_have_no_bound_pairs() {
        use crate::physics::potential::InverseIntegerPower;
        assert!(BoundPairs::new(InverseIntegerPower::<6>).is_none());
    }
}
