//! Master-equation generators on a [`VelocityGrid`] from collision events
//! (physics.md §4), and the Fokker-Planck generator of the same drift and
//! variance rates.
//!
//! Column `j` of the generator is the kernel `K(u_j -> u)` integrated over each
//! node's share: every event, reweighted to `u' = u_j` (Galilean invariance),
//! removes its three incoming velocities and adds its three outgoing ones, each
//! deposited with [`VelocityGrid::deposit`]. The `full` generator counts all
//! three particles (the linearized three-body operator acting on `h`: it
//! conserves number, momentum and energy event by event); the `tagged`
//! generator counts only the special particle's own pair (its velocity as a
//! Markov process, stationary in `f0` by detailed balance). Units: rates in
//! `rho^2 l v_th`, time in `1 / (rho^2 l v_th)`.

use rayon::prelude::*;

use super::dirichlet::DirichletForms;
use super::grid::{Stencil, VelocityGrid};
use super::propagate::Generator;
use crate::kernel::{Contribution, Draws, Event, images};

/// The two generators of one replicate.
#[derive(Clone, Debug, PartialEq)]
pub struct Generators {
    /// All three particles: the linearized collision operator.
    pub full: Generator,
    /// The special particle alone.
    pub tagged: Generator,
}

/// An event image with its launch weight at every node's `u'`.
struct Placed {
    /// The launch weight at `u' = u_j` for every node `j`: `weight |u2| |u3| /
    /// (2 pi) exp(-((u' + u2)^2 + (u' + u3)^2) / 2)`, written as the Gaussian
    /// `exp(-(u2 - u3)^2 / 4) exp(-(u' + (u2 + u3) / 2)^2)` of `u'`.
    weights: Vec<f64>,
    /// Per sorted rank, where its incoming and outgoing velocities (relative
    /// to `u'`) are deposited; `None` when the rank's velocity is unchanged.
    moves: [Option<[Stencil; 2]>; 3],
    self_rank: usize,
}

impl Placed {
    /// The image placed on `grid`, or `None` when it moves no velocity.
    fn new(image: &Contribution, scale: f64, grid: &VelocityGrid) -> Option<Placed> {
        let [_, u2, u3] = image.incoming;
        let incoming = image.sorted_incoming();
        let moves: [Option<[Stencil; 2]>; 3] = std::array::from_fn(|rank| {
            let (from, to) = (incoming[rank], image.outgoing[rank]);
            (from != to).then(|| [grid.stencil(from), grid.stencil(to)])
        });
        if moves.iter().all(Option::is_none) {
            return None;
        }
        let factor = image.weight * scale * (u2 * u3).abs() / (2.0 * std::f64::consts::PI)
            * libm::exp(-0.25 * (u2 - u3).powi(2));
        let mut weights = grid.gaussian(-0.5 * (u2 + u3));
        weights.iter_mut().for_each(|w| *w *= factor);
        Some(Placed {
            weights,
            moves,
            self_rank: image.self_rank,
        })
    }

    /// Adds rank `rank`'s move (nothing if its velocity is unchanged or the
    /// image has no weight there) to column `node`, weighted by the image's
    /// launch weight there.
    fn deposit_move(&self, grid: &VelocityGrid, node: usize, rank: usize, column: &mut [f64]) {
        let weight = self.weights[node];
        if let (Some([from, to]), true) = (&self.moves[rank], weight != 0.0) {
            grid.deposit_stencil(column, node, from, -weight);
            grid.deposit_stencil(column, node, to, weight);
        }
    }
}

/// One replicate's generator in the column form, stored by offset: entry
/// `(k, j)` (node `k` of column `j`) at `(k + n - 1 - j) n + j`, so that a
/// stencil seen from consecutive nodes adds along contiguous runs.
struct ColumnForm {
    n: usize,
    by_offset: Vec<f64>,
}

impl ColumnForm {
    fn new(n: usize) -> ColumnForm {
        ColumnForm {
            n,
            by_offset: vec![0.0; (2 * n - 1) * n],
        }
    }

    /// Adds an image's move (`[from, to]` stencils) to every column `j`,
    /// weighted by the image's launch weight `weights[j]` there.
    fn add_move(&mut self, grid: &VelocityGrid, [from, to]: &[Stencil; 2], weights: &[f64]) {
        self.add_stencil(grid, from, weights, -1.0);
        self.add_stencil(grid, to, weights, 1.0);
    }

