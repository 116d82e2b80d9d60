//! Least squares of the kernel model on one side's log-spaced groups: the
//! model's group means as functions of its knot values, damped Gauss-Newton
//! from a log-linear start.

use super::spline::{NaturalSpline, Warp};
use crate::linalg::Cholesky;

/// The 8-point Gauss-Legendre rule on `[-1, 1]`: `(node, weight)`, exact for
/// polynomials of degree 15 (Abramowitz & Stegun, Table 25.4).
const GAUSS_LEGENDRE: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Where a side's model puts its knots: the warp `t(x)` and the knots in `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct Knots {
    /// The warp (its cut-off scale `x_c`, `v_th`).
    pub warp: Warp,
    /// The knots in `t`, ascending.
    pub t: Vec<f64>,
}

/// The cut-off scale as a fraction of the outermost resolved distance:
/// `x_c = x_resolved / 4`, so the last quarter of the resolved range is
/// where `t` turns from logarithmic to linear in `x`.
const CUTOFF_SCALE_FRACTION: f64 = 0.25;

impl Knots {
    /// `count` knots uniform in `t` from `first` (the inner edge of the
    /// innermost group, `v_th`) to `resolved` (the outer edge of the
    /// outermost resolved group).
    pub fn uniform(first: f64, resolved: f64, count: usize) -> Knots {
        let warp = Warp {
            cutoff_scale: CUTOFF_SCALE_FRACTION * resolved,
        };
        let (start, end) = (warp.t(first), warp.t(resolved));
        let step = (end - start) / (count - 1) as f64;
        Knots {
            warp,
            t: (0..count).map(|k| start + k as f64 * step).collect(),
        }
    }

    /// `ln G` at distance `x > 0` from `u'` for the knot values `values`.
    pub fn ln_g(&self, values: &[f64], x: f64) -> f64 {
        NaturalSpline::through(&self.t, values).value(self.warp.t(x))
    }

    /// Standard error of [`Knots::ln_g`] for knot values with covariance
    /// `covariance` (row-major): `sqrt(b^T C b)`, `b` the cardinal basis at
    /// `x`.
    pub fn ln_g_stderr(&self, covariance: &[f64], x: f64) -> f64 {
        let basis = &self.basis(&[x])[0];
        let size = basis.len();
        let mut variance = 0.0;
        for i in 0..size {
            for j in 0..size {
                variance += basis[i] * covariance[i * size + j] * basis[j];
            }
        }
        variance.max(0.0).sqrt()
    }

    /// The cardinal basis at each of `x`: `basis[point][k]` is the spline
    /// through the `k`-th unit vector, so `ln G(x) = sum_k basis_k(x) y_k`.
    pub fn basis(&self, x: &[f64]) -> Vec<Vec<f64>> {
        let count = self.t.len();
        let cardinal: Vec<NaturalSpline> = (0..count)
            .map(|k| {
                let unit: Vec<f64> = (0..count).map(|j| f64::from(u8::from(j == k))).collect();
                NaturalSpline::through(&self.t, &unit)
            })
            .collect();
        x.iter()
            .map(|&x| {
                let t = self.warp.t(x);
                cardinal.iter().map(|spline| spline.value(t)).collect()
            })
            .collect()
    }
}

/// The model's mean over each group, `(1 / width) int exp(ln G(x)) dx` by
/// Gauss-Legendre in `x`, as a function of the knot values.
pub struct Design {
    /// Per group, per node: the node's share of the group mean (half its
    /// Gauss-Legendre weight).
    shares: Vec<[f64; 8]>,
    /// Per group and node (`8 g + q`): the cardinal basis there.
    basis: Vec<Vec<f64>>,
    /// Knots.
    count: usize,
}

impl Design {
    /// The design of groups `[lower_g, upper_g]` (`v_th`, `0 < lower < upper`).
    pub fn new(knots: &Knots, lower: &[f64], upper: &[f64]) -> Design {
        let nodes: Vec<f64> = lower
            .iter()
            .zip(upper)
            .flat_map(|(&a, &b)| GAUSS_LEGENDRE.map(|(z, _)| 0.5 * (a + b) + 0.5 * (b - a) * z))
            .collect();
        Design {
            shares: vec![GAUSS_LEGENDRE.map(|(_, w)| 0.5 * w); lower.len()],
            basis: knots.basis(&nodes),
            count: knots.t.len(),
        }
    }

    /// `exp(ln G)` at every node for knot values `values` (a large
    /// argument saturates rather than overflows: such a step is rejected).
    fn node_values(&self, values: &[f64]) -> Vec<f64> {
        self.basis
            .iter()
            .map(|row| libm::exp(dot(row, values).min(700.0)))
            .collect()
    }

    /// The model's group means.
    pub fn means(&self, values: &[f64]) -> Vec<f64> {
        let nodes = self.node_values(values);
        self.shares
            .iter()
            .enumerate()
            .map(|(g, shares)| (0..8).map(|q| shares[q] * nodes[8 * g + q]).sum())
            .collect()
    }

