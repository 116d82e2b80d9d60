//! Bound pairs forming and breaking in a ring at equilibrium: the molecular
//! dynamics check of the dissociation rate `k_d` and of the three-body
//! recombination rate (`A2 + A <-> A + A + A`), in scaled units (lengths in
//! `l`, velocities in `v_th`, times in `l / v_th`, energies in `kT`).
//!
//! A neighbour pair is bound when its internal energy `w^2/4 + U(d)` is
//! negative (`w` its relative velocity, `d` the chord of its gap), the
//! definition of `K_b` and of the scene engine. In a dilute gas at
//! equilibrium, with `rho_f` free atoms and `n_b` bound pairs per `l`, mass
//! action gives `n_b = K_b rho_f^2`; pairs break at `k_d n_b rho_f v_th` and
//! form at `K_b k_d rho_f^3 v_th` per `l` (`R/3` per atom, `R = 3 K_b k_d`).
//!
//! Counting the events one by one does not work: a pair's energy is not
//! conserved while a third particle is near, and the Lennard-Jones tail
//! keeps some particle near at any density that has events (tried: event
//! counts that read a pair only where it is alone moved by 4x between
//! `rho l = 0.01` and `0.08`, exchanges `A2 + A -> A + A2` split into a
//! breakup and a formation, unread states kept stale). The number of bound
//! pairs `N_b(t)` needs no such reading: its fluctuations relax by the rate
//! equation `dn_b/dt = K_b k_d rho_f^3 - k_d n_b rho_f` linearized at total
//! number fixed (`rho_f = rho - 2 n_b`), at the rate
//!
//! `lambda = k_d (rho_f + 4 n_b)` per `l / v_th`,
//!
//! exchanges leaving `N_b` unchanged and collisions in progress adding a
//! fast part (a few `l / v_th`) that the fit skips. Its autocorrelation is
//! not one exponential: after ~0.2 / lambda the decay slows (the local rate
//! falls to ~0.7 lambda by one relaxation time at theta = 1), the memory of
//! a one-dimensional gas whose binary collisions only exchange velocities,
//! so that the atoms a pair meets are not fresh thermal draws. The rate
//! equation's `lambda`, the rate at which equilibrium pairs break, is the
//! early slope of `-ln C` (the reactive-flux plateau), which
//! [`pair_relaxation`] fits, with `n_b / rho_f^2`, `k_d` and the formation
//! rate that stationarity then requires.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rayon::prelude::*;

use super::clusters::ClusterRing;
use super::md::{MAX_DRAWS, RunError};
use super::potential::{PairPotential, Potential, PotentialVisitor, bound_weight};
use super::ring::{Reach, RingForces, thermal_start};
use crate::stats::{Estimate, jackknife};

/// One equilibrium run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KineticsSettings {
    /// Particles `N`.
    pub particles: usize,
    /// Time observed, `l / v_th`.
    pub duration: f64,
    /// Time between observations, `l / v_th`.
    pub interval: f64,
    /// Integrator tolerance.
    pub tolerance: f64,
    /// Step budget per macro step of a cluster.
    pub max_steps: u64,
}

/// Runs a ring from a thermal start (every particle from `f0`, positions
/// with weight `exp(-PE/kT)`) drawn with `seed`: its number of bound
/// neighbour pairs at the start and after every `interval` for `duration`.
pub fn equilibrium_run<P: PairPotential>(
    forces: &RingForces<P>,
    settings: &KineticsSettings,
    seed: u64,
) -> Result<Vec<u32>, RunError> {
    let mut rng = StdRng::seed_from_u64(seed);
    let (positions, velocities) =
        thermal_start(forces, settings.particles, None, &mut rng, MAX_DRAWS)?;
    let mut ring = ClusterRing::new(*forces, &positions, &velocities, settings.tolerance);
    let observations = (settings.duration / settings.interval).round() as usize;
    let mut counts = Vec::with_capacity(observations + 1);
    counts.push(ring.bound_pairs() as u32);
    for _ in 0..observations {
        ring.advance(settings.interval, settings.max_steps)?;
        counts.push(ring.bound_pairs() as u32);
    }
    if !ring.energy().is_finite() {
        return Err(RunError::NonFinite);
    }
    Ok(counts)
}

