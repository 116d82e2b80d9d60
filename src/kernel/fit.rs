//! Shape of the kernel near `u'` (physics.md §5):
//! `g(x) = alpha |x|^-beta exp(-x^2 / (2 sigma^2))`, `x = u - u'`.
//!
//! Fine bins are first merged into log-spaced groups in `|x|` (both sides of
//! `u'` together): group means have accurate replicate errors, whereas weights
//! from noisy per-bin errors bias a least-squares fit (bins whose error happens
//! to be underestimated pull it), and the model is averaged over each group's
//! bins, so grouping adds no binning error.
//!
//! Weighted least squares in `G` itself (weights `1 / G_stderr^2`), solved by
//! Gauss-Newton with Levenberg damping in the parameters
//! `(ln alpha, beta, 1/sigma^2)`, started from the log-linear fit (in which the
//! model is linear). Bins are correlated (one scene feeds several bins), so the
//! parameters' standard errors and covariance come from refitting each
//! independent replicate and taking the spread; the chi-square of the mean fit
//! measures the goodness of fit. At high precision the three-parameter shape
//! does not describe the kernel exactly (chi2/dof of 20 at 1.2e6 scenes for
//! n = 6): the errors are then scaled by sqrt(chi2/dof), and the parameters
//! depend on the fit's [`Protocol`] (range and weights) by more than their
//! statistical errors; [`systematic`] measures that over [`varied_protocols`].

use crate::linalg::solve3;
use crate::stats::Estimate;

/// Fitted shape parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// Amplitude `alpha` (units of `G` times `v_th^beta`).
    pub alpha: f64,
    /// Power-law exponent `beta` of the near-`u'` divergence.
    pub beta: f64,
    /// Gaussian cut-off `sigma`, `v_th`: the largest momentum transfer.
    pub sigma: f64,
}

/// Points of a kernel to fit: each the mean of `G` over a group of bins.
#[derive(Clone, Copy, Debug)]
pub struct FitData<'a> {
    /// Per point, the centres `x = u - u'` of the bins it averages.
    pub members: &'a [Vec<f64>],
    /// Mean kernel values of the points.
    pub values: &'a [f64],
    /// Standard errors of the values (points with zero error are skipped).
    pub errors: &'a [f64],
}

/// Groups the bins with `low <= |x| <= high` into `groups` log-spaced
/// intervals of `|x|`; returns the member bin indices of each non-empty group.
pub fn log_groups(offsets: &[f64], low: f64, high: f64, groups: usize) -> Vec<Vec<usize>> {
    let ratio = libm::log(high / low) / groups as f64;
    let mut members = vec![Vec::new(); groups];
    for (k, &x) in offsets.iter().enumerate() {
        let size = x.abs();
        if (low..=high).contains(&size) {
            let group = ((libm::log(size / low) / ratio) as usize).min(groups - 1);
            members[group].push(k);
        }
    }
    members.retain(|m| !m.is_empty());
    members
}

/// The mean fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeFit {
    /// Parameters.
    pub shape: Shape,
    /// Chi-square per degree of freedom of the fit to the mean kernel.
    pub chi2_per_dof: f64,
    /// Bins used.
    pub bins: usize,
    /// Whether the iterations reached a minimum (`refine`); otherwise the
    /// parameters are the last iterate.
    pub converged: bool,
}

/// Parameters in the fit's coordinates `(ln alpha, beta, 1/sigma^2)`.
type Coordinates = [f64; 3];

/// The model at `x`, given `log = ln|x|`.
fn model(p: &Coordinates, x: f64, log: f64) -> f64 {
    libm::exp(p[0] - p[1] * log - 0.5 * p[2] * x * x)
}

/// A point's bins: their offsets `x` and `ln|x|`, taken once per fit (the iterations
/// evaluate the model at the same bins over and over).
struct PointBins<'a> {
    x: &'a [f64],
    log: Vec<f64>,
}

