//! A model of the kernel that fits to its errors (issue 59): on each side of
//! `u'`, `ln G` as a natural cubic spline in the warped distance
//! `t(x) = ln x + x / x_c` (`x = |u - u'|`, [`Warp`]), fitted to the
//! log-spaced groups of `kernel_log` (their means over the randomizations),
//! the number of knots chosen by cross-validation over the randomizations,
//! its goodness of fit calibrated by flipping the randomizations' signs.
//!
//! * **Shape.** Near `u'` the kernel is a power law `x^-beta`, a line in
//!   `t`; far out the cut-off `exp(-x^2 / 2 sigma^2)` is a parabola in `t`.
//!   Knots are uniform in `t` from the innermost group's inner edge to the
//!   outer edge of the outermost group measured to better than a third
//!   (`resolved`), `x_c = resolved / 4`; beyond the end knots the spline
//!   continues straight. The model's group value is its mean over the group,
//!   `(1 / width) int G dx` (8-point Gauss-Legendre), as the kernel's bins
//!   are means over their widths.
//! * **Weights.** `1 / var_g`, the variance of each group mean pooled with
//!   its two neighbours' (`pooled_variance`): with 8 randomizations a single
//!   group's variance is uncertain by half, which would make chi-square's
//!   spread twice that of known weights.
//! * **Knots.** From 2 to [`MAX_KNOTS`] (and fewer than the resolved
//!   groups): for each count, every randomization is left out in turn, the
//!   model fitted to the others and scored on it, `sum_g (Y_gr - m_g)^2 /
//!   (R var_g)`; the fewest knots within 1% of the best mean score win.
//!   The left-out fits of the chosen count give the knot values' jackknife
//!   covariance.
//! * **Goodness.** Groups share scenes (a slow launch feeds many; the
//!   near bins move together), so chi-square is not chi-square distributed on
//!   `groups - knots` degrees of freedom, and 8 randomizations cannot
//!   estimate a covariance of 55 groups. Its distribution under the model is
//!   drawn by the wild bootstrap over randomizations (Cameron, Gelbach &
//!   Miller, Rev. Econ. Stat. 90, 414 (2008)): each randomization's
//!   deviation from the fitted model `Y_r - m` is kept or flipped, `Y*_r = m
//!   + e_r (Y_r - m)`, for every sign pattern (all `2^R` for `R <= 12`, else
//!   4096 fixed ones), and the whole fit (weights included) is repeated. That
//!   keeps the groups' correlations, the weights' noise and any heavy tail
//!   the randomizations have. `chi2_expected` is the mean over the patterns
//!   (the `chi2/dof` a reader should compare with 1 is the ratio of the two),
//!   and `p` the share of patterns whose chi-square reaches the observed one
//!   (the identity counts: `p >= 1 / patterns`).

mod interpolation;
mod least_squares;
mod spline;

pub use interpolation::{
    FEWEST_NODES, Family, POTENTIAL_NODES, Replicated, SideCurve, U_PRIME_NODES, combine,
    combine_replicated, lagrange_weights, nearest_nodes, u_prime_nodes, without_farthest,
};
pub use least_squares::Knots;
pub use spline::{NaturalSpline, Warp};

use least_squares::{Design, Solution, least_squares, log_linear_start};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;

use crate::kernel::tail;

/// The most knots a side's model may take.
pub const MAX_KNOTS: usize = 16;

/// A group is resolved when its mean exceeds this many standard errors.
const RESOLVED_SIGNIFICANCE: f64 = 3.0;

/// Randomizations up to which every sign pattern is drawn.
const ALL_PATTERNS_UP_TO: usize = 12;

/// Sign patterns drawn above [`ALL_PATTERNS_UP_TO`] randomizations.
const DRAWN_PATTERNS: usize = 4096;

/// Seed of the drawn sign patterns.
const PATTERN_SEED: u64 = 59;