    /// Adds `sign` times [`VelocityGrid::deposit_stencil`] of `stencil` seen
    /// from every node `j`, scaled by `weights[j]`: the same products added
    /// to each entry in the same order as column by column, the interior
    /// nodes' along three contiguous runs.
    fn add_stencil(&mut self, grid: &VelocityGrid, stencil: &Stencil, weights: &[f64], sign: f64) {
        let n = self.n;
        let interior = grid.interior_nodes(stencil);
        let lo = (*interior.start()).clamp(0, n as i64) as usize;
        let hi = (*interior.end() + 1).clamp(lo as i64, n as i64) as usize;
        for j in (0..lo).chain(hi..n).filter(|&j| weights[j] != 0.0) {
            let scale = sign * weights[j];
            for (k, w) in grid.stencil_entries(j, stencil) {
                self.by_offset[(k + n - 1 - j) * n + j] += scale * w;
            }
        }
        // No run when no node sees the stencil inside the grid (its offsets
        // may then lie beyond the grid).
        for (offset, w) in stencil.relative_entries().into_iter().filter(|_| lo < hi) {
            let row = (offset + n as i64 - 1) as usize * n;
            let run = &mut self.by_offset[row + lo..row + hi];
            for (entry, weight) in run.iter_mut().zip(&weights[lo..hi]) {
                *entry += sign * weight * w;
            }
        }
    }

    /// The generator (columns of `n` entries).
    fn generator(&self) -> Generator {
        let n = self.n;
        let columns: Vec<Vec<f64>> = (0..n)
            .map(|j| {
                (0..n)
                    .map(|k| self.by_offset[(k + n - 1 - j) * n + j])
                    .collect()
            })
            .collect();
        Generator::from_columns(&columns)
    }
}

/// The events of each replicate, in their stored order.
fn by_replicate<'a>(events: &'a [Event], draws: &Draws) -> Vec<Vec<&'a Event>> {
    let mut grouped: Vec<Vec<&Event>> = vec![Vec::new(); draws.replicates()];
    for event in events {
        grouped[event.randomization as usize].push(event);
    }
    grouped
}

/// The images of one replicate's `events` that move a velocity, placed on
/// `grid`, in the events' order.
fn placed_images<'a>(
    events: &'a [&'a Event],
    draws: &'a Draws,
    grid: &'a VelocityGrid,
    kick_floor: f64,
) -> impl Iterator<Item = Placed> + 'a {
    events.iter().flat_map(move |event| {
        let scale = draws.scale(event);
        images(event, kick_floor).filter_map(move |image| Placed::new(&image, scale, grid))
    })
}

/// The full and tagged generators of every replicate, from the events in the
/// dilute limit (velocity changes within `kick_floor` count as zero). Each
/// replicate adds its events in their stored order: bit-identical for any
/// thread count. `progress` receives the
/// events of each replicate as it finishes.
pub fn kernel_generators(
    events: &[Event],
    draws: &Draws,
    grid: &VelocityGrid,
    kick_floor: f64,
    progress: impl Fn(usize) + Sync,
) -> Vec<Generators> {
    let n = grid.len();
    by_replicate(events, draws)
        .par_iter()
        .map(|events| {
            let (mut full, mut tagged) = (ColumnForm::new(n), ColumnForm::new(n));
            for placed in placed_images(events, draws, grid, kick_floor) {
                for (rank, stencils) in placed.moves.iter().enumerate() {
                    let Some(stencils) = stencils else { continue };
                    full.add_move(grid, stencils, &placed.weights);
                    if rank == placed.self_rank {
                        tagged.add_move(grid, stencils, &placed.weights);
                    }
                }
            }
            progress(events.len());
            Generators {
                full: full.generator(),
                tagged: tagged.generator(),
            }
        })
        .collect()
}