impl PointBins<'_> {
    /// The bins of every point of `data`.
    fn of<'a>(data: &FitData<'a>) -> Vec<PointBins<'a>> {
        data.members
            .iter()
            .map(|x| PointBins {
                x,
                log: x.iter().map(|x| libm::log(x.abs())).collect(),
            })
            .collect()
    }

    /// The model averaged over the bins.
    fn model(&self, p: &Coordinates) -> f64 {
        let models = self
            .x
            .iter()
            .zip(&self.log)
            .map(|(&x, &log)| model(p, x, log));
        models.sum::<f64>() / self.x.len() as f64
    }

    /// The model and its gradient in the fit coordinates averaged over the bins, one
    /// exponential per bin for both.
    fn model_and_gradient(&self, p: &Coordinates) -> (f64, [f64; 3]) {
        let count = self.x.len() as f64;
        let mut sum = -0.0;
        let mut gradient = [0.0; 3];
        for (&x, &log) in self.x.iter().zip(&self.log) {
            let g = model(p, x, log);
            sum += g;
            gradient = [
                gradient[0] + g / count,
                gradient[1] + -g * log / count,
                gradient[2] + -0.5 * g * x * x / count,
            ];
        }
        (sum / count, gradient)
    }
}

/// Geometric mean of `|x|` over a point's bins (for the log-linear start).
fn representative(members: &[f64]) -> f64 {
    libm::exp(members.iter().map(|x| libm::log(x.abs())).sum::<f64>() / members.len() as f64)
}

/// Indices of the points with a positive error.
fn selected(data: &FitData) -> Vec<usize> {
    (0..data.values.len())
        .filter(|&k| data.errors[k] > 0.0 && data.values[k].is_finite())
        .collect()
}

/// Log-linear start: `ln G = ln alpha - beta ln|x| - x^2/(2 sigma^2)` fitted on bins
/// measured to better than a third, weights `(G / error)^2`.
fn log_linear_start(data: &FitData, bins: &[usize]) -> Option<Coordinates> {
    let mut normal = [[0.0; 3]; 3];
    let mut right = [0.0; 3];
    for &k in bins
        .iter()
        .filter(|&&k| data.values[k] > 3.0 * data.errors[k])
    {
        let x = representative(&data.members[k]);
        let basis = [1.0, -libm::log(x), -0.5 * x * x];
        let weight = (data.values[k] / data.errors[k]).powi(2);
        for i in 0..3 {
            right[i] += weight * basis[i] * libm::log(data.values[k]);
            for j in 0..3 {
                normal[i][j] += weight * basis[i] * basis[j];
            }
        }
    }
    solve3(&normal, &right)
}

fn chi2(data: &FitData, points: &[PointBins], bins: &[usize], p: &Coordinates) -> f64 {
    bins.iter()
        .map(|&k| ((data.values[k] - points[k].model(p)) / data.errors[k]).powi(2))
        .sum()
}

/// Iterations `refine` allows.
const ITERATIONS: usize = 200;

/// Damped Gauss-Newton (Levenberg-Marquardt) iterations from `start` until
/// chi-square stops improving, and whether they converged: a step improved
/// chi-square by at most 1e-12 of it, or no step improves it at any damping
/// up to 1e12 (a minimum to rounding). Not converged: [`ITERATIONS`] spent,
/// or singular normal equations.
fn refine(
    data: &FitData,
    points: &[PointBins],
    bins: &[usize],
    start: Coordinates,
) -> (Coordinates, bool) {
    let mut p = start;
    let mut current = chi2(data, points, bins, &p);
    let mut damping = 1e-3;
    for _ in 0..ITERATIONS {
        let mut normal = [[0.0; 3]; 3];
        let mut right = [0.0; 3];
        for &k in bins {
            let (model, gradient) = points[k].model_and_gradient(&p);
            let residual = (data.values[k] - model) / data.errors[k];
            let grad = gradient.map(|g| g / data.errors[k]);
            for i in 0..3 {
                right[i] += grad[i] * residual;
                for j in 0..3 {
                    normal[i][j] += grad[i] * grad[j];
                }
            }
        }
        for (i, row) in normal.iter_mut().enumerate() {
            row[i] *= 1.0 + damping;
        }
        let Some(step) = solve3(&normal, &right) else {
            return (p, false);
        };
        let trial = [p[0] + step[0], p[1] + step[1], p[2] + step[2]];
        let value = chi2(data, points, bins, &trial);
        if value < current {
            let converged = current - value <= 1e-12 * current;
            (p, current, damping) = (trial, value, damping * 0.3);
            if converged {
                return (p, true);
            }
        } else {
            damping *= 10.0;
            if damping > 1e12 {
                return (p, true);
            }
        }
    }
    (p, false)
}

