//! Kernels between the computed ones: the models of neighbouring kernels,
//! each evaluated at the same `u - u'`, and `ln G` interpolated through them
//! by the Lagrange polynomial, in the potential's coordinate (`1/n` for the
//! inverse power laws, `ln theta` for Lennard-Jones) or in `u'` (with the
//! mirror images `G(u' -> u) = G(-u' -> -u)`, physics.md §3).

use super::least_squares::{Design, Knots};
use crate::physics::potential::Potential;
use crate::stats::jackknife;

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

/// The Lagrange weights of the nodes `coordinates` (distinct) at `at`:
/// the polynomial through `(x_i, y_i)` is `sum_i w_i y_i` there (one node
/// weighs 1).
pub fn lagrange_weights(coordinates: &[f64], at: f64) -> Vec<f64> {
    (0..coordinates.len())
        .map(|i| {
            (0..coordinates.len())
                .filter(|&j| j != i)
                .map(|j| (at - coordinates[j]) / (coordinates[i] - coordinates[j]))
                .product()
        })
        .collect()
}

/// The `u'` nodes of one potential's kernels computed at the `u'` values
/// `computed` (one density): each computed kernel, then the mirror image
/// `G(u' -> u) = G(-u' -> -u)` of each at `u' != 0` whose `-u'` is not
/// computed, as `(u', index into computed, mirrored)`.
pub fn u_prime_nodes(computed: &[f64]) -> Vec<(f64, usize, bool)> {
    let direct = computed.iter().enumerate().map(|(k, &u)| (u, k, false));
    let mirrors = computed
        .iter()
        .enumerate()
        .filter(|&(_, &u)| u != 0.0 && !computed.contains(&-u))
        .map(|(k, &u)| (-u, k, true));
    direct.chain(mirrors).collect()
}

/// The nodes without the one farthest from `at` (the first on a tie):
/// the interpolation one degree lower, whose difference from the full one
/// is the last correction of Neville's algorithm, the interpolation's own
/// estimate of its error (Numerical Recipes, 3rd ed., §3.2); empty for
/// fewer than two nodes.
pub fn without_farthest(coordinates: &[f64], at: f64) -> Vec<usize> {
    if coordinates.len() < 2 {
        return Vec::new();
    }
    let farthest = (0..coordinates.len()).fold(0, |f, k| {
        if (coordinates[k] - at).abs() > (coordinates[f] - at).abs() {
            k
        } else {
            f
        }
    });
    (0..coordinates.len()).filter(|&k| k != farthest).collect()
}

/// A value with its jackknife replicates: the value from every
/// randomization, and the value without each in turn.
#[derive(Clone, Debug, PartialEq)]
pub struct Replicated {
    /// The value.
    pub value: f64,
    /// The value without each randomization.
    pub left_out: Vec<f64>,
}

impl Replicated {
    /// The jackknife standard error ([`jackknife`]).
    pub fn stderr(&self) -> f64 {
        let rows: Vec<[f64; 1]> = self.left_out.iter().map(|&v| [v]).collect();
        jackknife(&[self.value], &rows)[0].stderr
    }
}

/// `sum_i w_i y_i` of values `y` with jackknife replicates, and its
/// standard error. When every value has the same number of replicates,
/// randomization `r` is taken to be the same scenes in each (every `u'` of
/// a potential reweights one set; the potentials of a study draw the same
/// launches), and the combination is jackknifed as a whole: its error
/// carries every covariance between the values (and, were they
/// independent, would still estimate `sqrt(sum (w_i e_i)^2)`). Otherwise
/// the values are taken as independent.
pub fn combine(weights: &[f64], values: &[Replicated]) -> (f64, f64) {
    if let Some(combined) = combine_replicated(weights, values) {
        return (combined.value, combined.stderr());
    }
    let value = weights.iter().zip(values).map(|(w, y)| w * y.value).sum();
    let variance: f64 = weights
        .iter()
        .zip(values)
        .map(|(w, y)| (w * y.stderr()).powi(2))
        .sum();
    (value, variance.sqrt())
}

/// `sum_i w_i y_i` with its jackknife replicates, when every value has the
/// same number (more than one) of replicates from the same randomizations
/// ([`combine`]); `None` otherwise.
pub fn combine_replicated(weights: &[f64], values: &[Replicated]) -> Option<Replicated> {
    let count = values.first().map_or(0, |y| y.left_out.len());
    if count < 2 || values.iter().any(|y| y.left_out.len() != count) {
        return None;
    }
    let sum = |value: &dyn Fn(&Replicated) -> f64| -> f64 {
        weights.iter().zip(values).map(|(w, y)| w * value(y)).sum()
    };
    Some(Replicated {
        value: sum(&|y| y.value),
        left_out: (0..count).map(|r| sum(&|y| y.left_out[r])).collect(),
    })
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
    /// The knot values fitted without each randomization,
    /// `[randomization][knot]`: the covariance's replicates.
    pub left_out: Vec<Vec<f64>>,
}

