//! Molecular dynamics of `N` particles on a ring (physics.md §7) in scaled
//! units: arc positions in `l`, velocities in `v_th`, time in `l / v_th`,
//! energies in `kT`, circumference `C = 2 pi R / l`.
//!
//! Pairs interact through the chord distance `d = (C/pi) sin(pi s / C)` of
//! their arc separation `s`, so the force on the trailing particle of a pair
//! is `-f(d) cos(pi s / C)` and on the leading one its opposite
//! (`f = -dU/dd`, physics.md §7): momentum is conserved pair by pair.
//! Particles keep their order, so the state is the `N` gaps `g_k = s_(k+1) - s_k`
//! (the last one wraps around) and their rates `w_k = u_(k+1) - u_k`, with the
//! total momentum kept aside: relative coordinates stay accurate however
//! large the ring (numerics.md), and momentum is conserved exactly.
//! This module integrates the whole ring on one adaptive step (DPRKN12, the
//! step set by the fastest pair anywhere).

use std::convert::Infallible;
use std::f64::consts::PI;

use rand::RngExt;
use rand_distr::StandardNormal;

use super::potential::PairPotential;
use crate::integrate::{
    Acceleration, AfterStep, Dprkn12, Drive, Ending, ErrorScales, Span, Vector, drive,
};
use crate::linalg::{EigenError, symmetric_eigen};

/// Which pairs interact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Every pair (the long-ranged `n = 2` Sutherland ring).
    All,
    /// Each particle with its `k` nearest neighbours on each side (`2k < N`);
    /// physics.md §7 found `k = 3` converged.
    Neighbours(usize),
}

/// The forces of a ring: potential, circumference and reach.
#[derive(Clone, Copy, Debug)]
pub struct RingForces<P> {
    /// Pair potential of the chord distance.
    pub potential: P,
    /// Circumference `C`, in `l`.
    pub circumference: f64,
    /// Which pairs interact.
    pub reach: Reach,
}

/// Below this half-angle (radians) [`half_angle`] sums Taylor series: the
/// first terms left out are below 3e-19 of the result.
const SMALL_HALF_ANGLE: f64 = 1.0 / 16.0;

/// `(sin x, cos x)` of the half-angle `x = pi s / C` a pair subtends. Pairs
/// inside a collision are a few `l` apart on rings of `C ~ 1e4 .. 3e5 l`
/// (`x ~ 1e-4`), where libm's general `sin` and `cos` took a third of the
/// molecular dynamics' time (docs/benchmarks.md): there the series through
/// `x^9` and `x^8`, exact to rounding; elsewhere libm.
#[inline]
fn half_angle(x: f64) -> (f64, f64) {
    if x.abs() >= SMALL_HALF_ANGLE {
        return libm::sincos(x);
    }
    // Taylor coefficients: (-1)^k / (2k + 1)! and (-1)^k / (2k)!.
    const SINE: [f64; 4] = [-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362_880.0];
    const COSINE: [f64; 4] = [-0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40_320.0];
    let x2 = x * x;
    let horner = |c: [f64; 4]| c[0] + x2 * (c[1] + x2 * (c[2] + x2 * c[3]));
    (x + x * x2 * horner(SINE), 1.0 + x2 * horner(COSINE))
}

impl<P: PairPotential> RingForces<P> {
    /// Chord distance of arc separation `arc` (`0 < arc < C`), in `l`.
    pub fn chord(&self, arc: f64) -> f64 {
        let (sine, _) = half_angle(arc * (PI / self.circumference));
        self.circumference / PI * sine
    }

    /// The arc separation (`l`) below which pairs are closer than the chord
    /// `chord`: `(C/pi) asin(pi chord / C)`; unbounded when every chord is shorter.
    pub fn arc_within(&self, chord: f64) -> f64 {
        let sine = PI * chord / self.circumference;
        if sine >= 1.0 {
            f64::INFINITY
        } else {
            self.circumference / PI * libm::asin(sine)
        }
    }

    /// Force along the ring that the leading particle of a pair `arc` apart
    /// exerts on the trailing one, negated: `f(d) cos(pi s / C)` with `d` the
    /// chord (`kT / l`).
    #[inline]
    pub fn push(&self, arc: f64) -> f64 {
        let (sine, cosine) = half_angle(arc * (PI / self.circumference));
        self.potential.force(self.circumference / PI * sine) * cosine
    }

