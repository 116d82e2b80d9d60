//! The velocity grid of the master equation and moment-preserving deposition.
//!
//! A population `h` on the grid is a set of node masses `h_i` at velocities
//! `u_i = (i - half_nodes) * step` (units of `v_th`); its moments are
//! `sum_i h_i u_i^p`. A measure is deposited onto the three nodes nearest to
//! it with the weights that reproduce its zeroth, first and second moments
//! exactly (quadratic Lagrange weights for a point mass). So number, momentum
//! and kinetic energy of every deposited collision are kept exactly on any
//! grid, and a kick much smaller than the step still carries its exact drift
//! and variance (a Kramers-Moyal stencil), instead of vanishing in its bin.

use crate::linalg::solve3;
use crate::physics::launch::thermal_density;

/// Where a point mass at a fixed offset from a node is deposited: its
/// offset in steps, the nearest node's and the three quadratic Lagrange weights
/// around that one. Computed once, it serves every node of a column sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stencil {
    /// Offset in node units.
    shift: f64,
    /// Nearest node, relative.
    centre: i64,
    /// Weights of the nodes `centre - 1`, `centre`, `centre + 1`.
    weights: [f64; 3],
}

impl Stencil {
    /// Its entries seen from a node away from the grid's ends (see
    /// [`VelocityGrid::interior_nodes`]): node offsets and weights.
    pub fn relative_entries(&self) -> [(i64, f64); 3] {
        let [w0, w1, w2] = self.weights;
        let c = self.centre;
        [(c - 1, w0), (c, w1), (c + 1, w2)]
    }
}

/// Nodes `u_i = (i - half_nodes) * step`, `i = 0 ..= 2 half_nodes`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityGrid {
    /// Node spacing, `v_th`.
    pub step: f64,
    /// Nodes on each side of `u = 0`.
    pub half_nodes: usize,
}

