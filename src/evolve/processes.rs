//! The three processes of the grid evolution (physics.md §4) from the
//! per-randomization kernel generators ([`operator::kernel_generators`]), with
//! jackknife errors: the full linearized operator, projected onto detailed
//! balance, the collision invariants `1, u, u^2` and dissipation
//! ([`Dissipative`]); the special particle alone (`tagged`, a Markov
//! generator); and the Fokker-Planck equation of the tagged drift and
//! variance rates. Also what the projection does to `h_full`
//! ([`ProjectionEffect`]). Not the generators' estimate (`operator`) nor the
//! tables (`stages::evolve`). Units: rates in `rho^2 l v_th`, times in
//! `1 / (rho^2 l v_th)`, `h` as node masses.
//!
//! [`operator::kernel_generators`]: super::operator::kernel_generators

use super::grid::VelocityGrid;
use super::operator::{Generators, tagged_fokker_planck};
use super::propagate::Generator;
use super::spectral::Dissipative;
use crate::linalg::EigenError;
use crate::stats::{Estimate, Replicated, replicate_means};

/// One evolved process from `delta(u - u')`.
pub struct Process {
    /// Node masses at every time, on all randomizations and with each left out.
    pub states: Replicated<Vec<Vec<f64>>>,
    /// The equilibrium it relaxes to (node masses).
    pub equilibrium: Vec<f64>,
    /// For the projected full generator: the largest positive eigenvalue
    /// removed and the raw estimate's detailed-balance violation
    /// (`Dissipative::largest_clipped`, `Dissipative::asymmetry`).
    pub diagnostics: Option<[Estimate; 2]>,
}

/// What projecting the full operator's estimate does to `h_full`, for the
/// full and every leave-one-out estimate (node masses).
pub struct ProjectionEffect {
    /// `h(t) - h_unclipped(t)` per time (`Dissipative::clipping_change`).
    pub clipping: Replicated<Vec<Vec<f64>>>,
    /// The part of `h` frozen in the clipped modes (`Dissipative::clipped_part`).
    pub clipped: Replicated<Vec<f64>>,
    /// `h(t) - exp(t M) h(0)` per time, `M` the raw estimate.
    pub projection: Replicated<Vec<Vec<f64>>>,
}

/// The grid evolution: the processes full, tagged and Fokker-Planck, in
/// this order, and the projection's effect on the full one.
pub struct GridEvolution {
    /// Full, tagged, Fokker-Planck.
    pub processes: [Process; 3],
    /// What the projection does to the full process's `h`.
    pub effect: ProjectionEffect,
}

/// The collision invariants `1, u, u^2` at the nodes.
pub fn collision_invariants(grid: &VelocityGrid) -> [Vec<f64>; 3] {
    let velocities = grid.velocities();
    [
        vec![1.0; grid.len()],
        velocities.clone(),
        velocities.iter().map(|u| u * u).collect(),
    ]
}

/// `a - b` entry by entry, per time.
fn difference(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p - q).collect())
        .collect()
}