    /// Calls `visit(i, j, arc)` for every interacting pair, `j` ahead of `i`
    /// by `arc` along the ring.
    fn for_each_pair(&self, gaps: &[f64], mut visit: impl FnMut(usize, usize, f64)) {
        let n = gaps.len();
        match self.reach {
            Reach::All => {
                for i in 0..n {
                    let mut arc = 0.0;
                    for j in i + 1..n {
                        arc += gaps[j - 1];
                        visit(i, j, arc);
                    }
                }
            }
            Reach::Neighbours(k) => {
                // Each pair once: at most (N - 1) / 2 neighbours on a side.
                let k = k.min((n - 1) / 2);
                for i in 0..n {
                    let mut arc = 0.0;
                    for m in 1..=k {
                        arc += gaps[(i + m - 1) % n];
                        visit(i, (i + m) % n, arc);
                    }
                }
            }
        }
    }

    /// Particle accelerations (unit masses) at the given gaps.
    pub fn particle_accelerations(&self, gaps: &[f64]) -> Vec<f64> {
        let mut accelerations = vec![0.0; gaps.len()];
        self.for_each_pair(gaps, |i, j, arc| {
            let push = self.push(arc);
            accelerations[i] -= push;
            accelerations[j] += push;
        });
        accelerations
    }

    /// Energy `sum_j U(d_kj)` of particle `k` with its interaction partners, `kT`.
    pub fn particle_energy(&self, gaps: &[f64], k: usize) -> f64 {
        let n = gaps.len();
        let (ahead, behind) = match self.reach {
            // Ahead around the whole ring: every other particle once.
            Reach::All => (n - 1, 0),
            Reach::Neighbours(reach) => {
                let reach = reach.min((n - 1) / 2);
                (reach, reach)
            }
        };
        let mut energy = 0.0;
        let mut arc = 0.0;
        for m in 0..ahead {
            arc += gaps[(k + m) % n];
            energy += self.potential.energy(self.chord(arc));
        }
        arc = 0.0;
        for m in 1..=behind {
            arc += gaps[(k + n - m) % n];
            energy += self.potential.energy(self.chord(arc));
        }
        energy
    }

    /// Potential energy `sum U(d)` over the interacting pairs, `kT`.
    pub fn potential_energy(&self, gaps: &[f64]) -> f64 {
        let mut energy = 0.0;
        self.for_each_pair(gaps, |_, _, arc| {
            energy += self.potential.energy(self.chord(arc));
        });
        energy
    }
}

impl<P: PairPotential> Acceleration<Vec<f64>> for RingForces<P> {
    /// Gap accelerations `a_(k+1) - a_k`.
    fn acceleration(&self, gaps: &Vec<f64>) -> Vec<f64> {
        let a = self.particle_accelerations(gaps);
        let n = a.len();
        (0..n).map(|k| a[(k + 1) % n] - a[k]).collect()
    }
}

/// The state of a ring: gaps, their rates and the total momentum.
#[derive(Clone, Debug, PartialEq)]
pub struct RingState {
    /// `g_k = s_(k+1) - s_k`, the last wrapping around; all positive, summing to `C`.
    pub gaps: Vec<f64>,
    /// `w_k = u_(k+1) - u_k`.
    pub rates: Vec<f64>,
    /// Total momentum `sum u_k` (unit masses), `v_th`.
    pub momentum: f64,
}

impl RingState {
    /// The state of particles at arc positions `positions` (ascending, within
    /// one circumference `circumference`) with velocities `velocities`.
    pub fn new(positions: &[f64], velocities: &[f64], circumference: f64) -> RingState {
        let n = positions.len();
        let gaps = gaps_of(positions, circumference);
        let rates = (0..n)
            .map(|k| velocities[(k + 1) % n] - velocities[k])
            .collect();
        RingState {
            gaps,
            rates,
            momentum: velocities.iter().sum(),
        }
    }

    /// Particle velocities: `u_k = u_0 + sum_(j<k) w_j`, with `u_0` fixed by the momentum.
    pub fn velocities(&self) -> Vec<f64> {
        ring_velocities(&self.rates, self.momentum)
    }

    /// Arc positions with particle 0 at 0.
    pub fn positions(&self) -> Vec<f64> {
        positions_of(&self.gaps)
    }

    /// Total energy `sum u^2/2 + sum U`, `kT`.
    pub fn energy<P: PairPotential>(&self, forces: &RingForces<P>) -> f64 {
        let kinetic: f64 = self.velocities().iter().map(|u| 0.5 * u * u).sum();
        kinetic + forces.potential_energy(&self.gaps)
    }