/// One side of `u'` on log-spaced groups, nearest `u'` first.
#[derive(Clone, Debug, PartialEq)]
pub struct SideGroups {
    /// Inner edge of each group, `|u - u'|` (`v_th`).
    pub lower: Vec<f64>,
    /// Outer edge of each group (`v_th`).
    pub upper: Vec<f64>,
    /// The group's mean kernel per randomization, `replicates[group][r]`
    /// (`rho^2 l v_th / v_th`).
    pub replicates: Vec<Vec<f64>>,
}

impl SideGroups {
    fn randomizations(&self) -> usize {
        self.replicates.first().map_or(0, Vec::len)
    }

    /// Mean over randomizations of each group.
    fn mean(&self) -> Vec<f64> {
        let count = self.randomizations() as f64;
        self.replicates
            .iter()
            .map(|row| row.iter().sum::<f64>() / count)
            .collect()
    }

    /// The variance of each group's mean, `s^2 / R`, averaged with its
    /// neighbours' on either side.
    fn pooled_variance(&self) -> Vec<f64> {
        let count = self.randomizations() as f64;
        let variance: Vec<f64> = self
            .replicates
            .iter()
            .map(|row| {
                let mean = row.iter().sum::<f64>() / count;
                row.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / ((count - 1.0) * count)
            })
            .collect();
        let last = variance.len().saturating_sub(1);
        (0..variance.len())
            .map(|g| {
                let window = &variance[g.saturating_sub(1)..=(g + 1).min(last)];
                window.iter().sum::<f64>() / window.len() as f64
            })
            .collect()
    }

    /// The groups whose pooled variance is positive: a group with no spread
    /// around it (no events in any randomization near it) has no error to
    /// fit to.
    fn with_spread(&self) -> SideGroups {
        let variance = self.pooled_variance();
        let keep: Vec<usize> = (0..variance.len()).filter(|&g| variance[g] > 0.0).collect();
        SideGroups {
            lower: keep.iter().map(|&g| self.lower[g]).collect(),
            upper: keep.iter().map(|&g| self.upper[g]).collect(),
            replicates: keep.iter().map(|&g| self.replicates[g].clone()).collect(),
        }
    }

    /// The groups without randomization `left_out`.
    fn without(&self, left_out: usize) -> SideGroups {
        let replicates = self
            .replicates
            .iter()
            .map(|row| {
                row.iter()
                    .enumerate()
                    .filter(|&(r, _)| r != left_out)
                    .map(|(_, &v)| v)
                    .collect()
            })
            .collect();
        SideGroups {
            replicates,
            ..self.clone()
        }
    }

    /// `m_g + e_r (Y_gr - m_g)`: each randomization's deviation from `model`
    /// kept (`+1`) or flipped (`-1`).
    fn flipped(&self, model: &[f64], signs: &[f64]) -> SideGroups {
        let replicates = self
            .replicates
            .iter()
            .zip(model)
            .map(|(row, m)| {
                row.iter()
                    .zip(signs)
                    .map(|(v, e)| m + e * (v - m))
                    .collect()
            })
            .collect();
        SideGroups {
            replicates,
            ..self.clone()
        }
    }
}

/// The fit's weights: `1 / var` of each group's pooled variance (0 where
/// there is no spread).
fn inverse_variances(variance: &[f64]) -> Vec<f64> {
    variance
        .iter()
        .map(|&v| if v > 0.0 { 1.0 / v } else { 0.0 })
        .collect()
}

/// The kernel's fine bins (`fine[r][bin]`, bin centres `centres` relative to
/// `u'`, width `bin_width`, `v_th`) on the log-spaced groups of
/// `kernel_log` ([`tail::sided_log_groups`]): below `u'`, then above.
pub fn side_groups(fine: &[Vec<f64>], centres: &[f64], bin_width: f64) -> [SideGroups; 2] {
    let groups = tail::sided_log_groups(centres);
    [-1.0, 1.0].map(|side| {
        let mut members: Vec<&Vec<usize>> = groups
            .iter()
            .filter(|(s, _)| *s == side)
            .map(|(_, members)| members)
            .collect();
        members.sort_by(|a, b| (side * centres[a[0]]).total_cmp(&(side * centres[b[0]])));
        let distance = |k: usize| side * centres[k];
        SideGroups {
            lower: members
                .iter()
                .map(|m| distance(m[0]) - 0.5 * bin_width)
                .collect(),
            upper: members
                .iter()
                .map(|m| distance(m[m.len() - 1]) + 0.5 * bin_width)
                .collect(),
            replicates: members
                .iter()
                .map(|m| {
                    fine.iter()
                        .map(|kernel| m.iter().map(|&k| kernel[k]).sum::<f64>() / m.len() as f64)
                        .collect()
                })
                .collect(),
        }
    })
}