/// Runs one ring per seed of `seeds` in parallel (circumference
/// `circumference` in `l`, forces to `neighbours` on each side), in seed
/// order; `done` hears each finished run.
pub fn equilibrium_runs(
    potential: &Potential,
    circumference: f64,
    neighbours: usize,
    settings: &KineticsSettings,
    seeds: &[u64],
    done: impl Fn() + Sync,
) -> Result<Vec<Vec<u32>>, RunError> {
    potential.visit(Runs {
        circumference,
        neighbours,
        settings,
        seeds,
        done,
    })
}

struct Runs<'a, F> {
    circumference: f64,
    neighbours: usize,
    settings: &'a KineticsSettings,
    seeds: &'a [u64],
    done: F,
}

impl<F: Fn() + Sync> PotentialVisitor for Runs<'_, F> {
    type Output = Result<Vec<Vec<u32>>, RunError>;
    fn visit<P: PairPotential>(self, potential: P) -> Self::Output {
        let forces = RingForces {
            potential,
            circumference: self.circumference,
            reach: Reach::Neighbours(self.neighbours),
        };
        self.seeds
            .par_iter()
            .map(|&seed| {
                let counts = equilibrium_run(&forces, self.settings, seed);
                (self.done)();
                counts
            })
            .collect()
    }
}

/// `n_b / rho_f^2` in the exact equilibrium of a one-dimensional gas of
/// nearest-neighbour pairs at density `density` (per `l`), `l`: its gaps are
/// independent with density `exp(-U(x) - p x)` (the isobaric ensemble), the
/// pressure `p` (`kT` per `l`) set by the mean gap `1 / rho`, and a gap
/// binds with probability `erf(sqrt(-U))` (`w ~ N(0, 2)`, `w^2/4 < -U`), so
/// `n_b = rho <exp(U) bound_weight(-U)>`. Tends to `K_b` as `rho -> 0`
/// (~3% above it at `rho l = 0.02`, theta = 1): the rings' equilibrium without the dilute
/// limit's corrections, neighbours beyond the nearest and `1/N` left out.
pub fn dense_bound_length(potential: &Potential, density: f64) -> f64 {
    potential.visit(DenseBoundLength { density })
}

struct DenseBoundLength {
    density: f64,
}

impl PotentialVisitor for DenseBoundLength {
    type Output = f64;
    fn visit<P: PairPotential>(self, potential: P) -> f64 {
        const STEP: f64 = 1e-3;
        // Inside: the core, where exp(-U) < e^-40; beyond `outer`, exp(-U) = 1
        // to 1e-16 and the bound weight's x^-3 tail holds < 1e-5 of K_b.
        let mut inner = 1.0;
        while potential.energy(inner) < 40.0 {
            inner *= 0.5;
        }
        let outer = potential.range(1e-16);
        let nodes = ((outer - inner) / STEP).ceil() as usize;
        let grid: Vec<(f64, f64, f64)> = (0..=nodes)
            .map(|k| {
                let x = inner + k as f64 * STEP;
                let u = potential.energy(x);
                let bound = if u < 0.0 { bound_weight(-u) } else { 0.0 };
                (x, libm::exp(-u), bound)
            })
            .collect();
        // Sums over the grid with weight exp(-p x) (trapezoid), closed beyond
        // `outer` by the free gas's exact integrals.
        let moments = |pressure: f64| {
            let (mut zero, mut first, mut bound) = (0.0, 0.0, 0.0);
            for (k, &(x, weight, b)) in grid.iter().enumerate() {
                let edge = if k == 0 || k == nodes { 0.5 } else { 1.0 };
                let decay = edge * STEP * libm::exp(-pressure * x);
                zero += weight * decay;
                first += x * weight * decay;
                bound += b * decay;
            }
            let tail = libm::exp(-pressure * outer) / pressure;
            (zero + tail, first + tail * (outer + 1.0 / pressure), bound)
        };
        let mean_gap = |pressure: f64| {
            let (zero, first, _) = moments(pressure);
            first / zero
        };
        // The mean gap falls as the pressure rises: bisection in ln p.
        let (mut low, mut high) = (libm::log(1e-9), libm::log(1e3));
        for _ in 0..100 {
            let mid = 0.5 * (low + high);
            if mean_gap(libm::exp(mid)) > 1.0 / self.density {
                low = mid;
            } else {
                high = mid;
            }
        }
        let (zero, _, bound) = moments(libm::exp(0.5 * (low + high)));
        let pairs = self.density * bound / zero;
        let free = self.density - 2.0 * pairs;
        pairs / (free * free)
    }
}