    /// The same positions with every velocity reversed.
    pub fn reversed(&self) -> RingState {
        RingState {
            gaps: self.gaps.clone(),
            rates: self.rates.iter().map(|w| -w).collect(),
            momentum: -self.momentum,
        }
    }

    /// Eigenvalues (ascending) of the Sutherland Lax matrix
    /// `L = diag(u) + i (pi/C) cot(pi (s_j - s_k)/C)`: conserved when the pair
    /// potential is the chord `d^-2` acting between all pairs (numerics.md).
    /// Computed from the real symmetric form `[[A, -B], [B, A]]` of `A + iB`,
    /// whose spectrum is `L`'s twice over. An error if the state is not
    /// finite or the diagonalization does not converge.
    pub fn sutherland_invariants(&self, circumference: f64) -> Result<Vec<f64>, EigenError> {
        let (u, s) = (self.velocities(), self.positions());
        let n = u.len();
        let m = 2 * n;
        let mut real = vec![0.0; m * m];
        for j in 0..n {
            real[j * m + j] = u[j];
            real[(j + n) * m + j + n] = u[j];
            for k in 0..n {
                if j != k {
                    let b = PI / circumference / libm::tan(PI * (s[j] - s[k]) / circumference);
                    real[j * m + k + n] = -b;
                    real[(j + n) * m + k] = b;
                }
            }
        }
        let mut values = symmetric_eigen(&real, m)?.values;
        values.sort_by(f64::total_cmp);
        Ok(values.into_iter().step_by(2).collect())
    }
}

/// Why no initial state could be drawn.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "no configuration accepted in {0} draws: the ring is too crowded for exp(-PE/kT) rejection"
)]
pub struct CrowdedRing(pub u32);

/// Initial state of physics.md §7: velocities from `f0` except particle 0 at
/// `u_prime` (or all thermal when `u_prime` is `None`), positions with weight
/// `exp(-PE/kT)`. Purely repulsive potentials (`PE >= 0`): uniform positions
/// accepted with probability `exp(-PE/kT)`, an exact independent draw (at
/// most `max_draws` tries). Potentials with a well (`PE` unbounded below in
/// the number of bound pairs, so no rejection bound): uniform positions
/// relaxed by [`WELL_SWEEPS`] Metropolis sweeps ([`metropolis_sweep`]); the
/// uniform start already has the ideal gas's long-wavelength statistics, the
/// sweeps equilibrate the local structure (cores, bound pairs).
/// Positions ascending from 0.
pub fn thermal_start<P: PairPotential, R: RngExt>(
    forces: &RingForces<P>,
    particles: usize,
    u_prime: Option<f64>,
    rng: &mut R,
    max_draws: u32,
) -> Result<(Vec<f64>, Vec<f64>), CrowdedRing> {
    let circumference = forces.circumference;
    let velocities: Vec<f64> = (0..particles)
        .map(|k| match (k, u_prime) {
            (0, Some(u)) => u,
            _ => rng.sample(StandardNormal),
        })
        .collect();
    let uniform_positions = |rng: &mut R| {
        let mut positions: Vec<f64> = (0..particles)
            .map(|_| circumference * rng.random::<f64>())
            .collect();
        positions.sort_by(f64::total_cmp);
        let origin = positions[0];
        positions.iter_mut().for_each(|s| *s -= origin);
        positions
    };
    if forces.potential.well_depth() > 0.0 {
        let mut gaps = gaps_of(&uniform_positions(rng), circumference);
        for _ in 0..WELL_SWEEPS {
            metropolis_sweep(forces, &mut gaps, rng);
        }
        return Ok((positions_of(&gaps), velocities));
    }
    for _ in 0..max_draws {
        let positions = uniform_positions(rng);
        let gaps = gaps_of(&positions, circumference);
        if rng.random::<f64>() < libm::exp(-forces.potential_energy(&gaps)) {
            return Ok((positions, velocities));
        }
    }
    Err(CrowdedRing(max_draws))
}

/// Metropolis sweeps that equilibrate the positions of a ring whose potential
/// has a well. A bound pair lives ~`exp(D/kT)` sweeps (`D` the well depth:
/// ~12 at `kT = eps/10`), so 200 sweeps relax the bound-pair population many
/// times over (checked against the dilute-limit count in the tests).
pub const WELL_SWEEPS: usize = 200;