impl GridEvolution {
    /// The three processes from `delta(u - u')` at node `start` (`u'` =
    /// `u_prime`, exactly as given) at every time of `times` (ascending),
    /// from the generators of every randomization; an error when a full
    /// generator's estimate cannot be projected ([`Dissipative::project`]).
    pub fn new(
        generators: &[Generators],
        grid: &VelocityGrid,
        start: usize,
        u_prime: f64,
        times: &[f64],
    ) -> Result<GridEvolution, EigenError> {
        let pick = |part: fn(&Generators) -> &Generator| -> Vec<Generator> {
            generators.iter().map(|g| part(g).clone()).collect()
        };
        let raw = replicate_means(&pick(|g| &g.full));
        let tagged = replicate_means(&pick(|g| &g.tagged));
        let diffusion = tagged.map(|m| tagged_fokker_planck(m, grid));
        let maxwellian = grid.maxwellian();
        let invariants = collision_invariants(grid);
        let full = raw
            .map(|m| Dissipative::project(m, &maxwellian, &invariants))
            .transpose()?;
        let mut h0 = vec![0.0; grid.len()];
        h0[start] = 1.0;
        let full_states = full.map(|m| m.propagate(&h0, times));
        let effect = ProjectionEffect {
            clipping: full.map(|m| m.clipping_change(&h0, times)),
            clipped: full.map(|m| m.clipped_part(&h0)),
            projection: full_states.zip(&raw.map(|m| m.propagate(&h0, times)), |h, raw| {
                difference(h, raw)
            }),
        };
        let diagnostics = [
            full.scalar(|d| d.largest_clipped),
            full.scalar(|d| d.asymmetry),
        ];
        let processes = [
            Process {
                states: full_states,
                equilibrium: grid.conserving_equilibrium(u_prime),
                diagnostics: Some(diagnostics),
            },
            Process {
                states: tagged.map(|m| m.propagate(&h0, times)),
                equilibrium: maxwellian.clone(),
                diagnostics: None,
            },
            Process {
                states: diffusion.map(|m| m.propagate(&h0, times)),
                equilibrium: maxwellian,
                diagnostics: None,
            },
        ];
        Ok(GridEvolution { processes, effect })
    }
}

/// The moments of one process's `h` at one time (jackknife estimates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProcessMoments {
    /// `sum_i h_i`.
    pub number: Estimate,
    /// `sum_i h_i u_i`, `v_th`.
    pub momentum: Estimate,
    /// `sum_i h_i u_i^2`, `v_th^2`.
    pub second_moment: Estimate,
    /// `sum_i h_i (u_i - u')^2`, `v_th^2`.
    pub variance: Estimate,
    /// The same within `|u_i - u'| <= reach`.
    pub window_variance: Estimate,
    /// `sum_i |h_i - h_eq,i|`: the L1 distance to the equilibrium.
    pub distance: Estimate,
    /// `sum_i (h_i - h_eq,i)^2 / (2 f0_i)`: the linearized relative entropy
    /// to the equilibrium (`H[f0 + df] - H[f0]` to second order in `df`),
    /// which the H-theorem makes non-increasing.
    pub entropy: Estimate,
}

impl Process {
    /// The moments of `h` at time index `k` on `grid`, the variances about
    /// `u_prime` (all nodes and within `reach` of it).
    pub fn moments(
        &self,
        grid: &VelocityGrid,
        k: usize,
        u_prime: f64,
        reach: f64,
    ) -> ProcessMoments {
        let all = |h: &[f64]| grid.moments(h, 0.0, f64::INFINITY);
        let estimate = |f: &dyn Fn(&[f64]) -> f64| self.states.estimate(k, f);
        ProcessMoments {
            number: estimate(&|h| all(h)[0]),
            momentum: estimate(&|h| all(h)[1]),
            second_moment: estimate(&|h| all(h)[2]),
            variance: estimate(&|h| grid.moments(h, u_prime, f64::INFINITY)[2]),
            window_variance: estimate(&|h| grid.moments(h, u_prime, reach)[2]),
            distance: estimate(&|h| {
                h.iter()
                    .zip(&self.equilibrium)
                    .map(|(a, b)| (a - b).abs())
                    .sum()
            }),
            entropy: estimate(&|h| self.entropy(grid, h)),
        }
    }

    /// `sum_i (h_i - h_eq,i)^2 / (2 f0_i)` of the node masses `h`.
    fn entropy(&self, grid: &VelocityGrid, h: &[f64]) -> f64 {
        let f0 = grid.maxwellian();
        (0..h.len())
            .map(|i| 0.5 * (h[i] - self.equilibrium[i]).powi(2) / f0[i])
            .sum()
    }

    /// The entropy's decay rate between time indices `k - 1` and `k`, `dt`
    /// apart: `-(ln S_k - ln S_(k-1)) / (2 dt)` (jackknife). A single mode
    /// `exp(-r t)` gives `r`; late in the relaxation, the slowest mode the
    /// start excites.
    pub fn entropy_decay(&self, grid: &VelocityGrid, k: usize, dt: f64) -> Estimate {
        self.states.scalar(|states| {
            let [before, after] = [k - 1, k].map(|j| self.entropy(grid, &states[j]));
            -(libm::log(after) - libm::log(before)) / (2.0 * dt)
        })
    }
}

