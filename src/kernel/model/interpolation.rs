//! Kernels between the computed ones: the models of neighbouring kernels,
//! each evaluated at the same `u - u'`, and `ln G` interpolated through them
//! by the Lagrange polynomial, in the potential's coordinate (`1/n` for the
//! inverse power laws, `ln theta` for Lennard-Jones) or in `u'` (with the
//! mirror images `G(u' -> u) = G(-u' -> -u)`, physics.md §3).

use super::least_squares::{Design, Knots};
use crate::physics::potential::Potential;

/// Kernels an interpolation between potentials goes through: five, degree
/// four, as the held-out n = 7, 9 and theta = 0.3, 3 measured
/// (docs/kernel-model.md).
pub const POTENTIAL_NODES: usize = 5;

/// Kernels an interpolation in `u'` goes through: four, cubic.
pub const U_PRIME_NODES: usize = 4;

/// Fewest kernels a held-out test predicts from (cubic): with one of five
/// inverse power laws held out, four remain.
pub const FEWEST_NODES: usize = 4;

/// A family of potentials whose kernels interpolate into one another.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Inverse power laws with kicks (`n > 2`), in `1/n`: the small-kick
    /// exponent goes as `1 + 1/(n + 1)`.
    InversePower,
    /// Lennard-Jones, in `ln theta` (`theta = kT/eps`).
    LennardJones,
}

impl Family {
    /// The family of `potential` and its coordinate there; `None` for a
    /// potential no interpolation reaches (n = 2, Morse).
    pub fn of(potential: &Potential) -> Option<(Family, f64)> {
        match potential {
            Potential::InversePower(law) if law.n > 2.0 => {
                Some((Family::InversePower, 1.0 / law.n))
            }
            Potential::LennardJones(lj) => Some((Family::LennardJones, libm::log(lj.theta))),
            _ => None,
        }
    }

    /// The coordinate's name.
    pub fn coordinate(self) -> &'static str {
        match self {
            Family::InversePower => "1/n",
            Family::LennardJones => "ln theta",
        }
    }

    /// Nodes closer than this in the coordinate are one (`theta` = 0.1 and
    /// 0.1052: a tenth of the grid's spacing in `ln theta`).
    pub fn separation(self) -> f64 {
        match self {
            Family::InversePower => 0.0,
            Family::LennardJones => 0.2,
        }
    }
}

/// Indices of the `count` entries of `coordinates` nearest `at`, each at
/// least `separation` from every one taken before it, in ascending
/// coordinate; `None` when fewer are left or they do not lie on both sides
/// of `at` (no extrapolation).
pub fn nearest_nodes(
    coordinates: &[f64],
    at: f64,
    count: usize,
    separation: f64,
) -> Option<Vec<usize>> {
    let mut order: Vec<usize> = (0..coordinates.len()).collect();
    order.sort_by(|&a, &b| {
        (coordinates[a] - at)
            .abs()
            .total_cmp(&(coordinates[b] - at).abs())
    });
    let mut taken: Vec<usize> = Vec::new();
    for k in order {
        let apart = taken
            .iter()
            .all(|&j| (coordinates[j] - coordinates[k]).abs() >= separation.max(f64::MIN_POSITIVE));
        if taken.len() < count && apart {
            taken.push(k);
        }
    }
    taken.sort_by(|&a, &b| coordinates[a].total_cmp(&coordinates[b]));
    let (first, last) = (coordinates[*taken.first()?], coordinates[*taken.last()?]);
    (taken.len() == count && first < at && at < last).then_some(taken)
}

/// A value known at several points of a coordinate (`(coordinate, value,
/// standard error)`, distinct coordinates) interpolated to `at`: the
/// Lagrange polynomial through all of them, and its error `sqrt(sum (w_i
/// e_i)^2)` with its weights `w_i` (the values taken as independent); one
/// point is itself.
pub fn interpolate(points: &[(f64, f64, f64)], at: f64) -> (f64, f64) {
    let weights: Vec<f64> = (0..points.len())
        .map(|i| {
            (0..points.len())
                .filter(|&j| j != i)
                .map(|j| (at - points[j].0) / (points[i].0 - points[j].0))
                .product()
        })
        .collect();
    let value = weights.iter().zip(points).map(|(w, p)| w * p.1).sum();
    let variance: f64 = weights
        .iter()
        .zip(points)
        .map(|(w, p)| (w * p.2).powi(2))
        .sum();
    (value, variance.sqrt())
}