/// The full and tagged generators of every replicate in detailed-balance
/// (Dirichlet) form, from the same events, images and deposition as
/// [`kernel_generators`]. With `mu` the equilibrium measure of the placed
/// images (`f0_j` times an image's launch weight at node `j`) and `Delta` an
/// image's deposited change (outgoing minus incoming velocities of the
/// counted particles), detailed balance (a collision and its time-reversed
/// mirror image are equally frequent in equilibrium) turns `phi^T M f0 g =
/// sum mu g(u') Delta phi` into `-1/6 sum mu (Delta g)(Delta phi)` for the
/// full operator (each collision is counted once per particle as the special
/// one); for the tagged one, whose special particle's change `delta_s` gives
/// `-1/2 sum mu (delta_s g)(delta_s phi)`, the same counting turns that into
/// `-1/6 sum mu sum_k (delta_k g)(delta_k phi)` over the three particles
/// (`delta_k` each one's own change, matched by rank): the partners' incoming
/// velocities lie between the nodes, so that a shape alternating from node to
/// node is not free to move (the special particle starts on a node, where the
/// interpolant of such a shape is flat: from it alone, small kicks leave it
/// a spurious slow mode). So `M = -A D^(-1) / 6`, `A = sum mu Delta
/// Delta^T` (or its per-particle sum), `D = diag(f0)`: `D^(-1/2) M
/// D^(1/2)` is symmetric and negative semi-definite for every sample, and its
/// zero modes are the invariants on both sides (each `Delta` keeps number,
/// momentum and energy). Where the scattering is nearly integrable (`n -> 2`),
/// an image's `Delta` is `O(e)` and enters squared, while the column form's
/// `O(e)` terms cancel only on average: the noise stays proportional to the
/// rates. Beside them, each replicate's tagged column at node `centre` as
/// [`kernel_generators`] computes it (the special particle's kernel there,
/// whose variance rate is exact), from the same placed images. Each
/// replicate adds its events in their stored order: bit-identical for any
/// thread count. `progress` receives the events of each replicate as it
/// finishes.
pub fn balanced_generators(
    events: &[Event],
    draws: &Draws,
    grid: &VelocityGrid,
    kick_floor: f64,
    centre: usize,
    progress: impl Fn(usize) + Sync,
) -> (Vec<Generators>, Vec<Vec<f64>>) {
    by_replicate(events, draws)
        .par_iter()
        .map(|events| {
            let mut forms = DirichletForms::new(grid);
            let mut centre_column = vec![0.0; grid.len()];
            for placed in placed_images(events, draws, grid, kick_floor) {
                forms.add(grid, &placed.weights, &placed.moves);
                placed.deposit_move(grid, centre, placed.self_rank, &mut centre_column);
            }
            progress(events.len());
            (forms.generators(), centre_column)
        })
        .unzip()
}

/// Drift `sum_i M_ij (u_i - u_j)` and variance rate `sum_i M_ij (u_i - u_j)^2`
/// of every column: for the tagged generator, the special particle's drift and
/// variance rates at `u' = u_j` (exact: deposition keeps both moments).
pub fn column_rates(generator: &Generator, grid: &VelocityGrid) -> (Vec<f64>, Vec<f64>) {
    (0..grid.len())
        .map(|j| {
            let [_, drift, variance] =
                grid.moments(&generator.column(j), grid.velocity(j), f64::INFINITY);
            (drift, variance)
        })
        .unzip()
}

/// The Fokker-Planck generator in detailed-balance form, `dh/dt = d/du
/// (D2/2 f0 d/du (h / f0))`, with the variance rate `D2` given at the nodes:
/// the drift is the one for which `f0` is stationary, `D1 = (D2' - u D2) / 2`
/// (expand the flux: `-D1 h + 1/2 d(D2 h)/du`). On the grid the flux between
/// neighbours `i`, `i + 1` is `w (g_(i+1) - g_i)` with `g = h / f0` (node
/// masses over the grid's `f0`) and `w = (D2_i + D2_(i+1)) / 4 sqrt(f0_i
/// f0_(i+1)) / step^2`: number is conserved, the grid's `f0` is stationary
/// and `f0^(-1/2) M f0^(1/2)` symmetric and negative semi-definite exactly,
/// so the relative entropy cannot rise (the ends reflect: no flux leaves).
pub fn balanced_fokker_planck(grid: &VelocityGrid, variance: &[f64]) -> Generator {
    let n = grid.len();
    let f0 = grid.maxwellian();
    let mut columns = vec![vec![0.0; n]; n];
    for i in 0..n - 1 {
        let w =
            0.25 * (variance[i] + variance[i + 1]) * (f0[i] * f0[i + 1]).sqrt() / grid.step.powi(2);
        // Flux w (h_(i+1) / f0_(i+1) - h_i / f0_i) from node i + 1 into node i.
        columns[i + 1][i] += w / f0[i + 1];
        columns[i + 1][i + 1] -= w / f0[i + 1];
        columns[i][i] -= w / f0[i];
        columns[i][i + 1] += w / f0[i];
    }
    Generator::from_columns(&columns)
}