/// The size of the projection's effect on `h_full` at one time (node
/// masses), against `h_full`'s statistical error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionSizes {
    /// L1 size of the clipping's change (jackknife).
    pub clipping: Estimate,
    /// L1 size of the weight frozen in the clipped modes (jackknife).
    pub clipped: Estimate,
    /// Number, momentum and second moment of the clipping's change (0 to
    /// rounding).
    pub moments: [Estimate; 3],
    /// L1 size of the whole projection's change (jackknife).
    pub projection: Estimate,
    /// `sum_i sigma_i`: the L1 size of `h_full`'s statistical error
    /// (jackknife `sigma_i` of node `i`'s mass).
    pub error: f64,
    /// The largest clipping change, clipped weight and projection change
    /// over the full and leave-one-out estimates, over `error` (`None`
    /// where the ratio is not finite: at `t = 0`, where `h` is exact and
    /// `error` zero or of rounding size). Below 1: the projection moves `h`
    /// by less than its error in every replicate.
    pub over_error: [Option<f64>; 3],
}

/// `sum_i |x_i|`.
fn l1(x: &[f64]) -> f64 {
    x.iter().map(|v| v.abs()).sum()
}

/// `estimate`, or NaN (null in the table: overflow) where a replicate's
/// unprojected evolution left the floating-point range: a noise mode
/// growing as `exp(lambda t)` with `lambda t > 709` makes the change infinite.
fn unless_overflowed(estimate: Estimate) -> Estimate {
    if estimate.mean.is_finite() && estimate.stderr.is_finite() {
        estimate
    } else {
        Estimate {
            mean: f64::NAN,
            stderr: f64::NAN,
        }
    }
}