/// The side of `u'` a model describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// `u < u'`.
    Below,
    /// `u > u'`.
    Above,
}

impl Side {
    /// The sign of `u - u'` on this side.
    pub fn sign(self) -> f64 {
        match self {
            Side::Below => -1.0,
            Side::Above => 1.0,
        }
    }

    /// `below` or `above`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Below => "below",
            Side::Above => "above",
        }
    }
}

/// The part of the kernel a model describes (physics.md §3): the whole
/// kernel `G`, or its self part `G_self` (the special particle's own
/// velocity). The bath part, `G - G_self`, changes sign and is zero within
/// its errors in most groups: it is the difference of the two models,
/// jackknifed over the randomizations they share.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// `G`, self plus bath.
    Total,
    /// `G_self`.
    SelfPart,
}

impl Part {
    /// Every part a kernel's model describes, the whole first.
    pub const MODELLED: [Part; 2] = [Part::Total, Part::SelfPart];

    /// `total` or `self`.
    pub fn name(self) -> &'static str {
        match self {
            Part::Total => "total",
            Part::SelfPart => "self",
        }
    }
}

/// One group as the model's fit saw it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupFit {
    /// Inner edge, `|u - u'|` (`v_th`).
    pub lower: f64,
    /// Outer edge (`v_th`).
    pub upper: f64,
    /// The group's mean kernel over the randomizations
    /// (`rho^2 l v_th / v_th`).
    pub mean: f64,
    /// The standard error its weight is made of: the pooled variance's root.
    pub stderr: f64,
    /// The model's mean over the group.
    pub model: f64,
}

impl GroupFit {
    /// `(mean - model) / stderr`: the group's share of chi-square is its
    /// square.
    pub fn residual(&self) -> f64 {
        (self.mean - self.model) / self.stderr
    }
}

/// The fitted model of one side.
#[derive(Clone, Debug, PartialEq)]
pub struct SideModel {
    /// The knots.
    pub knots: Knots,
    /// `ln G` at the knots (`G` in `rho^2 l v_th / v_th`).
    pub values: Vec<f64>,
    /// Jackknife covariance of `values` over the randomizations, row-major.
    pub covariance: Vec<f64>,
    /// The knot values fitted without each randomization in turn (the
    /// covariance's source; paired across kernels of the same scenes).
    pub left_out: Vec<Vec<f64>>,
    /// Weighted residual sum of squares of the fit to the mean groups.
    pub chi2: f64,
    /// The groups fitted, nearest `u'` first.
    pub groups: Vec<GroupFit>,
    /// Whether the fit to the mean groups converged.
    pub converged: bool,
}

impl SideModel {
    /// `ln G` at distance `x > 0` from `u'`.
    pub fn ln_g(&self, x: f64) -> f64 {
        self.knots.ln_g(&self.values, x)
    }

    /// Standard error of [`SideModel::ln_g`].
    pub fn ln_g_stderr(&self, x: f64) -> f64 {
        self.knots.ln_g_stderr(&self.covariance, x)
    }
}

/// The goodness of fit of a kernel's model, both sides together.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Goodness {
    /// Weighted residual sum of squares, every side.
    pub chi2: f64,
    /// Its mean over the sign patterns: what a model that follows the kernel
    /// gives.
    pub expected: f64,
    /// Its standard deviation over the sign patterns.
    pub spread: f64,
    /// Groups minus knots.
    pub dof: usize,
    /// Share of sign patterns whose chi-square reaches `chi2`.
    pub p_value: f64,
    /// Sign patterns drawn.
    pub patterns: usize,
}