/// The ring and the fit of its bound-pair relaxation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelaxationSettings {
    /// Particles `N`.
    pub particles: usize,
    /// Circumference, `l`.
    pub circumference: f64,
    /// Time between observations, `l / v_th`.
    pub interval: f64,
    /// The fit of `ln C(tau)` starts at this lag (past the collisions in
    /// progress), `l / v_th`.
    pub fit_from: f64,
    /// The fit ends where `C` first falls below this.
    pub fit_down_to: f64,
}

/// What equilibrium rings measured of their bound pairs (jackknife errors
/// over rings).
#[derive(Clone, Debug, PartialEq)]
pub struct PairRelaxation {
    /// Free atoms per `l`, `rho_f = (N - 2 <N_b>) / C`.
    pub free_density: Estimate,
    /// Bound pairs per `l`, `n_b = <N_b> / C`.
    pub bound_density: Estimate,
    /// `n_b / rho_f^2`: the equilibrium constant `K_b`, `l`.
    pub bound_length: Estimate,
    /// Relaxation rate `lambda` of the fluctuations of `N_b`, `v_th / l`.
    pub relaxation_rate: Estimate,
    /// `lambda / (rho_f + 4 n_b)`: the dissociation rate `k_d`, `l`.
    pub dissociation: Estimate,
    /// Formations per `l` and time over `rho_f^3 v_th` (stationarity:
    /// `k_d n_b / rho_f^2`), `l^2`.
    pub formation: Estimate,
    /// The lags fitted, `l / v_th`.
    pub fitted_lags: [f64; 2],
    /// The local rate `ln(C(a) / C(b)) / (b - a)` between successive lags
    /// of [`LOCAL_RATE_LAGS`] (within half a run): how the decay slows.
    pub local_rates: Vec<([f64; 2], Estimate)>,
}

/// Lags (`l / v_th`) between which [`PairRelaxation::local_rates`] are measured.
pub const LOCAL_RATE_LAGS: [f64; 8] = [10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0];

/// [`PairRelaxation`] of `runs` (bound-pair counts every `interval`; at
/// least two runs), `None` when `C` falls below `fit_down_to` within two
/// lags of `fit_from` or not within half a run. The autocorrelation `C(tau)` of `N_b` pools every ring
/// around the mean of all of them (a ring's own mean would bias `C` low by
/// `~2 / (lambda T)`); `lambda` is the least-squares slope of `-ln C` over
/// the lags from `fit_from` to where `C` first falls below `fit_down_to`,
/// the same lags for every jackknife replicate.
pub fn pair_relaxation(runs: &[Vec<u32>], settings: &RelaxationSettings) -> Option<PairRelaxation> {
    let full: Vec<&[u32]> = runs.iter().map(Vec::as_slice).collect();
    let first = (settings.fit_from / settings.interval).ceil() as usize;
    let fluctuations = Fluctuations::new(&full);
    let last = (first..fluctuations.longest_lag)
        .find(|&lag| fluctuations.correlation(lag) < settings.fit_down_to)
        .filter(|&lag| lag >= first + 2)?;
    let local_lags: Vec<usize> = LOCAL_RATE_LAGS
        .iter()
        .map(|lag| (lag / settings.interval).round() as usize)
        .filter(|&lag| lag < fluctuations.longest_lag)
        .collect();
    let measure = |runs: &[&[u32]]| {
        let fluctuations = Fluctuations::new(runs);
        let lags: Vec<f64> = (first..last)
            .map(|k| k as f64 * settings.interval)
            .collect();
        let logs: Vec<f64> = (first..last)
            .map(|lag| -libm::log(fluctuations.correlation(lag)))
            .collect();
        let rate = slope(&lags, &logs);
        let bound = fluctuations.mean / settings.circumference;
        let free = settings.particles as f64 / settings.circumference - 2.0 * bound;
        let dissociation = rate / (free + 4.0 * bound);
        let mut values = vec![
            free,
            bound,
            bound / (free * free),
            rate,
            dissociation,
            dissociation * bound / (free * free),
        ];
        values.extend(local_lags.windows(2).map(|pair| {
            let ratio = fluctuations.correlation(pair[0]) / fluctuations.correlation(pair[1]);
            libm::log(ratio) / ((pair[1] - pair[0]) as f64 * settings.interval)
        }));
        values
    };
    let leave_one_out: Vec<Vec<f64>> = (0..full.len())
        .map(|r| {
            let rest: Vec<&[u32]> = full
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != r)
                .map(|(_, run)| *run)
                .collect();
            measure(&rest)
        })
        .collect();
    let e = jackknife(&measure(&full), &leave_one_out);
    Some(PairRelaxation {
        free_density: e[0],
        bound_density: e[1],
        bound_length: e[2],
        relaxation_rate: e[3],
        dissociation: e[4],
        formation: e[5],
        fitted_lags: [first, last - 1].map(|k| k as f64 * settings.interval),
        local_rates: local_lags
            .windows(2)
            .zip(&e[6..])
            .map(|(pair, &rate)| {
                (
                    [pair[0], pair[1]].map(|k| k as f64 * settings.interval),
                    rate,
                )
            })
            .collect(),
    })
}