impl VelocityGrid {
    /// The grid of spacing `step` covering `[-range, range]` (at least 3 nodes).
    pub fn covering(range: f64, step: f64) -> VelocityGrid {
        VelocityGrid {
            step,
            half_nodes: ((range / step).round() as usize).max(1),
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        2 * self.half_nodes + 1
    }

    /// `true` when the grid has no nodes (never: it has at least three).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Velocity of node `index`, `v_th`.
    pub fn velocity(&self, index: usize) -> f64 {
        (index as f64 - self.half_nodes as f64) * self.step
    }

    /// Velocities of all nodes.
    pub fn velocities(&self) -> Vec<f64> {
        (0..self.len()).map(|i| self.velocity(i)).collect()
    }

    /// Position of velocity `u` in node units (node `i` sits at `i`).
    pub fn position(&self, u: f64) -> f64 {
        u / self.step + self.half_nodes as f64
    }

    /// The node of velocity `u`, if `u` is one (within 1e-9 of a step).
    pub fn node_of(&self, u: f64) -> Option<usize> {
        let position = self.position(u);
        let node = position.round();
        ((position - node).abs() < 1e-9 && node >= 0.0 && node < self.len() as f64)
            .then_some(node as usize)
    }

    /// Adds `scale` times a measure at `position` (node units) with moments
    /// `[m0, m1, m2]` about `position` (in node units) onto the three nodes
    /// around it, reproducing the three moments exactly. The grid's ends
    /// reflect: a position beyond them is moved onto the end node, and the
    /// weight a stencil centred on an end node would put outside is added to
    /// that node (number is kept; the moments only approximately, at the
    /// ends, where the Maxwellian's mass is negligible). This keeps the
    /// generators stable: an extrapolating stencil at the ends would give
    /// anti-diffusion there and exponentially growing modes.
    pub fn deposit(&self, column: &mut [f64], position: f64, moments: [f64; 3], scale: f64) {
        for (node, weight) in self.deposit_entries(position, moments) {
            column[node] += scale * weight;
        }
    }

    /// The nodes and weights [`VelocityGrid::deposit`] adds (once each, in
    /// this order; at an end two entries may name the same node).
    pub fn deposit_entries(&self, position: f64, moments: [f64; 3]) -> [(usize, f64); 3] {
        let last = self.len() - 1;
        let position = position.clamp(0.0, last as f64);
        let centre = position.round();
        let d = position - centre;
        let [m0, m1, m2] = moments;
        let (c1, c2) = (m1 + d * m0, m2 + 2.0 * d * m1 + d * d * m0);
        let weights = [0.5 * (c2 - c1), m0 - c2, 0.5 * (c2 + c1)];
        let k = centre as usize;
        [
            (k, weights[1]),
            (k.saturating_sub(1), weights[0]),
            ((k + 1).min(last), weights[2]),
        ]
    }

    /// The stencil of a point mass `x` (`v_th`) away from a node.
    pub fn stencil(&self, x: f64) -> Stencil {
        let shift = x / self.step;
        let centre = shift.round();
        let d = shift - centre;
        Stencil {
            shift,
            centre: centre as i64,
            weights: [0.5 * (d * d - d), 1.0 - d * d, 0.5 * (d * d + d)],
        }
    }

    /// Adds `scale` times the point mass of `stencil` seen from node `node`:
    /// [`VelocityGrid::deposit`] of it, whose weights inside the grid depend
    /// on the offset alone (the same three moments), and which near the ends,
    /// where it reflects, is called.
    pub fn deposit_stencil(&self, column: &mut [f64], node: usize, stencil: &Stencil, scale: f64) {
        for (k, weight) in self.stencil_entries(node, stencil) {
            column[k] += scale * weight;
        }
    }

    /// The nodes from which `stencil` lies inside the grid, where
    /// [`VelocityGrid::stencil_entries`] are its
    /// [`Stencil::relative_entries`] shifted (possibly empty).
    pub fn interior_nodes(&self, stencil: &Stencil) -> std::ops::RangeInclusive<i64> {
        1 - stencil.centre..=self.len() as i64 - 2 - stencil.centre
    }

    /// The nodes and weights [`VelocityGrid::deposit_stencil`] adds.
    pub fn stencil_entries(&self, node: usize, stencil: &Stencil) -> [(usize, f64); 3] {
        if !self.interior_nodes(stencil).contains(&(node as i64)) {
            return self.deposit_entries(node as f64 + stencil.shift, [1.0, 0.0, 0.0]);
        }
        let k = node as i64 + stencil.centre;
        let k = k as usize;
        let [w0, w1, w2] = stencil.weights;
        [(k - 1, w0), (k, w1), (k + 1, w2)]
    }

    /// Adds a point mass `scale` at velocity `u`.
    pub fn deposit_point(&self, column: &mut [f64], u: f64, scale: f64) {
        self.deposit(column, self.position(u), [1.0, 0.0, 0.0], scale);
    }

    /// `exp(-(u_i - centre)^2)` at every node `i`, with one `exp` per node
    /// replaced by two multiplications: outward from the node `k` nearest to
    /// `centre`, `g_(i+1) = g_i q_i` with `q_(i+1) = q_i exp(-2 h^2)` (and the
    /// mirror recurrence below `k`), exact Gaussian ratios on a uniform grid
    /// of step `h`. Rounding grows like the square of the distance from `k`
    /// in nodes: below 1e-12 relative over 200 nodes (unit test). Starting at
    /// the peak, an underflow to zero happens only where the Gaussian is
    /// below the smallest double anyway.
    pub fn gaussian(&self, centre: f64) -> Vec<f64> {
        let h = self.step;
        let peak = self
            .position(centre)
            .round()
            .clamp(0.0, (self.len() - 1) as f64) as usize;
        let x = self.velocity(peak) - centre;
        let curvature = libm::exp(-2.0 * h * h);
        let mut values = vec![0.0; self.len()];
        values[peak] = libm::exp(-x * x);
        let (mut value, mut ratio) = (values[peak], libm::exp(-2.0 * x * h - h * h));
        for slot in &mut values[peak + 1..] {
            value *= ratio;
            ratio *= curvature;
            *slot = value;
        }
        let (mut value, mut ratio) = (values[peak], libm::exp(2.0 * x * h - h * h));
        for slot in values[..peak].iter_mut().rev() {
            value *= ratio;
            ratio *= curvature;
            *slot = value;
        }
        values
    }

    /// Node masses of `f0` (density times step), the stationary state of the
    /// special particle's own (tagged) evolution.
    pub fn maxwellian(&self) -> Vec<f64> {
        self.velocities()
            .iter()
            .map(|&u| thermal_density(u) * self.step)
            .collect()
    }

    /// Node masses of `f0 (a + b u + c u^2)` with the three moments of
    /// `delta(u - u')` on this grid: the equilibrium that the perturbation
    /// relaxes to under a collision operator that conserves number, momentum
    /// and energy (the projection onto `f0 {1, u, u^2}`: the whole gas heats
    /// or cools and drifts by the special particle's share). On an unbounded
    /// grid `f0 (1 + u u' + (u'^2 - 1)(u^2 - 1)/2)`; here the grid's own sums
    /// of `f0 u^p` fix `a, b, c`, so that the projected evolution reaches it
    /// exactly (the continuum form missed it by 0.0035 in L1 at `|u| <= 4`).
    pub fn conserving_equilibrium(&self, u_prime: f64) -> Vec<f64> {
        let f0 = self.maxwellian();
        let powers = |u: f64| [1.0, u, u * u];
        let mut gram = [[0.0; 3]; 3];
        for (i, &mass) in f0.iter().enumerate() {
            let p = powers(self.velocity(i));
            for j in 0..3 {
                for k in 0..3 {
                    gram[j][k] += mass * p[j] * p[k];
                }
            }
        }
        let c = solve3(&gram, &powers(u_prime)).unwrap_or([f64::NAN; 3]);
        f0.iter()
            .enumerate()
            .map(|(i, &mass)| {
                let p = powers(self.velocity(i));
                mass * (c[0] * p[0] + c[1] * p[1] + c[2] * p[2])
            })
            .collect()
    }

    /// Moments `sum_i h_i (u_i - centre)^p` for `p = 0, 1, 2`, counting only
    /// nodes with `|u_i - centre| <= reach`.
    pub fn moments(&self, h: &[f64], centre: f64, reach: f64) -> [f64; 3] {
        let mut sums = [0.0; 3];
        for (i, &mass) in h.iter().enumerate() {
            let x = self.velocity(i) - centre;
            if x.abs() <= reach {
                sums[0] += mass;
                sums[1] += mass * x;
                sums[2] += mass * x * x;
            }
        }
        sums
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Gaussian by recurrence agrees with `exp` node by node to 1e-12
    /// relative wherever it is a normal double, on and off the grid's nodes
    /// and with its peak inside, at or beyond the grid's ends.
    #[test]
    fn the_gaussian_by_recurrence_is_the_exponential() {
        let grid = VelocityGrid::covering(4.0, 0.02);
        for centre in [0.0, 0.013, -1.2345, 3.99, 4.0, -4.3, 9.7, -25.0] {
            let values = grid.gaussian(centre);
            for (i, value) in values.iter().enumerate() {
                let x = grid.velocity(i) - centre;
                let exact = libm::exp(-x * x);
                if exact > 1e-290 {
                    let error = (value - exact).abs() / exact;
                    assert!(
                        error < 1e-12,
                        "centre {centre}, node {i}: {value} vs {exact}"
                    );
                } else {
                    assert!(*value < 1e-280, "centre {centre}, node {i}: {value}");
                }
            }
        }
    }

    /// Deposited points keep number, momentum and energy exactly away from
    /// the grid's ends.
    #[test]
    fn deposition_keeps_three_moments() {
        let grid = VelocityGrid::covering(1.0, 0.1);
        for u in [-0.949, -0.9, -0.03, 0.0, 0.049, 0.05, 0.5123, 0.949] {
            let mut column = vec![0.0; grid.len()];
            grid.deposit_point(&mut column, u, 2.5);
            let moments = grid.moments(&column, 0.0, f64::INFINITY);
            assert!((moments[0] - 2.5).abs() < 1e-13, "{u}: {moments:?}");
            assert!((moments[1] - 2.5 * u).abs() < 1e-13, "{u}: {moments:?}");
            assert!((moments[2] - 2.5 * u * u).abs() < 1e-13, "{u}: {moments:?}");
        }
    }

    /// A stencil deposits the three moments of its point mass from every
    /// node, inside the grid and where it reflects at the ends.
    #[test]
    fn stencils_keep_three_moments_from_every_node() {
        let grid = VelocityGrid::covering(1.0, 0.1);
        for x in [-0.349, -0.05, 0.0, 0.031, 0.05, 0.27] {
            let stencil = grid.stencil(x);
            for node in 0..grid.len() {
                let mut column = vec![0.0; grid.len()];
                grid.deposit_stencil(&mut column, node, &stencil, 2.5);
                let mut direct = vec![0.0; grid.len()];
                let position = node as f64 + x / grid.step;
                grid.deposit(&mut direct, position, [1.0, 0.0, 0.0], 2.5);
                let u = grid.velocity(node) + x;
                let m = grid.moments(&column, 0.0, f64::INFINITY);
                assert!((m[0] - 2.5).abs() < 1e-13, "{x} from {node}: {m:?}");
                let centre = node as i64 + (x / grid.step).round() as i64;
                if centre >= 1 && centre + 2 <= grid.len() as i64 {
                    assert!((m[1] - 2.5 * u).abs() < 1e-13, "{x} from {node}: {m:?}");
                    assert!((m[2] - 2.5 * u * u).abs() < 1e-13, "{x} from {node}: {m:?}");
                } else {
                    let apart = column.iter().zip(&direct).map(|(a, b)| (a - b).abs());
                    assert!(apart.fold(0.0, f64::max) < 1e-13, "{x} from {node}");
                }
            }
        }
    }

    /// Beyond and at the ends, number is kept and no weight is negative.
    #[test]
    fn deposition_reflects_at_the_ends() {
        let grid = VelocityGrid::covering(1.0, 0.1);
        for u in [-1.37, -1.0, -0.96, 0.97, 1.0, 1.2] {
            let mut column = vec![0.0; grid.len()];
            grid.deposit_point(&mut column, u, 1.0);
            assert!((column.iter().sum::<f64>() - 1.0).abs() < 1e-15, "{u}");
            assert!(column.iter().all(|&w| w >= 0.0), "{u}: {column:?}");
        }
    }

    /// A measure with zero mass, drift `a` and second moment `b` (a Kramers-Moyal
    /// stencil) keeps them inside the grid.
    #[test]
    fn deposition_of_a_stencil_keeps_its_moments() {
        let grid = VelocityGrid::covering(1.0, 0.1);
        for node in [1, 3, grid.len() - 2] {
            let mut column = vec![0.0; grid.len()];
            grid.deposit(&mut column, node as f64, [0.0, 0.3, 0.7], 1.0);
            let centre = grid.velocity(node);
            let m = grid.moments(&column, centre, f64::INFINITY);
            assert!(m[0].abs() < 1e-14);
            assert!((m[1] - 0.3 * grid.step).abs() < 1e-14, "{m:?}");
            assert!((m[2] - 0.7 * grid.step.powi(2)).abs() < 1e-14, "{m:?}");
        }
    }

    /// The conserving equilibrium has the delta's number, momentum and energy.
    #[test]
    fn conserving_equilibrium_has_the_moments_of_the_delta() {
        let grid = VelocityGrid::covering(9.0, 0.01);
        for u_prime in [0.0, 0.7, -1.9] {
            let m = grid.moments(&grid.conserving_equilibrium(u_prime), 0.0, f64::INFINITY);
            assert!((m[0] - 1.0).abs() < 1e-12);
            assert!((m[1] - u_prime).abs() < 1e-12);
            assert!((m[2] - u_prime * u_prime).abs() < 1e-12, "{m:?}");
        }
    }
}