/// One side's model as stored (`kernel_model`, `kernel_model_covariance`):
/// its knots, `ln G` there and their covariance.
#[derive(Clone, Debug, PartialEq)]
pub struct SideCurve {
    /// The knots.
    pub knots: Knots,
    /// `ln G` at the knots (`G` in `rho^2 l v_th / v_th`).
    pub values: Vec<f64>,
    /// Their covariance, row-major.
    pub covariance: Vec<f64>,
}

impl SideCurve {
    /// `ln G` at distance `x > 0` from `u'`, with its standard error.
    pub fn ln_g(&self, x: f64) -> (f64, f64) {
        (
            self.knots.ln_g(&self.values, x),
            self.knots.ln_g_stderr(&self.covariance, x),
        )
    }

    /// Whether `[lower, upper]` (`v_th`) lies between the first and the
    /// last knot, where the model was fitted (beyond, it continues
    /// straight).
    pub fn covers(&self, lower: f64, upper: f64) -> bool {
        let (first, last) = (self.knots.t[0], self.knots.t[self.knots.t.len() - 1]);
        first <= self.knots.warp.t(lower) && self.knots.warp.t(upper) <= last
    }

    /// `ln` of the model's mean `G` over `[lower, upper]` (`0 < lower <
    /// upper`, `v_th`), with the standard error of `ln G` at the middle.
    pub fn ln_group_mean(&self, lower: f64, upper: f64) -> (f64, f64) {
        let mean = Design::new(&self.knots, &[lower], &[upper]).means(&self.values)[0];
        let middle = 0.5 * (lower + upper);
        (
            libm::log(mean),
            self.knots.ln_g_stderr(&self.covariance, middle),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The interpolation reproduces a polynomial of its degree exactly,
    /// returns a node's own value there, and carries the nodes' errors
    /// through its weights.
    #[test]
    fn lagrange_is_exact_for_a_cubic_and_its_error_follows_the_weights() {
        let cubic = |x: f64| 1.0 - 2.0 * x + 0.5 * x * x * x;
        let points: Vec<(f64, f64, f64)> = [0.0, 1.0, 2.5, 4.0]
            .iter()
            .map(|&x| (x, cubic(x), 0.1))
            .collect();
        let (value, error) = interpolate(&points, 3.0);
        assert!((value - cubic(3.0)).abs() < 1e-12);
        // At a node, the polynomial is that node alone.
        let (at_node, node_error) = interpolate(&points, 1.0);
        assert!((at_node - cubic(1.0)).abs() < 1e-12 && (node_error - 0.1).abs() < 1e-12);
        assert!(error > 0.1, "between nodes the weights spread: {error}");
        assert_eq!(interpolate(&points[..1], 7.0), (cubic(0.0), 0.1));
    }

    /// Nodes: the nearest, apart, on both sides of the target.
    #[test]
    fn nodes_are_the_nearest_apart_and_around_the_target() {
        let thetas = [0.05f64, 0.1, 0.1052, 0.2, 0.5, 0.8, 1.0, 2.0];
        let ln: Vec<f64> = thetas.iter().map(|t| libm::log(*t)).collect();
        let taken = nearest_nodes(&ln, libm::log(0.15), 5, 0.2).unwrap();
        let picked: Vec<f64> = taken.iter().map(|&k| thetas[k]).collect();
        // 0.1 and 0.1052 are one node: the nearer, 0.1052, stands for both.
        assert_eq!(picked, vec![0.05, 0.1052, 0.2, 0.5, 0.8]);
        // Beyond the last node, or with too few: none.
        assert_eq!(nearest_nodes(&ln, libm::log(3.0), 5, 0.2), None);
        assert_eq!(nearest_nodes(&ln[..3], libm::log(0.07), 5, 0.2), None);
        // Equal coordinates are never two nodes.
        assert_eq!(nearest_nodes(&[0.0, 0.0, 1.0], 0.5, 3, 0.0), None);
    }

    /// Which potentials interpolate, and in what.
    #[test]
    fn the_families_coordinates() {
        let ipp = Potential::inverse_power;
        assert_eq!(Family::of(&ipp(8.0)), Some((Family::InversePower, 0.125)));
        assert_eq!(Family::of(&ipp(2.0)), None);
        let lj = Family::of(&Potential::lennard_jones(1.0));
        assert_eq!(lj, Some((Family::LennardJones, 0.0)));
    }
}