/// A kernel's model.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelModel {
    /// Each side's model: below `u'` then above; only `Above` when
    /// `mirrored`.
    pub sides: Vec<(Side, SideModel)>,
    /// The two sides are one measurement (`G(u' - x) = G(u' + x)` to
    /// rounding in every randomization: the mirror images at `u' = 0`), so
    /// one model describes both.
    pub mirrored: bool,
    /// Goodness of fit.
    pub goodness: Goodness,
}

impl KernelModel {
    /// The model of each side, below `u'` then above: a mirrored kernel's
    /// one model stands for both.
    pub fn both_sides(&self) -> Vec<(Side, &SideModel)> {
        if self.mirrored {
            let above = &self.sides[0].1;
            vec![(Side::Below, above), (Side::Above, above)]
        } else {
            self.sides
                .iter()
                .map(|(side, model)| (*side, model))
                .collect()
        }
    }
}

impl NoModel {
    /// Why, for a table's status column.
    pub fn reason(self) -> &'static str {
        match self {
            NoModel::TooFewRandomizations => {
                "fewer than three randomizations: no errors to fit to once one is left out"
            }
            NoModel::Unresolved => {
                "a side has fewer than three groups measured to better than a third"
            }
            NoModel::NoFit => "no fit could start (singular normal equations)",
        }
    }
}

/// Why a kernel has no model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoModel {
    /// Fewer than three randomizations: no errors to fit to once one is left
    /// out.
    TooFewRandomizations,
    /// A side has fewer than three groups measured to better than a third
    /// (the kernel vanishes, as at n = 2, or is noise).
    Unresolved,
    /// No fit could start (singular normal equations).
    NoFit,
}

/// The model of a kernel from its two sides' groups ([`side_groups`]).
pub fn fit_kernel_model(below: SideGroups, above: SideGroups) -> Result<KernelModel, NoModel> {
    if above.randomizations() < 3 {
        return Err(NoModel::TooFewRandomizations);
    }
    let mirrored = mirror_images(&below, &above);
    let sides: Vec<(Side, SideGroups)> = if mirrored {
        vec![(Side::Above, above.with_spread())]
    } else {
        vec![
            (Side::Below, below.with_spread()),
            (Side::Above, above.with_spread()),
        ]
    };
    let fitted: Vec<Fitted> = sides
        .iter()
        .map(|(_, groups)| fit_side(groups))
        .collect::<Result<_, _>>()?;
    let goodness = sign_flip_test(&sides, &fitted);
    Ok(KernelModel {
        sides: sides
            .iter()
            .zip(fitted)
            .map(|((side, _), f)| (*side, f.model))
            .collect(),
        mirrored,
        goodness,
    })
}

/// Whether the two sides hold the same values in every randomization, to
/// 1e-9 of the largest.
fn mirror_images(below: &SideGroups, above: &SideGroups) -> bool {
    let largest = above
        .replicates
        .iter()
        .flatten()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    below.replicates.len() == above.replicates.len()
        && below
            .replicates
            .iter()
            .flatten()
            .zip(above.replicates.iter().flatten())
            .all(|(b, a)| (b - a).abs() <= 1e-9 * largest)
}

/// A side's model with what its goodness test reuses.
struct Fitted {
    model: SideModel,
    design: Design,
    means: Vec<f64>,
}