impl ProjectionEffect {
    /// The sizes at time index `k`, `states` those of `h_full`.
    pub fn sizes(
        &self,
        grid: &VelocityGrid,
        states: &Replicated<Vec<Vec<f64>>>,
        k: usize,
    ) -> ProjectionSizes {
        let error: f64 = states.states(k).iter().map(|e| e.stderr).sum();
        let moment = |p: usize| {
            unless_overflowed(
                self.clipping
                    .estimate(k, |d| grid.moments(d, 0.0, f64::INFINITY)[p]),
            )
        };
        ProjectionSizes {
            clipping: unless_overflowed(self.clipping.estimate(k, l1)),
            clipped: self.clipped.scalar(|part| l1(part)),
            moments: [0, 1, 2].map(moment),
            projection: unless_overflowed(self.projection.estimate(k, l1)),
            error,
            over_error: [
                self.clipping.largest(|d| l1(&d[k])),
                self.clipped.largest(|part| l1(part)),
                self.projection.largest(|d| l1(&d[k])),
            ]
            .map(|change| Some(change / error).filter(|ratio| ratio.is_finite())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A Markov generator of jumps to the nodes up to `reach` away, each
    /// at a random rate in `[0, rate)`, its columns summing to zero: it keeps
    /// number, neither momentum nor energy, and is not in detailed balance.
    fn random_jumps(grid: &VelocityGrid, reach: usize, rate: f64, rng: &mut StdRng) -> Generator {
        let n = grid.len();
        let columns: Vec<Vec<f64>> = (0..n)
            .map(|j| {
                let mut column = vec![0.0; n];
                for i in j.saturating_sub(reach)..(j + reach + 1).min(n) {
                    if i != j {
                        column[i] = rate * rng.random::<f64>();
                        column[j] -= column[i];
                    }
                }
                column
            })
            .collect();
        Generator::from_columns(&columns)
    }

    /// Four randomizations of random jumps: two nodes far for the full
    /// estimate, one for the tagged one.
    fn noisy_generators(grid: &VelocityGrid) -> Vec<Generators> {
        let mut rng = StdRng::seed_from_u64(33);
        (0..4)
            .map(|_| Generators {
                full: random_jumps(grid, 2, 1.0, &mut rng),
                tagged: random_jumps(grid, 1, 0.5, &mut rng),
            })
            .collect()
    }

    /// Every member's states, the full and the leave-one-out ones.
    fn members(states: &Replicated<Vec<Vec<f64>>>) -> impl Iterator<Item = &Vec<f64>> {
        std::iter::once(&states.full)
            .chain(&states.leave_one_out)
            .flatten()
    }

    /// The output times.
    const TIMES: [f64; 4] = [0.0, 0.3, 4.0, 60.0];
    /// The start `u'`, a node of the test grid.
    const U_PRIME: f64 = 0.6;

    /// The grid evolution of the noisy generators from `delta(u - U_PRIME)`.
    fn evolution(grid: &VelocityGrid) -> GridEvolution {
        let start = grid.node_of(U_PRIME).unwrap();
        GridEvolution::new(&noisy_generators(grid), grid, start, U_PRIME, &TIMES).unwrap()
    }

    /// The projected full operator conserves number, momentum and energy
    /// whatever its estimate: `1, u, u^2` are left null vectors, so every
    /// member's `h(t)` keeps the moments `1, u', u'^2` of `delta(u - u')`,
    /// and the clipping changes none of them. The estimate had growing modes
    /// (clipped), so the projection did work. Rounding: the moment `p` is
    /// `p^T D^(1/2) V g(t) V^T D^(-1/2) h0`, and the eigenvectors `V` are
    /// orthogonal to the invariant directions `D^(1/2) p` to `n EPSILON`
    /// (Jacobi), so its error is below `n EPSILON ||D^(1/2) p||_1 / sqrt(f0_start)`;
    /// for the clipping change `D^(1/2) sum_k w_k v_k` over at most `n`
    /// clipped modes, below `n EPSILON ||D^(1/2) p||_2 sum_k |w_k|`, and
    /// `sum_k |w_k| <= sqrt(n) ||D^(-1/2) change||_2`.
    #[test]
    fn the_projected_full_process_conserves_number_momentum_and_energy() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let n = grid.len() as f64;
        let evolution = evolution(&grid);
        let [full, ..] = &evolution.processes;
        let [clipped, _] = full.diagnostics.unwrap();
        assert!(clipped.mean > 0.0, "{clipped:?}");
        let root: Vec<f64> = grid.maxwellian().iter().map(|f| f.sqrt()).collect();
        let start = grid.node_of(U_PRIME).unwrap();
        let rounding: Vec<f64> = collision_invariants(&grid)
            .iter()
            .map(|p| {
                let weight: f64 = p.iter().zip(&root).map(|(p, r)| (p * r).abs()).sum();
                n * f64::EPSILON * weight / root[start]
            })
            .collect();
        let delta = [1.0, U_PRIME, U_PRIME * U_PRIME];
        for h in members(&full.states) {
            let m = grid.moments(h, 0.0, f64::INFINITY);
            for p in 0..3 {
                assert!((m[p] - delta[p]).abs() < rounding[p], "{m:?} {rounding:?}");
            }
        }
        let invariants = collision_invariants(&grid);
        let mut largest_change: f64 = 0.0;
        for d in members(&evolution.effect.clipping) {
            let m = grid.moments(d, 0.0, f64::INFINITY);
            let modes = norm_2(d.iter().zip(&root).map(|(d, r)| d / r));
            largest_change = largest_change.max(modes);
            for (p, invariant) in invariants.iter().enumerate() {
                let direction = norm_2(invariant.iter().zip(&root).map(|(p, r)| p * r));
                let rounding = n * n.sqrt() * f64::EPSILON * direction * modes;
                assert!(m[p].abs() <= rounding, "{m:?}: {p} {rounding}");
            }
        }
        assert!(largest_change > 0.0);
    }

    /// `sqrt(sum x^2)`.
    fn norm_2(x: impl Iterator<Item = f64>) -> f64 {
        x.map(|x| x * x).sum::<f64>().sqrt()
    }

    /// Conserving number, momentum and energy, the full process keeps the
    /// variance about `u'`, `m2 - 2 u' m1 + u'^2 m0`, at that of
    /// `delta(u - u')`: zero; not within a window, where `h` is not
    /// conserved. At `t = 0` its distance to equilibrium is that of the
    /// delta, `sum_i |delta_i - h_eq,i|`. Rounding: the three moments'
    /// bounds (above) weighted by `1, 2 |u'|, u'^2` stay below
    /// `2 n EPSILON sum_i (1 + u_i^2) sqrt(f0_i) / sqrt(f0_start)` at
    /// `u' = 0.6`, and the jackknife error of four members below `2 sqrt(3)`
    /// times that: 8 covers both.
    #[test]
    fn the_full_process_keeps_zero_variance_about_u_prime() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let evolution = evolution(&grid);
        let full = &evolution.processes[0];
        let start = grid.node_of(U_PRIME).unwrap();
        let root: Vec<f64> = grid.maxwellian().iter().map(|f| f.sqrt()).collect();
        let scale: f64 = grid
            .velocities()
            .iter()
            .zip(&root)
            .map(|(u, r)| (1.0 + u * u) * r)
            .sum::<f64>()
            / root[start];
        let rounding = 8.0 * grid.len() as f64 * f64::EPSILON * scale;
        for k in 0..TIMES.len() {
            let moments = full.moments(&grid, k, U_PRIME, 1.0);
            let variance = moments.variance;
            assert!(variance.mean.abs() < rounding, "{k}: {moments:?}");
            assert!(variance.stderr < rounding, "{k}: {moments:?}");
        }
        let mut delta = vec![0.0; grid.len()];
        delta[start] = 1.0;
        let distance: f64 = delta
            .iter()
            .zip(&full.equilibrium)
            .map(|(a, b)| (a - b).abs())
            .sum();
        let at_start = full.moments(&grid, 0, U_PRIME, 1.0).distance.mean;
        assert!(
            (at_start - distance).abs() < rounding,
            "{at_start} vs {distance}"
        );
    }

    /// At `t = 0` the clipping has changed nothing (its modes' gain
    /// `1 - exp(lambda t)` vanishes exactly), later it has (the estimate had
    /// growing modes), and the clipped weight is the same at every time.
    #[test]
    fn the_clipping_starts_at_zero_and_grows() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let evolution = evolution(&grid);
        let states = &evolution.processes[0].states;
        let sizes: Vec<ProjectionSizes> = (0..TIMES.len())
            .map(|k| evolution.effect.sizes(&grid, states, k))
            .collect();
        assert_eq!(sizes[0].clipping.mean, 0.0);
        assert_eq!(sizes[0].clipping.stderr, 0.0);
        assert!(sizes[TIMES.len() - 1].clipping.mean > 0.0);
        assert!(sizes.iter().all(|s| s.clipped == sizes[0].clipped));
        assert!(sizes[0].clipped.mean > 0.0);
    }

    /// The tagged and Fokker-Planck generators are Markov generators (their
    /// columns sum to zero): every member's `h(t)` keeps number 1. Rounding:
    /// scaling and squaring amplifies a product's rounding (`n EPSILON`) by
    /// `~4 ||M||_1 t`; `||M||_1 <= 4 x 0.5` for the tagged jumps and, with
    /// the same first two moments on three nodes, for Fokker-Planck.
    #[test]
    fn the_tagged_and_fokker_planck_processes_conserve_probability() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let evolution = evolution(&grid);
        let n = grid.len() as f64;
        for process in &evolution.processes[1..] {
            for (h, t) in members(&process.states).zip(TIMES.iter().cycle()) {
                let rounding = n * f64::EPSILON * (1.0 + 4.0 * 2.0 * t);
                let number: f64 = h.iter().sum();
                assert!((number - 1.0).abs() < rounding, "t {t}: {number}");
            }
        }
    }
}