/// Fits the shape to the points.
pub fn fit_shape(data: &FitData) -> Option<ShapeFit> {
    let bins = selected(data);
    if bins.len() < 4 {
        return None;
    }
    let points = PointBins::of(data);
    let (p, converged) = refine(data, &points, &bins, log_linear_start(data, &bins)?);
    if p.iter().any(|v| !v.is_finite()) || p[2] <= 0.0 {
        return None;
    }
    let shape = Shape {
        alpha: libm::exp(p[0]),
        beta: p[1],
        sigma: p[2].sqrt().recip(),
    };
    // ln alpha beyond ~709 overflows: no shape a table can hold (seen for
    // Lennard-Jones at theta = 300, u' = -3, whose few kicks fit nothing).
    if !(shape.alpha.is_finite() && shape.sigma.is_finite()) {
        return None;
    }
    Some(ShapeFit {
        shape,
        chi2_per_dof: chi2(data, &points, &bins, &p) / (bins.len() - 3) as f64,
        bins: bins.len(),
        converged,
    })
}

/// Log-spaced groups of bins per decade of `|x|` (36 over the default range
/// 2e-4..0.05).
pub const GROUPS_PER_DECADE: f64 = 15.0;

/// Groups over `low <= |x| <= high`: [`GROUPS_PER_DECADE`] per decade, at least 4.
pub fn group_count((low, high): (f64, f64)) -> usize {
    ((GROUPS_PER_DECADE * libm::log10(high / low)).round() as usize).max(4)
}

/// How the groups are weighted in a fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// `1 / stderr^2` from the randomizations: the best fit were the shape exact.
    Statistical,
    /// Equal relative weights, `1 / G^2` (up to one common factor): least
    /// squares in `ln G`, as a fit drawn on log axes weights the points. Its
    /// chi-square is not a goodness of fit.
    Relative,
}

impl Weighting {
    /// Name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Weighting::Statistical => "statistical",
            Weighting::Relative => "relative",
        }
    }

    /// Errors that weight the points: the statistical ones, or each value's
    /// size times the median relative error (so chi-squares stay comparable).
    fn errors(self, values: &[f64], errors: &[f64]) -> Vec<f64> {
        match self {
            Weighting::Statistical => errors.to_vec(),
            Weighting::Relative => {
                let mut relative: Vec<f64> = values
                    .iter()
                    .zip(errors)
                    .filter(|&(v, e)| *v > 0.0 && *e > 0.0)
                    .map(|(v, e)| e / v)
                    .collect();
                relative.sort_by(f64::total_cmp);
                let typical = relative.get(relative.len() / 2).copied().unwrap_or(0.0);
                values.iter().map(|v| v.max(0.0) * typical).collect()
            }
        }
    }
}

/// A fit protocol: the range of `|x|` fitted and the weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    /// Smallest and largest `|x|` fitted, `v_th`.
    pub range: (f64, f64),
    /// Weights of the groups.
    pub weighting: Weighting,
}

/// Lower ends of the fit range varied for the systematic error, `v_th`: 2 to
/// 10 bins of the default width from `u'`.
pub const VARIED_LOWER: [f64; 3] = [1e-4, 2e-4, 5e-4];
/// Upper ends varied: the kernel's half-width at half the paper's truncation,
/// the truncation 0.04, and the default range's end, `v_th`.
pub const VARIED_UPPER: [f64; 3] = [0.02, 0.04, 0.05];

/// Every protocol of the systematic variation: [`VARIED_LOWER`] x
/// [`VARIED_UPPER`] x both weightings (18 fits).
pub fn varied_protocols() -> Vec<Protocol> {
    let mut protocols = Vec::new();
    for weighting in [Weighting::Statistical, Weighting::Relative] {
        for low in VARIED_LOWER {
            for high in VARIED_UPPER {
                protocols.push(Protocol {
                    range: (low, high),
                    weighting,
                });
            }
        }
    }
    protocols
}

/// Systematic error of one parameter from the choice of protocol: half the
/// spread (largest minus smallest) of its mean fits over `fits`; NaN when
/// none converged.
pub fn systematic<'a>(
    fits: impl IntoIterator<Item = &'a KernelFit>,
    parameter: fn(&Shape) -> f64,
) -> f64 {
    let values: Vec<f64> = fits
        .into_iter()
        .filter_map(|f| f.mean.map(|m| parameter(&m.shape)))
        .collect();
    if values.is_empty() {
        return f64::NAN;
    }
    let (low, high) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    0.5 * (high - low)
}