    /// The group means and their derivatives in the knot values,
    /// `jacobian[g][k]`.
    fn linearized(&self, values: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let nodes = self.node_values(values);
        let mut means = vec![0.0; self.shares.len()];
        let mut jacobian = vec![vec![0.0; self.count]; self.shares.len()];
        for (g, shares) in self.shares.iter().enumerate() {
            for (q, share) in shares.iter().enumerate() {
                let value = share * nodes[8 * g + q];
                means[g] += value;
                for (k, entry) in jacobian[g].iter_mut().enumerate() {
                    *entry += value * self.basis[8 * g + q][k];
                }
            }
        }
        (means, jacobian)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Weighted residual sum of squares `sum_g w_g (data_g - model_g)^2`.
pub fn chi2(data: &[f64], weights: &[f64], model: &[f64]) -> f64 {
    data.iter()
        .zip(weights)
        .zip(model)
        .map(|((d, w), m)| w * (d - m) * (d - m))
        .sum()
}

/// A least-squares fit of the knot values.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// `ln G` at the knots (`ln` of `rho^2 l v_th / v_th`).
    pub values: Vec<f64>,
    /// The model's group means.
    pub means: Vec<f64>,
    /// Weighted residual sum of squares.
    pub chi2: f64,
    /// Whether the iterations reached a minimum: a step improved chi-square
    /// by at most 1e-12 of it, or no step improves it at any damping up to
    /// 1e12. Otherwise 200 iterations were spent.
    pub converged: bool,
}

/// Damped Gauss-Newton (Levenberg-Marquardt) iterations from `start`.
pub fn least_squares(design: &Design, data: &[f64], weights: &[f64], start: &[f64]) -> Solution {
    let mut values = start.to_vec();
    let mut means = design.means(&values);
    let mut current = chi2(data, weights, &means);
    let mut damping = 1e-3;
    for _ in 0..200 {
        let (model, jacobian) = design.linearized(&values);
        let (normal, gradient) = normal_equations(&jacobian, weights, data, &model);
        loop {
            let trial = damped_step(&normal, &gradient, damping).map(|step| {
                values
                    .iter()
                    .zip(&step)
                    .map(|(v, s)| v + s)
                    .collect::<Vec<f64>>()
            });
            let outcome = trial.map(|trial| {
                let trial_means = design.means(&trial);
                let value = chi2(data, weights, &trial_means);
                (trial, trial_means, value)
            });
            match outcome {
                Some((trial, trial_means, value)) if value.is_finite() && value < current => {
                    let converged = current - value <= 1e-12 * current;
                    (values, means, current) = (trial, trial_means, value);
                    damping *= 0.3;
                    if converged {
                        return Solution {
                            values,
                            means,
                            chi2: current,
                            converged,
                        };
                    }
                    break;
                }
                _ => {
                    damping *= 10.0;
                    if damping > 1e12 {
                        return Solution {
                            values,
                            means,
                            chi2: current,
                            converged: true,
                        };
                    }
                }
            }
        }
    }
    Solution {
        values,
        means,
        chi2: current,
        converged: false,
    }
}

/// `J^T W J` (row-major) and `J^T W (data - model)`.
fn normal_equations(
    jacobian: &[Vec<f64>],
    weights: &[f64],
    data: &[f64],
    model: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let count = jacobian.first().map_or(0, Vec::len);
    let mut normal = vec![0.0; count * count];
    let mut gradient = vec![0.0; count];
    for (g, row) in jacobian.iter().enumerate() {
        let residual = weights[g] * (data[g] - model[g]);
        for i in 0..count {
            gradient[i] += row[i] * residual;
            for j in 0..count {
                normal[i * count + j] += weights[g] * row[i] * row[j];
            }
        }
    }
    (normal, gradient)
}

/// The step solving `(N + damping diag N) step = gradient`, or `None` when
/// that matrix is not positive definite to rounding.
fn damped_step(normal: &[f64], gradient: &[f64], damping: f64) -> Option<Vec<f64>> {
    let count = gradient.len();
    let mut damped = normal.to_vec();
    for i in 0..count {
        damped[i * count + i] *= 1.0 + damping;
    }
    Some(Cholesky::of(&damped, count)?.solve(gradient))
}

/// The start of the iterations: `ln G` fitted by linear least squares to the
/// logarithms of the groups measured to better than a third, at each group's
/// geometric centre, weights `(G / error)^2`. `None` when fewer such groups
/// than knots, or their normal equations are singular.
pub fn log_linear_start(
    knots: &Knots,
    (lower, upper): (&[f64], &[f64]),
    data: &[f64],
    variance: &[f64],
) -> Option<Vec<f64>> {
    let measured: Vec<usize> = (0..data.len())
        .filter(|&g| data[g] > 3.0 * variance[g].sqrt())
        .collect();
    let count = knots.t.len();
    if measured.len() < count {
        return None;
    }
    let centres: Vec<f64> = measured
        .iter()
        .map(|&g| (lower[g] * upper[g]).sqrt())
        .collect();
    let jacobian = knots.basis(&centres);
    let logs: Vec<f64> = measured.iter().map(|&g| libm::log(data[g])).collect();
    let weights: Vec<f64> = measured
        .iter()
        .map(|&g| data[g] * data[g] / variance[g])
        .collect();
    let zeros = vec![0.0; measured.len()];
    let (normal, gradient) = normal_equations(&jacobian, &weights, &logs, &zeros);
    Some(Cholesky::of(&normal, count)?.solve(&gradient))
}