/// The detailed-balance Fokker-Planck generator ([`balanced_fokker_planck`])
/// of the variance rates of `tagged` ([`column_rates`]): the diffusion limit
/// of the special particle's own evolution, stationary in `f0` by
/// construction (the measured drift is tested against stationarity apart,
/// by the sweep).
pub fn tagged_fokker_planck(tagged: &Generator, grid: &VelocityGrid) -> Generator {
    let (_, variance) = column_rates(tagged, grid);
    balanced_fokker_planck(grid, &variance)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A variance rate that varies with `u` as the three-body one does
    /// (falling from `u = 0`), to test the structure beyond a constant.
    fn falling_variance(grid: &VelocityGrid) -> Vec<f64> {
        grid.velocities()
            .iter()
            .map(|u| 0.3 / (1.0 + 0.2 * u * u))
            .collect()
    }

    /// The detailed-balance Fokker-Planck generator conserves number (its
    /// columns sum to zero), keeps the grid's `f0` stationary, is symmetric
    /// under `f0^(-1/2) . f0^(1/2)`, and moves mass only to neighbours with
    /// positive rates: to rounding (a few operations on entries of size
    /// `||M||_1`, each to `EPSILON`).
    #[test]
    fn balanced_fokker_planck_keeps_f0_and_is_symmetric() {
        let grid = VelocityGrid::covering(4.0, 0.1);
        let generator = balanced_fokker_planck(&grid, &falling_variance(&grid));
        let rounding = 16.0 * f64::EPSILON * generator.norm_1();
        let f0 = grid.maxwellian();
        let stationary = generator.apply(&f0);
        for j in 0..grid.len() {
            assert!(
                generator.column(j).iter().sum::<f64>().abs() < rounding,
                "column {j}"
            );
            assert!(
                stationary[j].abs() < rounding,
                "node {j}: {}",
                stationary[j]
            );
            for i in 0..grid.len() {
                let m = generator.entry(i, j);
                let s = m * (f0[j] / f0[i]).sqrt();
                let t = generator.entry(j, i) * (f0[i] / f0[j]).sqrt();
                assert!((s - t).abs() < rounding, "({i}, {j}): {s} vs {t}");
                if i != j {
                    assert!(
                        m >= 0.0 && (m == 0.0 || i.abs_diff(j) == 1),
                        "({i}, {j}): {m}"
                    );
                }
            }
        }
    }

    /// Ornstein-Uhlenbeck (`D2 = D`): the mean decays as `exp(-D t / 2)` up
    /// to the discretization's second-order error (halving the step divides
    /// the error by 4, within 10%), and the state relaxes to the grid's `f0`
    /// exactly (its stationary state by construction).
    #[test]
    fn ornstein_uhlenbeck_mean_converges_at_second_order() {
        let d = 0.3;
        let miss = |step: f64| {
            let grid = VelocityGrid::covering(9.0, step);
            let generator = balanced_fokker_planck(&grid, &vec![d; grid.len()]);
            let mut h0 = vec![0.0; grid.len()];
            h0[grid.node_of(1.6).unwrap()] = 1.0;
            let [h, last] = &generator.propagate(&h0, &[3.0, 400.0])[..] else {
                unreachable!()
            };
            let [m0, m1, _] = grid.moments(h, 0.0, f64::INFINITY);
            assert!((m0 - 1.0).abs() < 1e-12);
            let distance: f64 = last
                .iter()
                .zip(grid.maxwellian())
                .map(|(a, b)| (a - b).abs())
                .sum();
            assert!(distance < 1e-9, "step {step}: {distance}");
            m1 - 1.6 * libm::exp(-0.5 * d * 3.0)
        };
        let (coarse, fine) = (miss(0.2), miss(0.1));
        let order = libm::log2(coarse / fine);
        assert!((order - 2.0).abs() < 0.15, "{coarse} {fine}: order {order}");
    }
}