/// A kernel's shape fit: to the mean over the replicates, and to each one.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelFit {
    /// Fit to the replicate mean (`None` when nothing could be fitted).
    pub mean: Option<ShapeFit>,
    /// Fits of the replicates that converged to a shape: a refit stopped
    /// at the iteration limit or on singular normal equations lies wherever
    /// its last iterate did, no sample of the error (the default study's
    /// `lj-50` at `u' = -3`: one such refit made a standard error of 1e52).
    pub replicates: Vec<Shape>,
    /// Groups of bins with a nonzero standard error.
    pub measured: usize,
    /// Fits (the mean's and the replicates') that gave a shape without
    /// converging (`ShapeFit::converged`).
    pub unconverged: usize,
}

impl KernelFit {
    /// `max(1, chi2/dof)` of the mean fit: when the shape misfits the kernel
    /// (as the Particle Data Group does) the replicate spread alone would
    /// ignore that the parameters then depend on how the bins are weighted.
    pub fn scale(&self) -> f64 {
        self.mean.map_or(1.0, |f| f.chi2_per_dof.max(1.0))
    }

    /// Covariance of the means of two parameters over the replicate fits,
    /// times [`KernelFit::scale`]; NaN (not estimable) with fewer than two
    /// replicate fits or where it overflows (a replicate fit's parameter
    /// far out of range).
    pub fn covariance(&self, a: fn(&Shape) -> f64, b: fn(&Shape) -> f64) -> f64 {
        let count = self.replicates.len() as f64;
        if self.replicates.len() < 2 {
            return f64::NAN;
        }
        let mean = |f: fn(&Shape) -> f64| self.replicates.iter().map(f).sum::<f64>() / count;
        let (mean_a, mean_b) = (mean(a), mean(b));
        let sum: f64 = self
            .replicates
            .iter()
            .map(|s| (a(s) - mean_a) * (b(s) - mean_b))
            .sum();
        let covariance = self.scale() * (sum / ((count - 1.0) * count));
        if covariance.is_finite() {
            covariance
        } else {
            f64::NAN
        }
    }

    /// Standard error of one parameter.
    pub fn stderr(&self, parameter: fn(&Shape) -> f64) -> f64 {
        self.covariance(parameter, parameter).sqrt()
    }
}