/// The side's knots by cross-validation, its fit and the jackknife covariance.
fn fit_side(groups: &SideGroups) -> Result<Fitted, NoModel> {
    let mean = groups.mean();
    let variance = groups.pooled_variance();
    let weights = inverse_variances(&variance);
    let resolved: Vec<usize> = (0..mean.len())
        .filter(|&g| mean[g] > RESOLVED_SIGNIFICANCE * variance[g].sqrt())
        .collect();
    let Some(&outermost) = resolved.last().filter(|_| resolved.len() >= 3) else {
        return Err(NoModel::Unresolved);
    };
    let (first, edge) = (groups.lower[0], groups.upper[outermost]);
    let most = MAX_KNOTS.min(resolved.len() - 1).max(2);
    let candidates: Vec<Candidate> = (2..=most)
        .map(|count| Candidate::scored(groups, Knots::uniform(first, edge, count), &weights))
        .collect();
    let best = candidates
        .iter()
        .map(|c| c.score)
        .fold(f64::INFINITY, f64::min);
    let chosen = candidates
        .into_iter()
        .find(|c| best.is_finite() && c.score <= 1.01 * best)
        .ok_or(NoModel::NoFit)?;
    let design = Design::new(&chosen.knots, &groups.lower, &groups.upper);
    let fit = fit_groups(&design, &chosen.knots, groups).ok_or(NoModel::NoFit)?;
    let fitted = (0..mean.len())
        .map(|g| GroupFit {
            lower: groups.lower[g],
            upper: groups.upper[g],
            mean: mean[g],
            stderr: variance[g].sqrt(),
            model: fit.means[g],
        })
        .collect();
    let model = SideModel {
        covariance: jackknife_covariance(&chosen.left_out),
        left_out: chosen.left_out,
        values: fit.values,
        chi2: fit.chi2,
        groups: fitted,
        converged: fit.converged,
        knots: chosen.knots,
    };
    Ok(Fitted {
        model,
        design,
        means: fit.means,
    })
}

/// A knot count and its cross-validated score.
struct Candidate {
    knots: Knots,
    /// `sum_r sum_g (Y_gr - m^(-r)_g)^2 / (R var_g)`, infinite when a fit
    /// failed.
    score: f64,
    /// Knot values fitted without each randomization.
    left_out: Vec<Vec<f64>>,
}

impl Candidate {
    /// `weights`: the full data's, which score every left-out randomization.
    fn scored(groups: &SideGroups, knots: Knots, weights: &[f64]) -> Candidate {
        let design = Design::new(&knots, &groups.lower, &groups.upper);
        let count = groups.randomizations();
        let mut score = 0.0;
        let mut left_out = Vec::with_capacity(count);
        for r in 0..count {
            let Some(fit) = fit_groups(&design, &knots, &groups.without(r)) else {
                score = f64::INFINITY;
                break;
            };
            score += groups
                .replicates
                .iter()
                .zip(&fit.means)
                .zip(weights)
                .map(|((row, m), w)| w * (row[r] - m) * (row[r] - m) / count as f64)
                .sum::<f64>();
            left_out.push(fit.values);
        }
        Candidate {
            knots,
            score: score / count as f64,
            left_out,
        }
    }
}

/// The model fitted to the groups' means with pooled-variance weights, from
/// the log-linear start.
fn fit_groups(design: &Design, knots: &Knots, groups: &SideGroups) -> Option<Solution> {
    let (mean, variance) = (groups.mean(), groups.pooled_variance());
    let start = log_linear_start(knots, (&groups.lower, &groups.upper), &mean, &variance)?;
    Some(least_squares(
        design,
        &mean,
        &inverse_variances(&variance),
        &start,
    ))
}

/// `(R - 1) / R sum_r (c_r - c_bar)(c_r - c_bar)^T` of the leave-one-out fits.
fn jackknife_covariance(left_out: &[Vec<f64>]) -> Vec<f64> {
    let count = left_out.len() as f64;
    let size = left_out.first().map_or(0, Vec::len);
    let centre: Vec<f64> = (0..size)
        .map(|k| left_out.iter().map(|c| c[k]).sum::<f64>() / count)
        .collect();
    let mut covariance = vec![0.0; size * size];
    for c in left_out {
        for i in 0..size {
            for j in 0..size {
                covariance[i * size + j] +=
                    (count - 1.0) / count * (c[i] - centre[i]) * (c[j] - centre[j]);
            }
        }
    }
    covariance
}