/// One Metropolis sweep over the particles of a ring, in order: particle `k`
/// moves to a uniform point between its two neighbours (a symmetric proposal
/// that keeps the order: `g_(k-1) + g_k` is fixed), accepted with probability
/// `min(1, exp(-dPE/kT))`. Only the pairs that contain `k` change.
pub fn metropolis_sweep<P: PairPotential, R: RngExt>(
    forces: &RingForces<P>,
    gaps: &mut [f64],
    rng: &mut R,
) {
    let n = gaps.len();
    for k in 0..n {
        let behind = (k + n - 1) % n;
        let span = gaps[behind] + gaps[k];
        let before = (gaps[behind], forces.particle_energy(gaps, k));
        gaps[behind] = span * rng.random::<f64>();
        gaps[k] = span - gaps[behind];
        let change = forces.particle_energy(gaps, k) - before.1;
        // A NaN change (both energies infinite: overlapping cores) rejects.
        let accepted = rng.random::<f64>() < libm::exp(-change);
        if !accepted {
            gaps[behind] = before.0;
            gaps[k] = span - before.0;
        }
    }
}

/// Neighbour pairs that are bound: internal energy `w^2/4 + U(d)` below zero
/// (`w` the pair's relative velocity; the pair alone, other neighbours
/// ignored, as in the scene engine's recombination test).
pub fn bound_pairs<P: PairPotential>(
    forces: &RingForces<P>,
    gaps: &[f64],
    velocities: &[f64],
) -> usize {
    let n = gaps.len();
    (0..n)
        .filter(|&k| {
            let w = velocities[(k + 1) % n] - velocities[k];
            0.25 * w * w + forces.potential.energy(forces.chord(gaps[k])) < 0.0
        })
        .count()
}

/// Gaps `g_k = s_(k+1) - s_k` of ascending arc positions, the last wrapping
/// around the circumference.
pub fn gaps_of(positions: &[f64], circumference: f64) -> Vec<f64> {
    let n = positions.len();
    (0..n)
        .map(|k| {
            if k + 1 < n {
                positions[k + 1] - positions[k]
            } else {
                positions[0] + circumference - positions[k]
            }
        })
        .collect()
}

/// Arc positions of a ring's particles from its gaps, particle 0 at 0.
pub fn positions_of(gaps: &[f64]) -> Vec<f64> {
    let mut positions = Vec::with_capacity(gaps.len());
    let mut sum = 0.0;
    for gap in gaps {
        positions.push(sum);
        sum += gap;
    }
    positions
}

/// Particle velocities of a whole ring from its gap rates `w_k = u_(k+1) - u_k`
/// (the last one wrapping) and total momentum: `u_k = u_0 + sum_(j<k) w_j`,
/// with `u_0` fixed by the momentum.
pub fn ring_velocities(rates: &[f64], momentum: f64) -> Vec<f64> {
    let n = rates.len();
    let mut offsets = Vec::with_capacity(n);
    let mut sum = 0.0;
    for rate in rates {
        offsets.push(sum);
        sum += rate;
    }
    let first = (momentum - offsets.iter().sum::<f64>()) / n as f64;
    offsets.iter().map(|o| first + o).collect()
}

/// Work done by [`evolve`] and [`advance`].
pub use crate::integrate::Work as RingWork;

/// Why an evolution stopped early.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum RingError {
    /// The step budget ran out.
    #[error("step budget of {0} exhausted")]
    StepBudget(u64),
    /// The step size collapsed (a singular approach).
    #[error("step size collapsed")]
    Breakdown,
}

/// Advances `state` by `duration` with DPRKN12 on one adaptive step for the
/// whole ring: the local error per step at most `tolerance` relative to each
/// gap and to `v_th` for the rates.
pub fn evolve<P: PairPotential>(
    forces: &RingForces<P>,
    state: &mut RingState,
    duration: f64,
    tolerance: f64,
    max_steps: u64,
) -> Result<RingWork, RingError> {
    advance(
        forces,
        &mut state.gaps,
        &mut state.rates,
        duration,
        tolerance,
        max_steps,
        |_, _| (),
    )
}