/// The bound-pair counts of several runs as deviations from the mean over
/// all of them, pooled.
struct Fluctuations {
    /// Mean count over every run and observation.
    mean: f64,
    /// Each run's deviations from `mean`.
    deviations: Vec<Vec<f64>>,
    /// Variance of the pooled deviations.
    variance: f64,
    /// Lags below half the shortest run.
    longest_lag: usize,
}

impl Fluctuations {
    fn new(runs: &[&[u32]]) -> Fluctuations {
        let samples: usize = runs.iter().map(|r| r.len()).sum();
        let mean = runs
            .iter()
            .flat_map(|r| r.iter())
            .map(|&c| f64::from(c))
            .sum::<f64>()
            / samples as f64;
        let deviations = runs
            .iter()
            .map(|r| r.iter().map(|&c| f64::from(c) - mean).collect())
            .collect();
        let mut fluctuations = Fluctuations {
            mean,
            deviations,
            variance: 1.0,
            longest_lag: runs.iter().map(|r| r.len()).min().unwrap_or(0) / 2,
        };
        fluctuations.variance = fluctuations.covariance(0);
        fluctuations
    }

    /// Pooled autocovariance at `lag` (observations).
    fn covariance(&self, lag: usize) -> f64 {
        let (mut sum, mut pairs) = (0.0, 0usize);
        for d in self.deviations.iter().filter(|d| d.len() > lag) {
            sum += d[..d.len() - lag]
                .iter()
                .zip(&d[lag..])
                .map(|(a, b)| a * b)
                .sum::<f64>();
            pairs += d.len() - lag;
        }
        sum / pairs as f64
    }

    /// Normalized autocorrelation `C` at `lag` (observations).
    fn correlation(&self, lag: usize) -> f64 {
        self.covariance(lag) / self.variance
    }
}

/// Least-squares slope of `y` against `x`.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    #[test]
    fn the_dense_bound_length_tends_to_k_b() {
        let potential = Potential::lennard_jones(1.0);
        let k_b = potential.family().bound_pair_length();
        let dilute = dense_bound_length(&potential, 1e-5);
        assert!((dilute / k_b - 1.0).abs() < 1e-4, "{dilute} vs {k_b}");
        // Denser gases bind more per rho_f^2 (the pressure presses gaps shut).
        let dense = dense_bound_length(&potential, 0.02);
        assert!(dense > 1.02 * k_b && dense < 1.05 * k_b, "{dense} vs {k_b}");
    }

    /// A two-state count flipping at rates `up` and `down` per step relaxes
    /// at `up + down`: the fit finds it.
    #[test]
    fn relaxation_rate_of_a_telegraph_count() {
        let (up, down) = (0.004, 0.006);
        let runs: Vec<Vec<u32>> = (0..16)
            .map(|seed| {
                let mut rng = StdRng::seed_from_u64(seed);
                let mut state = 0_u32;
                (0..20_000)
                    .map(|_| {
                        let flip = if state == 0 { up } else { down };
                        if rng.random::<f64>() < flip {
                            state = 1 - state;
                        }
                        state
                    })
                    .collect()
            })
            .collect();
        let settings = RelaxationSettings {
            particles: 10,
            circumference: 1000.0,
            interval: 1.0,
            fit_from: 10.0,
            fit_down_to: 0.25,
        };
        let relaxation = pair_relaxation(&runs, &settings).unwrap();
        let rate = relaxation.relaxation_rate;
        // Discrete steps: C(k) = (1 - up - down)^k exactly.
        let exact = -libm::log(1.0 - up - down);
        assert!(
            (rate.mean - exact).abs() < 3.0 * rate.stderr,
            "{rate:?} vs {exact}"
        );
        assert!(rate.stderr < 0.1 * exact, "{rate:?}");
        // Mean occupation up / (up + down) = 0.4 pairs on 1000 l.
        let bound = relaxation.bound_density;
        assert!((bound.mean - 4e-4).abs() < 3.0 * bound.stderr, "{bound:?}");
    }
}