/// The wild-bootstrap test of the fitted sides (module docs).
fn sign_flip_test(sides: &[(Side, SideGroups)], fitted: &[Fitted]) -> Goodness {
    let patterns = sign_patterns(sides[0].1.randomizations());
    let null: Vec<f64> = patterns
        .par_iter()
        .map(|signs| {
            sides
                .iter()
                .zip(fitted)
                .map(|((_, groups), f)| refit_chi2(f, &groups.flipped(&f.means, signs)))
                .sum()
        })
        .collect();
    let chi2: f64 = fitted.iter().map(|f| f.model.chi2).sum();
    let reached = null[1..].iter().filter(|&&q| q >= chi2).count();
    let expected = null.iter().sum::<f64>() / null.len() as f64;
    let variance = null
        .iter()
        .map(|q| (q - expected) * (q - expected))
        .sum::<f64>()
        / null.len() as f64;
    Goodness {
        chi2,
        expected,
        spread: variance.sqrt(),
        dof: fitted
            .iter()
            .map(|f| f.model.groups.len() - f.model.values.len())
            .sum(),
        p_value: (1 + reached) as f64 / null.len() as f64,
        patterns: null.len(),
    }
}

/// Chi-square of the side's model refitted to `groups` (from its fitted
/// values, with the groups' own pooled weights).
fn refit_chi2(fitted: &Fitted, groups: &SideGroups) -> f64 {
    least_squares(
        &fitted.design,
        &groups.mean(),
        &inverse_variances(&groups.pooled_variance()),
        &fitted.model.values,
    )
    .chi2
}