/// Advances gaps and gap rates under `forces` by `duration` on adaptive
/// DPRKN12 steps (the whole ring, or one cluster of it) with the [`drive`]r:
/// the step is a controlled fraction of the fastest gap's time scale, never
/// lets an approaching gap close by more than half, and ends exactly at
/// `duration`. `on_step(gaps, rates)` sees the state after every accepted step.
pub fn advance<V: Vector, A: Acceleration<V>>(
    forces: &A,
    gaps: &mut V,
    rates: &mut V,
    duration: f64,
    tolerance: f64,
    max_steps: u64,
    mut on_step: impl FnMut(&[f64], &[f64]),
) -> Result<RingWork, RingError> {
    let mut rate_scale = gaps.zeros_like();
    rate_scale
        .components_mut()
        .iter_mut()
        .for_each(|s| *s = tolerance);
    let scales = RingErrorScales {
        tolerance,
        rate_scale,
    };
    let span = Span {
        duration,
        max_attempts: max_steps,
    };
    let Drive { ending, work } =
        drive::<Dprkn12, _, _, _>(forces, &scales, gaps, rates, span, |gaps, rates, _| {
            on_step(gaps.components(), rates.components());
            AfterStep::<Infallible>::Continue
        });
    match ending {
        Ending::Elapsed => Ok(work),
        Ending::Stopped(never) => match never {},
        Ending::BudgetExhausted => Err(RingError::StepBudget(max_steps)),
        Ending::Collapse => Err(RingError::Breakdown),
    }
}

/// A ring's error scales: each gap to `tolerance` relative to itself, each
/// rate to `tolerance` in `v_th`.
struct RingErrorScales<V> {
    tolerance: f64,
    rate_scale: V,
}

impl<V: Vector> ErrorScales<V> for RingErrorScales<V> {
    fn gap_scale(&self, gaps: &V) -> V {
        let mut scale = gaps.clone();
        scale
            .components_mut()
            .iter_mut()
            .for_each(|s| *s *= self.tolerance);
        scale
    }