/// Fits the shape to the per-replicate kernels `fine` (`G` per bin at bin
/// centres `offsets`) under `protocol`, in [`group_count`] log-spaced groups
/// of bins: the mean fit weighted by the protocol's errors of the group
/// means, and each replicate alone weighted by `sqrt(R)` times them.
pub fn fit_kernel(fine: &[Vec<f64>], offsets: &[f64], protocol: Protocol) -> KernelFit {
    let (low, high) = protocol.range;
    let groups = log_groups(offsets, low, high, group_count(protocol.range));
    let members: Vec<Vec<f64>> = groups
        .iter()
        .map(|g| g.iter().map(|&k| offsets[k]).collect())
        .collect();
    // Mean kernel over each group's bins, per replicate.
    let replicates: Vec<Vec<f64>> = fine
        .iter()
        .map(|kernel| {
            groups
                .iter()
                .map(|g| g.iter().map(|&k| kernel[k]).sum::<f64>() / g.len() as f64)
                .collect()
        })
        .collect();
    let estimates: Vec<Estimate> = (0..groups.len())
        .map(|j| Estimate::from_replicates(&replicates.iter().map(|r| r[j]).collect::<Vec<_>>()))
        .collect();
    let values: Vec<f64> = estimates.iter().map(|e| e.mean).collect();
    let statistical: Vec<f64> = estimates.iter().map(|e| e.stderr).collect();
    let measured = statistical.iter().filter(|&&e| e > 0.0).count();
    let errors = protocol.weighting.errors(&values, &statistical);
    let Some(mean) = fit_shape(&FitData {
        members: &members,
        values: &values,
        errors: &errors,
    }) else {
        return KernelFit {
            mean: None,
            replicates: Vec::new(),
            measured,
            unconverged: 0,
        };
    };
    let scale = (replicates.len() as f64).sqrt();
    let replicate_errors: Vec<f64> = errors.iter().map(|e| e * scale).collect();
    let fits: Vec<ShapeFit> = replicates
        .iter()
        .filter_map(|values| {
            fit_shape(&FitData {
                members: &members,
                values,
                errors: &replicate_errors,
            })
        })
        .collect();
    let unconverged = std::iter::once(&mean).chain(&fits);
    KernelFit {
        mean: Some(mean),
        replicates: fits
            .iter()
            .filter(|f| f.converged)
            .map(|f| f.shape)
            .collect(),
        measured,
        unconverged: unconverged.filter(|f| !f.converged).count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact data with noise-free values are fitted back to the generating shape.
    #[test]
    fn recovers_the_generating_shape() {
        let truth: Coordinates = [libm::log(2.0f64), 1.17, 1.0 / (0.02f64 * 0.02)];
        let offsets: Vec<f64> = (1..=400)
            .map(|k| f64::from(k) * 2.5e-4 * if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let members: Vec<Vec<f64>> = log_groups(&offsets, 1e-3, 0.08, 30)
            .into_iter()
            .map(|group| group.into_iter().map(|k| offsets[k]).collect())
            .collect();
        let values: Vec<f64> = members
            .iter()
            .map(|x| {
                let log = x.iter().map(|x| libm::log(x.abs())).collect();
                PointBins { x, log }.model(&truth)
            })
            .collect();
        let errors: Vec<f64> = values.iter().map(|v| 0.01 * v).collect();
        let data = FitData {
            members: &members,
            values: &values,
            errors: &errors,
        };
        let fit = fit_shape(&data).unwrap();
        assert!((fit.shape.alpha / 2.0 - 1.0).abs() < 1e-8, "{fit:?}");
        assert!((fit.shape.beta - 1.17).abs() < 1e-8, "{fit:?}");
        assert!((fit.shape.sigma / 0.02 - 1.0).abs() < 1e-8, "{fit:?}");
        assert!(fit.chi2_per_dof < 1e-10);
        assert!(fit.converged);
        // Points that all sit at |x| = 1, where the model does not depend on
        // beta (ln |x| = 0): the normal equations are singular at any
        // damping, and the iterations say they did not converge (the start
        // comes back).
        let one_place = vec![vec![1.0]; 5];
        let data = FitData {
            members: &one_place,
            values: &values[..5],
            errors: &errors[..5],
        };
        let start = [0.0, 1.0, 100.0];
        let points = PointBins::of(&data);
        assert_eq!(
            refine(&data, &points, &[0, 1, 2, 3, 4], start),
            (start, false)
        );
    }

    /// Replicates of a shape on bins of 5e-5 out to 0.1, each a multiple of
    /// `g` times `1 + distortion |x| / 0.01` (no noise in the shape itself).
    fn replicates_of(truth: &Coordinates, distortion: f64) -> (Vec<Vec<f64>>, Vec<f64>) {
        let offsets: Vec<f64> = (-2000..2000).map(|k| (f64::from(k) + 0.5) * 5e-5).collect();
        let fine = [0.98, 1.01, 0.99, 1.02]
            .iter()
            .map(|scale| {
                offsets
                    .iter()
                    .map(|&x| {
                        let g = model(truth, x, libm::log(x.abs()));
                        scale * g * (1.0 + distortion * x.abs() / 0.01)
                    })
                    .collect()
            })
            .collect();
        (fine, offsets)
    }

    fn systematics(fine: &[Vec<f64>], offsets: &[f64]) -> [f64; 3] {
        let fits: Vec<KernelFit> = varied_protocols()
            .into_iter()
            .map(|p| fit_kernel(fine, offsets, p))
            .collect();
        assert!(fits.iter().all(|f| f.mean.is_some()));
        [
            systematic(&fits, |s| s.alpha),
            systematic(&fits, |s| s.beta),
            systematic(&fits, |s| s.sigma),
        ]
    }

    /// An exact shape is the same under every protocol, so its systematic
    /// error vanishes; a shape the model misses (a linear factor in `|x|`)
    /// moves the parameters with the range and weights.
    #[test]
    fn only_a_misfitting_shape_has_a_systematic_error() {
        let truth: Coordinates = [libm::log(0.2f64), 1.1, 1.0 / (0.02f64 * 0.02)];
        let (fine, offsets) = replicates_of(&truth, 0.0);
        let [alpha, beta, sigma] = systematics(&fine, &offsets);
        assert!(
            alpha < 1e-9 * 0.2 && beta < 1e-9 && sigma < 1e-9 * 0.02,
            "{alpha} {beta} {sigma}"
        );
        let (fine, offsets) = replicates_of(&truth, 0.1);
        let [alpha, beta, sigma] = systematics(&fine, &offsets);
        assert!(
            alpha > 1e-3 * 0.2 && beta > 1e-3 && sigma > 1e-3 * 0.02,
            "{alpha} {beta} {sigma}"
        );
    }
}