impl SideCurve {
    /// `ln G` at distance `x > 0` from `u'`, with its jackknife replicates.
    pub fn ln_g(&self, x: f64) -> Replicated {
        Replicated {
            value: self.knots.ln_g(&self.values, x),
            left_out: self
                .left_out
                .iter()
                .map(|v| self.knots.ln_g(v, x))
                .collect(),
        }
    }

    /// Whether `[lower, upper]` (`v_th`) lies between the first and the
    /// last knot, where the model was fitted (beyond, it continues
    /// straight).
    pub fn covers(&self, lower: f64, upper: f64) -> bool {
        let (first, last) = (self.knots.t[0], self.knots.t[self.knots.t.len() - 1]);
        first <= self.knots.warp.t(lower) && self.knots.warp.t(upper) <= last
    }

    /// `ln` of the model's mean `G` over `[lower, upper]` (`0 < lower <
    /// upper`, `v_th`), with its jackknife replicates.
    pub fn ln_group_mean(&self, lower: f64, upper: f64) -> Replicated {
        let design = Design::new(&self.knots, &[lower], &[upper]);
        let ln_mean = |values: &[f64]| libm::log(design.means(values)[0]);
        Replicated {
            value: ln_mean(&self.values),
            left_out: self.left_out.iter().map(|v| ln_mean(v)).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Lagrange weights reproduce a polynomial of their degree exactly
    /// and a node's own value there; one node weighs 1.
    #[test]
    fn lagrange_is_exact_for_its_degree() {
        let cubic = |x: f64| 1.0 - 2.0 * x + 0.5 * x * x * x;
        let nodes = [0.0, 1.0, 2.5, 4.0];
        let at = |x: f64| -> f64 {
            let w = lagrange_weights(&nodes, x);
            w.iter().zip(&nodes).map(|(w, n)| w * cubic(*n)).sum()
        };
        assert!((at(3.0) - cubic(3.0)).abs() < 1e-12);
        assert!((at(1.0) - cubic(1.0)).abs() < 1e-12);
        assert_eq!(lagrange_weights(&[2.0], 7.0), vec![1.0]);
    }

    /// One degree lower drops the farthest node; its difference from the
    /// full interpolation vanishes for a polynomial of the lower degree and
    /// not for one of the full.
    #[test]
    fn neville_correction_sees_the_degree() {
        let nodes = [0.0, 1.0, 2.0, 4.0];
        assert_eq!(without_farthest(&nodes, 1.5), vec![0, 1, 2]);
        assert_eq!(without_farthest(&nodes[..1], 1.5), Vec::<usize>::new());
        let correction = |f: &dyn Fn(f64) -> f64| {
            let lower: Vec<f64> = without_farthest(&nodes, 1.5)
                .iter()
                .map(|&k| nodes[k])
                .collect();
            let at = |xs: &[f64]| -> f64 {
                let w = lagrange_weights(xs, 1.5);
                w.iter().zip(xs).map(|(w, x)| w * f(*x)).sum()
            };
            at(&nodes) - at(&lower)
        };
        assert!(correction(&|x| 2.0 - x + 3.0 * x * x).abs() < 1e-12);
        assert!(correction(&|x| x * x * x).abs() > 0.1);
    }

    /// Paired replicates carry the covariance: a difference of two values
    /// that move together has no error, a sum twice one's; unpaired
    /// (different counts) combine as independent.
    #[test]
    fn combined_errors_follow_the_pairing() {
        let a = Replicated {
            value: 1.0,
            left_out: vec![1.1, 0.9, 1.0, 1.0],
        };
        let (difference, none) = combine(&[1.0, -1.0], &[a.clone(), a.clone()]);
        assert_eq!((difference, none), (0.0, 0.0));
        let (_, twice) = combine(&[1.0, 1.0], &[a.clone(), a.clone()]);
        assert!((twice - 2.0 * a.stderr()).abs() < 1e-12);
        let b = Replicated {
            value: 2.0,
            left_out: vec![2.0, 2.2, 1.8],
        };
        let (sum, independent) = combine(&[1.0, 1.0], &[a.clone(), b.clone()]);
        assert_eq!(sum, 3.0);
        assert!((independent - libm::hypot(a.stderr(), b.stderr())).abs() < 1e-12);
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