    fn rate_scale(&self) -> &V {
        &self.rate_scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::potential::{Family, InverseIntegerPower, LennardJones, Morse};
    use crate::stats::Estimate;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// The half-angle series agree with libm's `sin` and `cos` to two units
    /// in the last place from 1e-12 up to the switch at 1/16.
    #[test]
    fn half_angle_series_match_libm() {
        let ulps = |a: f64, b: f64| (a - b).abs() / (b.abs() * f64::EPSILON);
        for k in 0..4000 {
            let x = 1e-12 * libm::pow(SMALL_HALF_ANGLE / 1e-12, f64::from(k) / 4000.0);
            for x in [x, -x] {
                let (sine, cosine) = half_angle(x);
                assert!(ulps(sine, libm::sin(x)) <= 2.0, "sin {x:e}: {sine:e}");
                assert!(ulps(cosine, libm::cos(x)) <= 2.0, "cos {x:e}: {cosine:e}");
            }
        }
    }

    /// Thermal starts of a ring with a well of 2.5 kT bind the fraction
    /// `rho K_b` of their gaps that the dilute limit predicts (Metropolis
    /// sampling against a closed-form integral), within four standard errors
    /// (~13% with 1600 starts at 0.2 bound pairs a start); the correction of
    /// order `rho K_b` (a particle bound to one neighbour is not free to bind
    /// the other) must stay far below them, so `density` keeps `rho K_b`
    /// under 2% (at `rho K_b = 9%` a Morse ring binds 11% fewer pairs).
    fn binds_the_dilute_limit_fraction<P: PairPotential + Family>(potential: P, density: f64) {
        assert!(density * potential.bound_pair_length() < 0.02);
        let particles = 40;
        let circumference = (particles - 1) as f64 / density;
        let forces = RingForces {
            potential,
            circumference,
            reach: Reach::Neighbours(3),
        };
        let mut rng = StdRng::seed_from_u64(5);
        let counts: Vec<f64> = (0..1600)
            .map(|_| {
                let (positions, velocities) =
                    thermal_start(&forces, particles, None, &mut rng, 1).unwrap();
                let state = RingState::new(&positions, &velocities, circumference);
                bound_pairs(&forces, &state.gaps, &velocities) as f64
            })
            .collect();
        let Estimate {
            mean,
            stderr: error,
        } = Estimate::from_replicates(&counts);
        let expected = particles as f64 * density * potential.bound_pair_length();
        assert!(
            (mean - expected).abs() < 4.0 * error,
            "{}: {mean} +- {error} bound pairs per start, dilute limit {expected}",
            potential.id()
        );
    }

    /// Lennard-Jones at kT = eps/10 and Morse at kT = 0.4 eps (both a well
    /// of 2.5 kT).
    #[test]
    fn thermal_start_binds_the_dilute_limit_fraction_of_pairs() {
        binds_the_dilute_limit_fraction(LennardJones { theta: 0.1 }, 0.005);
        let morse = Morse {
            theta: 0.4,
            x0: 4.0,
        };
        binds_the_dilute_limit_fraction(morse, 0.001);
    }

    /// Six particles on a ring of 30 l (dense: many collisions), fixed
    /// velocities of thermal size with a net momentum.
    fn dense_ring() -> (Vec<f64>, Vec<f64>, f64) {
        let positions = vec![0.0, 4.1, 9.3, 15.2, 19.8, 25.5];
        let velocities = vec![1.3, -0.7, 0.4, -1.9, 0.8, 0.35];
        (positions, velocities, 30.0)
    }

    /// Energy is conserved to the integrator's tolerance over many collisions,
    /// momentum exactly, and the order of the particles is kept.
    #[test]
    fn energy_and_momentum_are_conserved() {
        let (positions, velocities, circumference) = dense_ring();
        let forces = RingForces {
            potential: InverseIntegerPower::<6>,
            circumference,
            reach: Reach::Neighbours(2),
        };
        let mut state = RingState::new(&positions, &velocities, circumference);
        let (energy, momentum) = (state.energy(&forces), state.momentum);
        let work = evolve(&forces, &mut state, 200.0, 1e-12, 1_000_000).unwrap();
        let drift = (state.energy(&forces) - energy).abs() / energy;
        assert!(drift < 1e-10, "relative energy drift {drift:e} ({work:?})");
        let total: f64 = state.velocities().iter().sum();
        assert!((total - momentum).abs() < 1e-12, "{total} vs {momentum}");
        let circumference_now: f64 = state.gaps.iter().sum();
        assert!((circumference_now - circumference).abs() < 1e-9);
        assert!(
            work.steps > 1000,
            "too few collisions to test anything: {work:?}"
        );
    }

    /// Reversing the velocities and evolving as long again returns to the start.
    #[test]
    fn evolution_is_time_reversible() {
        let (positions, velocities, circumference) = dense_ring();
        let forces = RingForces {
            potential: InverseIntegerPower::<6>,
            circumference,
            reach: Reach::Neighbours(2),
        };
        let start = RingState::new(&positions, &velocities, circumference);
        let mut state = start.clone();
        evolve(&forces, &mut state, 50.0, 1e-13, 1_000_000).unwrap();
        let mut back = state.reversed();
        evolve(&forces, &mut back, 50.0, 1e-13, 1_000_000).unwrap();
        let back = back.reversed();
        for (a, b) in back.gaps.iter().zip(&start.gaps) {
            assert!((a - b).abs() < 1e-8, "{a} vs {b}");
        }
        for (a, b) in back.velocities().iter().zip(start.velocities()) {
            assert!((a - b).abs() < 1e-8, "{a} vs {b}");
        }
    }

    /// The n = 2 chord ring is Sutherland's integrable model: the Lax
    /// eigenvalues stay put through many collisions.
    #[test]
    fn sutherland_invariants_are_conserved() {
        let (positions, velocities, circumference) = dense_ring();
        let forces = RingForces {
            potential: InverseIntegerPower::<2>,
            circumference,
            reach: Reach::All,
        };
        let mut state = RingState::new(&positions, &velocities, circumference);
        let before = state.sutherland_invariants(circumference).unwrap();
        let energy = state.energy(&forces);
        evolve(&forces, &mut state, 100.0, 1e-12, 1_000_000).unwrap();
        let after = state.sutherland_invariants(circumference).unwrap();
        for (a, b) in before.iter().zip(&after) {
            assert!((a - b).abs() < 1e-9, "{before:?} vs {after:?}");
        }
        // Sum of eigenvalues = trace L = momentum; sum of squares = trace L^2
        // = sum u^2 + sum_(j != k) (pi/C)^2 cot^2 = 2 E - (pi/C)^2 N (N - 1).
        let n = positions.len() as f64;
        let trace_square = 2.0 * energy - (PI / circumference).powi(2) * n * (n - 1.0);
        let sum_squares: f64 = before.iter().map(|l| l * l).sum();
        assert!(
            (sum_squares - trace_square).abs() < 1e-10 * energy,
            "{sum_squares} vs {trace_square}"
        );
        assert!((before.iter().sum::<f64>() - state.momentum).abs() < 1e-12);
    }
}
