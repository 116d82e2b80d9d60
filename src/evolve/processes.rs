//! The three processes of the grid evolution (physics.md §4) from the
//! per-randomization generators of the Dirichlet form
//! ([`operator::balanced_generators`]), with jackknife errors: the full
//! linearized operator, the special particle alone (`tagged`), and the
//! Fokker-Planck equation of the tagged variance rate in detailed-balance
//! form ([`operator::tagged_fokker_planck`]). Each generator is symmetric
//! under `f0^(-1/2) . f0^(1/2)` and negative semi-definite by construction,
//! with its invariants exact (`1, u, u^2` for full, number for the others);
//! each is propagated through its eigen-decomposition ([`Dissipative`]),
//! whose diagnostics (a positive eigenvalue, an asymmetry) then measure
//! rounding alone. So every process relaxes to its equilibrium with a
//! relative entropy that cannot rise. Not the generators' estimate
//! (`operator`) nor the tables (`stages::evolve`). Units: rates in
//! `rho^2 l v_th`, times in `1 / (rho^2 l v_th)`, `h` as node masses.
//!
//! [`operator::balanced_generators`]: super::operator::balanced_generators
//! [`operator::tagged_fokker_planck`]: super::operator::tagged_fokker_planck

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
    /// The largest positive eigenvalue set to zero and the detailed-balance
    /// violation of `S` (`Dissipative::largest_clipped`,
    /// `Dissipative::asymmetry`): rounding, for generators of the Dirichlet
    /// form.
    pub diagnostics: [Estimate; 2],
}

/// The grid evolution: the processes full, tagged and Fokker-Planck, in
/// this order.
pub struct GridEvolution {
    /// Full, tagged, Fokker-Planck.
    pub processes: [Process; 3],
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

/// The equilibrium of a process that conserves number alone: `f0` on the
/// grid, normalized to the number 1 of `delta(u - u')`.
fn number_equilibrium(grid: &VelocityGrid) -> Vec<f64> {
    let f0 = grid.maxwellian();
    let number: f64 = f0.iter().sum();
    f0.iter().map(|f| f / number).collect()
}

impl GridEvolution {
    /// The three processes from `delta(u - u')` at node `start` (`u'` =
    /// `u_prime`, exactly as given) at every time of `times` (ascending),
    /// from the generators of every randomization; an error when a
    /// generator's estimate cannot be diagonalized ([`Dissipative::project`]).
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
        let full = replicate_means(&pick(|g| &g.full));
        let tagged = replicate_means(&pick(|g| &g.tagged));
        let diffusion = tagged.map(|m| tagged_fokker_planck(m, grid));
        let maxwellian = grid.maxwellian();
        let mut h0 = vec![0.0; grid.len()];
        h0[start] = 1.0;
        let evolve = |estimate: Replicated<Generator>,
                      invariants: &[Vec<f64>],
                      equilibrium: Vec<f64>|
         -> Result<Process, EigenError> {
            let symmetric = estimate
                .map(|m| Dissipative::project(m, &maxwellian, invariants))
                .transpose()?;
            Ok(Process {
                states: symmetric.map(|m| m.propagate(&h0, times)),
                equilibrium,
                diagnostics: [
                    symmetric.scalar(|d| d.largest_clipped),
                    symmetric.scalar(|d| d.asymmetry),
                ],
            })
        };
        let number = [vec![1.0; grid.len()]];
        Ok(GridEvolution {
            processes: [
                evolve(
                    full,
                    &collision_invariants(grid),
                    grid.conserving_equilibrium(u_prime),
                )?,
                evolve(tagged, &number, number_equilibrium(grid))?,
                evolve(diffusion, &number, number_equilibrium(grid))?,
            ],
        })
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
    /// member's `h(t)` keeps the moments `1, u', u'^2` of `delta(u - u')`.
    /// The estimate had growing modes (clipped), so the projection did work.
    /// Rounding: the moment `p` is `p^T D^(1/2) V g(t) V^T D^(-1/2) h0`, and
    /// the eigenvectors `V` are orthogonal to the invariant directions
    /// `D^(1/2) p` to `n EPSILON` (Jacobi), so its error is below
    /// `n EPSILON ||D^(1/2) p||_1 / sqrt(f0_start)`.
    #[test]
    fn the_projected_full_process_conserves_number_momentum_and_energy() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let evolution = evolution(&grid);
        let [full, ..] = &evolution.processes;
        let [clipped, _] = full.diagnostics;
        assert!(clipped.mean > 0.0, "{clipped:?}");
        let rounding: Vec<f64> = collision_invariants(&grid)
            .iter()
            .map(|p| invariant_rounding(&grid, p))
            .collect();
        let delta = [1.0, U_PRIME, U_PRIME * U_PRIME];
        for h in members(&full.states) {
            let m = grid.moments(h, 0.0, f64::INFINITY);
            for p in 0..3 {
                assert!((m[p] - delta[p]).abs() < rounding[p], "{m:?} {rounding:?}");
            }
        }
    }

    /// `n EPSILON ||D^(1/2) p||_1 / sqrt(f0_start)`: the rounding of the
    /// invariant `p`'s moment after propagation by eigen-decomposition.
    fn invariant_rounding(grid: &VelocityGrid, p: &[f64]) -> f64 {
        let root: Vec<f64> = grid.maxwellian().iter().map(|f| f.sqrt()).collect();
        let start = grid.node_of(U_PRIME).unwrap();
        let weight: f64 = p.iter().zip(&root).map(|(p, r)| (p * r).abs()).sum();
        grid.len() as f64 * f64::EPSILON * weight / root[start]
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

    /// The tagged and Fokker-Planck processes conserve number whatever the
    /// estimate (number is an invariant of their projection): every
    /// member's `h(t)` keeps number 1, to the rounding of the invariant's
    /// moment ([`invariant_rounding`]).
    #[test]
    fn the_tagged_and_fokker_planck_processes_conserve_probability() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let evolution = evolution(&grid);
        let rounding = invariant_rounding(&grid, &vec![1.0; grid.len()]);
        for process in &evolution.processes[1..] {
            for h in members(&process.states) {
                let number: f64 = h.iter().sum();
                assert!((number - 1.0).abs() < rounding, "{number}");
            }
        }
    }

    /// The H-theorem by construction: for every process and every member,
    /// even from these noisy estimates that violate detailed balance, the
    /// relative entropy to the process's equilibrium never increases
    /// (`sum_k c_k^2 exp(2 lambda_k t) / 2` over modes with `lambda_k <= 0`;
    /// clipped noise modes keep their weight, so it need not reach 0).
    /// Rounding: a sum of `n` squares, each to `n EPSILON` of the first
    /// entropy.
    #[test]
    fn no_process_lets_the_entropy_rise() {
        let grid = VelocityGrid::covering(4.0, 0.2);
        let evolution = evolution(&grid);
        for (p, process) in evolution.processes.iter().enumerate() {
            let entropy = |h: &[f64]| process.entropy(&grid, h);
            let members: Vec<&Vec<Vec<f64>>> = std::iter::once(&process.states.full)
                .chain(&process.states.leave_one_out)
                .collect();
            for states in members {
                let values: Vec<f64> = states.iter().map(|h| entropy(h)).collect();
                let rounding = (grid.len() as f64).powi(2) * f64::EPSILON * values[0];
                for pair in values.windows(2) {
                    assert!(pair[1] <= pair[0] + rounding, "process {p}: {values:?}");
                }
                assert!(
                    values[values.len() - 1] < values[0],
                    "process {p}: {values:?}"
                );
            }
        }
    }
}