/// The sign patterns: every one (the bits of `j`) up to
/// [`ALL_PATTERNS_UP_TO`] randomizations, else [`DRAWN_PATTERNS`] drawn from
/// a fixed seed; pattern 0 keeps every sign (the data).
fn sign_patterns(randomizations: usize) -> Vec<Vec<f64>> {
    let sign = |flip: bool| if flip { -1.0 } else { 1.0 };
    if randomizations <= ALL_PATTERNS_UP_TO {
        return (0..1usize << randomizations)
            .map(|j| {
                (0..randomizations)
                    .map(|r| sign((j >> r) & 1 == 1))
                    .collect()
            })
            .collect();
    }
    let mut rng = StdRng::seed_from_u64(PATTERN_SEED);
    std::iter::once(vec![1.0; randomizations])
        .chain(
            (1..DRAWN_PATTERNS).map(|_| (0..randomizations).map(|_| sign(rng.random())).collect()),
        )
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::{Distribution, Normal};

    /// The paper's shape, `0.2 x^-1.12 exp(-x^2 / 2 (0.02)^2)`.
    fn kernel(x: f64) -> f64 {
        0.2 * libm::pow(x, -1.12) * libm::exp(-x * x / (2.0 * 0.02 * 0.02))
    }

    const WIDTH: f64 = 5e-5;

    /// Fine bins of width 5e-5 out to 0.1 on both sides, each the kernel's
    /// mean over its bin (`dip` scales the bins in `[1.95e-3, 2.25e-3]`), in
    /// `randomizations` randomizations with 1% independent noise per bin and
    /// an absolute floor of 0.01, the same on both sides when `mirrored`.
    fn bins(dip: f64, mirrored: bool, randomizations: usize) -> (Vec<Vec<f64>>, Vec<f64>) {
        let centres: Vec<f64> = (-2000..=2000).map(|k| f64::from(k) * WIDTH).collect();
        let mean = |c: f64| {
            let x = c.abs();
            let scale = if (1.95e-3..2.25e-3).contains(&x) {
                dip
            } else {
                1.0
            };
            let pieces = 64;
            scale
                * (0..pieces)
                    .map(|i| kernel(x - 0.5 * WIDTH + (f64::from(i) + 0.5) * WIDTH / 64.0))
                    .sum::<f64>()
                / f64::from(pieces)
        };
        let truth: Vec<f64> = centres
            .iter()
            .map(|&c| if c == 0.0 { 0.0 } else { mean(c) })
            .collect();
        let mut rng = StdRng::seed_from_u64(59);
        let normal = Normal::new(0.0, 1.0).expect("a unit normal");
        let fine = (0..randomizations)
            .map(|_| {
                let noise: Vec<f64> = (0..=2000).map(|_| normal.sample(&mut rng)).collect();
                let other: Vec<f64> = (0..=2000).map(|_| normal.sample(&mut rng)).collect();
                truth
                    .iter()
                    .enumerate()
                    .map(|(k, g)| {
                        let (index, above) = (k.abs_diff(2000), k >= 2000);
                        let z = if above || mirrored {
                            noise[index]
                        } else {
                            other[index]
                        };
                        g * (1.0 + 0.01 * z) + 0.01 * z
                    })
                    .collect()
            })
            .collect();
        (fine, centres)
    }

    fn model_of(dip: f64, mirrored: bool, randomizations: usize) -> Result<KernelModel, NoModel> {
        let (fine, centres) = bins(dip, mirrored, randomizations);
        let [below, above] = side_groups(&fine, &centres, WIDTH);
        fit_kernel_model(below, above)
    }

    /// Data drawn from a smooth kernel: the model passes its own test, its
    /// residuals make its chi-square, and it recovers the kernel within its
    /// errors where it is resolved.
    #[test]
    fn model_follows_a_smooth_kernel_within_its_errors() {
        let model = model_of(1.0, false, 8).expect("a model");
        assert!(!model.mirrored);
        let test = model.goodness;
        assert_eq!(test.patterns, 256);
        assert!(test.p_value > 0.01, "{test:?}");
        let ratio = test.chi2 / test.expected;
        assert!((0.5..2.0).contains(&ratio), "chi2 / expected {ratio}");
        let residuals: f64 = model
            .sides
            .iter()
            .flat_map(|(_, side)| side.groups.iter().map(|g| g.residual() * g.residual()))
            .sum();
        assert!((residuals / test.chi2 - 1.0).abs() < 1e-12);
        for (_, side) in &model.sides {
            for x in [1e-4, 1e-3, 5e-3, 0.02, 0.04] {
                let z = (side.ln_g(x) - libm::log(kernel(x))) / side.ln_g_stderr(x);
                assert!(z.abs() < 4.0, "x = {x}: z = {z}");
            }
        }
    }

    /// A 3% dip in two groups near 2e-3, thirty of their errors, is
    /// rejected: the test has power against what a smooth curve cannot follow.
    #[test]
    fn model_test_rejects_a_dip_it_cannot_follow() {
        let test = model_of(0.97, false, 8).expect("a model").goodness;
        assert!(test.p_value < 0.01, "{test:?}");
        assert!(test.chi2 > 3.0 * test.expected, "{test:?}");
    }

    /// Sides equal in every randomization are one measurement: one model.
    #[test]
    fn mirror_images_take_one_model() {
        let model = model_of(1.0, true, 8).expect("a model");
        assert!(model.mirrored);
        assert_eq!(model.sides.len(), 1);
        assert_eq!(model.sides[0].0, Side::Above);
        assert_eq!(model.both_sides().len(), 2);
    }

    /// Two randomizations cannot leave one out: no model, and why.
    #[test]
    fn two_randomizations_give_no_model() {
        assert_eq!(
            model_of(1.0, false, 2).err(),
            Some(NoModel::TooFewRandomizations)
        );
    }

    /// Every sign pattern up to 12 randomizations, the data's first; beyond,
    /// 4096 drawn from a fixed seed, the same each time.
    #[test]
    fn sign_patterns_enumerate_then_draw() {
        let eight = sign_patterns(8);
        assert_eq!(eight.len(), 256);
        assert!(eight[0].iter().all(|&e| e == 1.0));
        let distinct: std::collections::BTreeSet<Vec<i8>> = eight
            .iter()
            .map(|p| p.iter().map(|&e| e as i8).collect())
            .collect();
        assert_eq!(distinct.len(), 256);
        let drawn = sign_patterns(24);
        assert_eq!(drawn.len(), DRAWN_PATTERNS);
        assert!(drawn[0].iter().all(|&e| e == 1.0));
        assert_eq!(drawn, sign_patterns(24));
    }
}
