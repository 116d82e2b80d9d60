//! Statistics over independent Monte Carlo replicates (randomizations of the
//! collision events, runs of a ring): the mean and standard error of a
//! quantity measured once per replicate ([`Estimate`]), ratios with
//! first-order error propagation, the jackknife over leave-one-out replicate
//! sets for nonlinear functions of replicate means ([`Replicated`],
//! [`replicate_means`], [`jackknife`]), the chi-square of two estimate
//! vectors ([`chi_square`]), and that of a binned estimator of counts
//! against a reference with the covariance of its counts ([`CountModel`]).
//!
//! Owns the estimators only: what a replicate is (a histogram, a generator
//! matrix, a run's moments) and what is computed from it belong to `kernel`,
//! `evolve` and `analysis`. Pure math: no IO. Units are those of the
//! quantities estimated.

use std::ops::Range;

use rayon::prelude::*;

use crate::linalg::inverse_quadratic_form;

/// Mean and standard error over independent replicates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean over replicates.
    pub mean: f64,
    /// Standard error of the mean (sample standard deviation / sqrt(R)).
    pub stderr: f64,
}

impl Estimate {
    /// From one value per replicate (at least two): mean `sum v / R` and
    /// standard error `sqrt(sum (v - mean)^2 / ((R - 1) R))`.
    pub fn from_replicates(values: &[f64]) -> Estimate {
        let count = values.len() as f64;
        let mean = values.iter().sum::<f64>() / count;
        let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (count - 1.0);
        Estimate {
            mean,
            stderr: (variance / count).sqrt(),
        }
    }

    /// `self` times an exact `factor` (a unit or a known constant).
    pub fn scaled(self, factor: f64) -> Estimate {
        Estimate {
            mean: self.mean * factor,
            stderr: self.stderr * factor.abs(),
        }
    }

    /// `self / other`, with the two relative standard errors combined to
    /// first order (the two estimates treated as independent):
    /// `s_r = |r| hypot(s_a / a, s_b / b)`. A ratio without a finite value
    /// (`0/0`, `x/0`) has neither value nor error: NaN (a null in a table),
    /// written as `f64::NAN` because the sign of a product of two NaNs
    /// depends on the compiler's choice of operand order, and files must not.
    pub fn ratio(self, other: Estimate) -> Estimate {
        let quotient = self.mean / other.mean;
        let mean = if quotient.is_finite() {
            quotient
        } else {
            f64::NAN
        };
        let relative = libm::hypot(self.stderr / self.mean, other.stderr / other.mean);
        Estimate {
            mean,
            stderr: if mean.is_nan() {
                f64::NAN
            } else {
                mean.abs() * relative
            },
        }
    }

    /// The ratio of the means of two quantities measured on the same
    /// replicates (`numerator[k]`, `denominator[k]` from replicate `k`), with
    /// their correlation kept: `r = mean(a) / mean(b)`, its standard error
    /// that of the mean of the linearized residuals `(a_k - r b_k) / mean(b)`
    /// (first order, the delta method on the replicates). Equal to the
    /// independent [`Estimate::ratio`] only when the two are uncorrelated;
    /// `a_k = c b_k` gives `c` exactly, without error.
    pub fn paired_ratio(numerator: &[f64], denominator: &[f64]) -> Estimate {
        let a = Estimate::from_replicates(numerator).mean;
        let b = Estimate::from_replicates(denominator).mean;
        let mean = a / b;
        let residuals: Vec<f64> = numerator
            .iter()
            .zip(denominator)
            .map(|(x, y)| (x - mean * y) / b)
            .collect();
        Estimate {
            mean,
            stderr: Estimate::from_replicates(&residuals).stderr,
        }
    }

    /// `mean / stderr`: how many standard errors the mean lies from zero
    /// (NaN when both vanish, infinite for a nonzero mean without spread).
    pub fn z(self) -> f64 {
        self.mean / self.stderr
    }
}

/// A replicate's value as a flat list of numbers (a vector, a matrix), so that
/// means and leave-one-out means are one implementation for every shape.
pub trait Entries: Clone {
    /// The numbers.
    fn entries(&self) -> &[f64];

    /// The numbers, to change in place.
    fn entries_mut(&mut self) -> &mut [f64];

    /// Entry-wise sum of `all` (at least one), added in their order starting
    /// from the first.
    fn sum(all: &[Self]) -> Self {
        let mut sum = all[0].clone();
        for other in &all[1..] {
            for (a, b) in sum.entries_mut().iter_mut().zip(other.entries()) {
                *a += b;
            }
        }
        sum
    }

    /// `sum / count`: the mean of `count` replicates whose total is `sum`.
    fn mean(mut sum: Self, count: usize) -> Self {
        sum.entries_mut()
            .iter_mut()
            .for_each(|t| *t /= count as f64);
        sum
    }

    /// `(sum - self) / (count - 1)`: the mean of the other members when `sum`
    /// is the total of `count` replicates and `self` one of them.
    fn leave_out(&self, sum: &Self, count: usize) -> Self {
        let others = (count - 1) as f64;
        let mut mean = self.clone();
        for (own, total) in mean.entries_mut().iter_mut().zip(sum.entries()) {
            *own = (total - *own) / others;
        }
        mean
    }
}

impl Entries for Vec<f64> {
    fn entries(&self) -> &[f64] {
        self
    }

    fn entries_mut(&mut self) -> &mut [f64] {
        self
    }
}

/// A quantity evaluated on the mean of all replicates and on every
/// leave-one-out replicate set.
pub struct Replicated<T> {
    /// On all replicates.
    pub full: T,
    /// With each replicate left out.
    pub leave_one_out: Vec<T>,
}

/// The mean of `replicates` (at least two), [`Entries::mean`], and the means
/// with each one left out, `(sum - own) / (R - 1)`.
pub fn replicate_means<T: Entries>(replicates: &[T]) -> Replicated<T> {
    let count = replicates.len();
    let sum = T::sum(replicates);
    Replicated {
        leave_one_out: replicates
            .iter()
            .map(|own| own.leave_out(&sum, count))
            .collect(),
        full: T::mean(sum, count),
    }
}

impl<T: Sync> Replicated<T> {
    /// Applies `f` to every member, in parallel.
    pub fn map<U: Send>(&self, f: impl Fn(&T) -> U + Sync) -> Replicated<U> {
        Replicated {
            full: f(&self.full),
            leave_one_out: self.leave_one_out.par_iter().map(&f).collect(),
        }
    }

    /// Jackknife estimate of the scalar `f` of the member.
    pub fn scalar(&self, f: impl Fn(&T) -> f64) -> Estimate {
        let loo: Vec<[f64; 1]> = self.leave_one_out.iter().map(|x| [f(x)]).collect();
        jackknife(&[f(&self.full)], &loo)[0]
    }

    /// `f` of the members of `self` and `other` pairwise (the same replicate
    /// sets), in parallel.
    pub fn zip<U: Sync, V: Send>(
        &self,
        other: &Replicated<U>,
        f: impl Fn(&T, &U) -> V + Sync,
    ) -> Replicated<V> {
        Replicated {
            full: f(&self.full, &other.full),
            leave_one_out: self
                .leave_one_out
                .par_iter()
                .zip(&other.leave_one_out)
                .map(|(a, b)| f(a, b))
                .collect(),
        }
    }

    /// The largest scalar `f` of the full and every leave-one-out member.
    pub fn largest(&self, f: impl Fn(&T) -> f64) -> f64 {
        self.leave_one_out
            .iter()
            .map(&f)
            .fold(f(&self.full), f64::max)
    }
}

impl<T, E> Replicated<Result<T, E>> {
    /// Every member, or the first error (the full estimate's, then the
    /// leave-one-out members' in order).
    pub fn transpose(self) -> Result<Replicated<T>, E> {
        Ok(Replicated {
            full: self.full?,
            leave_one_out: self.leave_one_out.into_iter().collect::<Result<_, _>>()?,
        })
    }
}

impl<T: Entries> Replicated<T> {
    /// Jackknife estimates, entry by entry.
    pub fn values(&self) -> Vec<Estimate> {
        let loo: Vec<&[f64]> = self.leave_one_out.iter().map(Entries::entries).collect();
        jackknife(self.full.entries(), &loo)
    }
}

impl Replicated<Vec<Vec<f64>>> {
    /// Jackknife estimate of `f` of the state at time index `k`.
    pub fn estimate(&self, k: usize, f: impl Fn(&[f64]) -> f64) -> Estimate {
        self.scalar(|states| f(&states[k]))
    }

    /// Jackknife estimates of the state at time index `k`, node by node.
    pub fn states(&self, k: usize) -> Vec<Estimate> {
        let loo: Vec<&[f64]> = self.leave_one_out.iter().map(|s| s[k].as_slice()).collect();
        jackknife(&self.full[k], &loo)
    }
}

/// Jackknife estimates of a vector-valued function of `R` replicates, given
/// its value on all of them (`full`) and with each one left out
/// (`leave_one_out`): mean `full`, standard error
/// `sqrt((R - 1)/R sum_r (f_(-r) - mean_r f_(-r))^2)`. This is how the
/// uncertainty of a nonlinear function of replicate means (such as
/// `exp(t M)` of a mean generator) is carried.
pub fn jackknife<V: AsRef<[f64]>>(full: &[f64], leave_one_out: &[V]) -> Vec<Estimate> {
    let count = leave_one_out.len() as f64;
    full.iter()
        .enumerate()
        .map(|(i, &value)| {
            let mean = leave_one_out.iter().map(|v| v.as_ref()[i]).sum::<f64>() / count;
            let spread = leave_one_out
                .iter()
                .map(|v| (v.as_ref()[i] - mean).powi(2))
                .sum::<f64>();
            Estimate {
                mean: value,
                stderr: ((count - 1.0) / count * spread).sqrt(),
            }
        })
        .collect()
}

/// Jackknife covariance of quantities estimated on the same `R` replicate
/// sets: `leave_one_out[i][r]` is quantity `i` with replicate `r` left out;
/// entry `(i, j)`, row-major, is `(R - 1)/R sum_r (x_ir - mean_r x_ir) (x_jr
/// - mean_r x_jr)`. Its diagonal is the square of [`jackknife`]'s errors.
pub fn jackknife_covariance<V: AsRef<[f64]>>(leave_one_out: &[V]) -> Vec<f64> {
    let centred: Vec<Vec<f64>> = leave_one_out
        .iter()
        .map(|v| {
            let v = v.as_ref();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            v.iter().map(|x| x - mean).collect()
        })
        .collect();
    let count = centred.first().map_or(0, Vec::len) as f64;
    let mut covariance = Vec::with_capacity(centred.len() * centred.len());
    for a in &centred {
        for b in &centred {
            let product: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            covariance.push((count - 1.0) / count * product);
        }
    }
    covariance
}

/// The factor `(R - 1) / (R - p - 2)` by which a covariance of `p`
/// quantities estimated from `R` replicates is scaled so that its inverse is
/// unbiased (Hartlap, Simon & Schneider 2007, A&A 464, 399: the inverse of a
/// Wishart matrix with `R - 1` degrees of freedom overshoots by its
/// inverse); `None` when `R <= p + 2`, too few replicates for an
/// invertible estimate.
pub fn estimated_covariance_inflation(replicates: usize, quantities: usize) -> Option<f64> {
    (replicates > quantities + 2)
        .then(|| (replicates as f64 - 1.0) / (replicates - quantities - 2) as f64)
}

/// Chi-square of two estimate vectors and its degrees of freedom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChiSquare {
    /// `sum (a - b)^2 / (s_a^2 + s_b^2)`.
    pub chi2: f64,
    /// Entries summed.
    pub dof: usize,
}

impl ChiSquare {
    /// `chi2 / dof`: ~1 when the two agree within their errors.
    pub fn per_dof(self) -> f64 {
        self.chi2 / self.dof as f64
    }

    /// The p-value as a table or a note prints it: `no test` with fewer than
    /// [`MIN_TEST_DOF`] degrees of freedom (a test without power), the bound
    /// `< 1e-300` where the tail underflows to 0 (not `0.0e0`), three digits
    /// above 1e-3, and two significant digits below.
    pub fn p_text(self) -> String {
        if self.dof < MIN_TEST_DOF {
            format!("no test ({} degrees of freedom)", self.dof)
        } else {
            self.p_digits()
        }
    }

    /// The p-value's digits as [`ChiSquare::p_text`] writes them, whatever
    /// the degrees of freedom (a fit's chi-square with 1 or 2 rejects a law
    /// as well as any: `-` when there are none).
    pub fn p_digits(self) -> String {
        let p = self.p_value();
        if p.is_nan() {
            "-".into()
        } else if p == 0.0 {
            "< 1e-300".into()
        } else if p < 1e-3 {
            format!("{p:.1e}")
        } else {
            format!("{p:.3}")
        }
    }

    /// [`ChiSquare::p_text`] as a phrase of a note: `p = 0.440`,
    /// `p < 1e-300`, `no test (2 degrees of freedom)`.
    pub fn p_phrase(self) -> String {
        let text = self.p_text();
        match text.chars().next() {
            Some('<') => format!("p {text}"),
            Some(c) if c.is_ascii_digit() => format!("p = {text}"),
            _ => text,
        }
    }

    /// Probability that a chi-square variable with `dof` degrees of freedom
    /// is at least `chi2`: `Q(dof/2, chi2/2)`, the regularized upper
    /// incomplete gamma function. NaN without degrees of freedom.
    pub fn p_value(self) -> f64 {
        if self.dof == 0 || !self.chi2.is_finite() {
            return f64::NAN;
        }
        upper_regularized_gamma(0.5 * self.dof as f64, 0.5 * self.chi2.max(0.0))
    }
}

/// Expected count per group below which [`CountModel::chi_square`] merges
/// neighbours, so that the statistic follows its chi-square distribution:
/// Pearson's usual 5 leaves the p-values of a ring of 64 runs of ~4 tagged
/// lineages visibly non-uniform (Kolmogorov-Smirnov D = 0.013 over 20000
/// simulated sets), 10 does not (`physics::md`'s calibration test).
pub const MINIMUM_EXPECTED_COUNT: f64 = 10.0;

/// Fewest degrees of freedom of a chi-square test worth printing: with one
/// or two, a test has almost no power against a misfit (README: "no test").
pub const MIN_TEST_DOF: usize = 3;

/// One multinomial source of a binned estimator's counts: in each replicate,
/// objects fall into bin `k` with probability `p_k`, or beyond the bins with
/// `1 - sum p`, independently of each other and of other sources.
#[derive(Clone, Debug, PartialEq)]
pub struct Multinomial {
    /// `c` in the covariance `c (p_g delta_gh - p_g p_h)` that the source gives
    /// the estimator's masses (a mass: the estimate times the bin width,
    /// summed over a group of bins); `trials / (replicates * replicate trials)^2`
    /// summed, e.g. `sum_r 1 / L_r / R^2` for `L_r` objects per replicate, each
    /// counted as `1 / (R L_r)`.
    pub weight: f64,
    /// `p_k` of each bin.
    pub probabilities: Vec<f64>,
    /// Objects drawn over all replicates: `trials * p_k` is the source's
    /// expected count in bin `k`.
    pub trials: f64,
}

impl Multinomial {
    /// `p` summed over each group of bins.
    fn grouped(&self, groups: &[Range<usize>]) -> Vec<f64> {
        groups
            .iter()
            .map(|g| self.probabilities[g.clone()].iter().sum())
            .collect()
    }

    /// Expected count beyond the bins: `trials (1 - sum p)`, at least 0.
    fn beyond(&self) -> f64 {
        self.trials * (1.0 - self.probabilities.iter().sum::<f64>()).max(0.0)
    }
}

/// How a binned estimator scatters if the data followed a reference: the sum
/// of independent multinomial sources, and the counts behind each bin that
/// decide the grouping.
#[derive(Clone, Debug, PartialEq)]
pub struct CountModel {
    /// The sources of the counts.
    pub sources: Vec<Multinomial>,
    /// Expected counts behind each bin.
    pub expected: Vec<f64>,
}

impl CountModel {
    /// The model of `sources`, expecting `sum_m trials_m p_(m,k)` counts in bin `k`.
    pub fn new(sources: Vec<Multinomial>) -> CountModel {
        let bins = sources.first().map_or(0, |s| s.probabilities.len());
        let expected = (0..bins)
            .map(|k| sources.iter().map(|s| s.trials * s.probabilities[k]).sum())
            .collect();
        CountModel { sources, expected }
    }

    /// The difference of two independent estimators, `self` minus `other`:
    /// both models' sources; the fewer expected counts of the two per bin
    /// (the smaller sample decides whether a group is large enough).
    pub fn difference(&self, other: &CountModel) -> CountModel {
        CountModel {
            sources: self.sources.iter().chain(&other.sources).cloned().collect(),
            expected: self
                .expected
                .iter()
                .zip(&other.expected)
                .map(|(a, b)| a.min(*b))
                .collect(),
        }
    }

    /// Covariance of the group masses (row-major): `sum_m c_m (P_(m,g)
    /// delta_gh - P_(m,g) P_(m,h))`, `P_(m,g)` source `m`'s probability of
    /// group `g`.
    pub fn covariance(&self, groups: &[Range<usize>]) -> Vec<f64> {
        let n = groups.len();
        let mut covariance = vec![0.0; n * n];
        for source in &self.sources {
            let p = source.grouped(groups);
            for g in 0..n {
                covariance[g * n + g] += source.weight * p[g];
                for h in 0..n {
                    covariance[g * n + h] -= source.weight * p[g] * p[h];
                }
            }
        }
        covariance
    }

    /// Chi-square of the estimate `md` (per unit of `u`, bins of `width`)
    /// against `reference`, with the covariance the model gives `md` plus
    /// `reference`'s own variance (its standard errors, bins independent).
    ///
    /// Bins are grouped from the first on until a group expects at least
    /// `minimum` counts (a short last group joins the one before). The
    /// groups and everything beyond the bins partition each source's
    /// objects, so their masses sum to one per object and the complete
    /// covariance is singular: the cell with the most expected counts is left
    /// out, beyond the bins when that is it (the published estimator, whose
    /// thermal particles lie mostly outside the window), else the largest
    /// group together with everything beyond (the tagged estimator, whose
    /// lineages stay in the window). On the `G` groups kept, with `d_g =
    /// width sum_(k in g) (md_k - reference_k)`,
    ///
    /// ```text
    /// chi2 = d^T (C + S)^(-1) d,   dof = G,
    /// ```
    ///
    /// `C` the model's covariance of the group masses and `S` the diagonal of
    /// `width^2 sum_(k in g) s_k^2` of the reference. Asymptotically
    /// chi-square with `G` degrees of freedom (for one source, Pearson's
    /// statistic over the complete partition). NaN when `C + S` is not
    /// positive definite.
    pub fn chi_square(
        &self,
        md: &[Estimate],
        reference: &[Estimate],
        width: f64,
        minimum: f64,
    ) -> ChiSquare {
        let mut groups = expected_groups(&self.expected, minimum);
        let beyond: f64 = self.sources.iter().map(Multinomial::beyond).sum();
        let counts: Vec<f64> = groups
            .iter()
            .map(|g| self.expected[g.clone()].iter().sum())
            .collect();
        if let Some((largest, &count)) = counts.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))
            && count > beyond
        {
            groups.remove(largest);
        }
        let n = groups.len();
        let mut covariance = self.covariance(&groups);
        let difference: Vec<f64> = groups
            .iter()
            .enumerate()
            .map(|(g, range)| {
                let (mut sum, mut variance) = (0.0, 0.0);
                for (x, y) in md[range.clone()].iter().zip(&reference[range.clone()]) {
                    sum += x.mean - y.mean;
                    variance += y.stderr.powi(2);
                }
                covariance[g * n + g] += width * width * variance;
                width * sum
            })
            .collect();
        ChiSquare {
            chi2: inverse_quadratic_form(&covariance, &difference).unwrap_or(f64::NAN),
            dof: n,
        }
    }
}

/// Groups of adjacent bins: from the first bin on, bins join a group until
/// its `expected` count reaches `minimum`; a short last group joins the one
/// before (all bins in one group when none reaches it).
fn expected_groups(expected: &[f64], minimum: f64) -> Vec<Range<usize>> {
    let mut groups: Vec<Range<usize>> = Vec::new();
    let (mut start, mut count) = (0, 0.0);
    for (k, e) in expected.iter().enumerate() {
        count += e;
        if count >= minimum {
            groups.push(start..k + 1);
            (start, count) = (k + 1, 0.0);
        }
    }
    if start < expected.len() {
        match groups.last_mut() {
            Some(last) => last.end = expected.len(),
            None => groups.push(start..expected.len()),
        }
    }
    groups
}

/// The median of `values` (the mean of the middle two for an even count;
/// NaN when empty).
pub fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    match sorted.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => sorted[n / 2],
        n => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    }
}

/// Kolmogorov-Smirnov test of `values` (at least one) against the uniform
/// distribution on `[0, 1]`: the largest distance `D` between their
/// empirical distribution and the identity, and the probability of a larger
/// one, `Q_KS((sqrt n + 0.12 + 0.11 / sqrt n) D)` with `Q_KS(x) = 2
/// sum_(j >= 1) (-1)^(j-1) exp(-2 j^2 x^2)` (Stephens' approximation,
/// Numerical Recipes §14.3). For calibration tests: p-values of a correct
/// test are uniform.
#[cfg(test)]
pub(crate) fn kolmogorov_smirnov_uniform(values: &[f64]) -> (f64, f64) {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len() as f64;
    let distance = sorted
        .iter()
        .enumerate()
        .map(|(k, &v)| (v - k as f64 / n).max((k + 1) as f64 / n - v))
        .fold(0.0, f64::max);
    let root = n.sqrt();
    (
        distance,
        kolmogorov_tail((root + 0.12 + 0.11 / root) * distance),
    )
}

/// `Q_KS(x) = 2 sum_(j >= 1) (-1)^(j-1) exp(-2 j^2 x^2)`, summed until a
/// term is below `1e-10` of the sum; 1 where the series does not settle in
/// 100 terms (`x` below ~0.2, where `Q_KS` is 1 to 1e-15).
#[cfg(test)]
fn kolmogorov_tail(x: f64) -> f64 {
    let mut sum = 0.0;
    let mut sign = 2.0;
    for j in 1..=100 {
        let term = sign * libm::exp(-2.0 * f64::from(j * j) * x * x);
        sum += term;
        if term.abs() <= 1e-10 * sum.abs() {
            return sum.clamp(0.0, 1.0);
        }
        sign = -sign;
    }
    1.0
}

/// `Q(a, x) = Gamma(a, x) / Gamma(a)`: the series of `P = 1 - Q` below
/// `x = a + 1`, Lentz's continued fraction above (Numerical Recipes §6.2),
/// each to relative 1e-15. Hand-written because no admissible crate computes
/// `Q` itself to relative precision (docs/crates.md); `ln Gamma(a)` is
/// `libm::lgamma`.
fn upper_regularized_gamma(a: f64, x: f64) -> f64 {
    const EPSILON: f64 = 1e-15;
    const TINY: f64 = 1e-300;
    const MAX_TERMS: usize = 10_000;
    if x <= 0.0 {
        return 1.0;
    }
    let prefactor = libm::exp(a * libm::log(x) - x - libm::lgamma(a));
    if x < a + 1.0 {
        let (mut term, mut sum, mut denominator) = (1.0 / a, 1.0 / a, a);
        for _ in 0..MAX_TERMS {
            denominator += 1.0;
            term *= x / denominator;
            sum += term;
            if term.abs() < sum.abs() * EPSILON {
                break;
            }
        }
        return 1.0 - prefactor * sum;
    }
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut fraction = d;
    for k in 1..MAX_TERMS {
        let an = -(k as f64) * (k as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let step = d * c;
        fraction *= step;
        if (step - 1.0).abs() < EPSILON {
            break;
        }
    }
    prefactor * fraction
}

/// `chi2 = sum (a - b)^2 / (s_a^2 + s_b^2)` over the entries where `a` has a
/// nonzero error (an entry without an error estimate, e.g. a bin no run
/// reached, would have zero Gaussian error), and their number as `dof`.
pub fn chi_square(a: &[Estimate], b: &[Estimate]) -> ChiSquare {
    let (chi2, dof) =
        a.iter()
            .zip(b)
            .filter(|(x, _)| x.stderr > 0.0)
            .fold((0.0, 0), |(sum, count), (x, y)| {
                let variance = x.stderr.powi(2) + y.stderr.powi(2);
                (sum + (x.mean - y.mean).powi(2) / variance, count + 1)
            });
    ChiSquare { chi2, dof }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rounding of sums of a handful of O(1) numbers.
    const ROUNDING: f64 = 1e-14;

    /// Proportional replicates have an exact ratio; for a numerator that is
    /// the denominator plus a term uncorrelated with it, the error is that
    /// term's alone (worked by hand: residuals `d_k / mean(b)`).
    #[test]
    fn paired_ratio_keeps_the_replicates_correlation() {
        let b = [1.0, 2.0, 3.0, 4.0];
        let exact = Estimate::paired_ratio(&b.map(|x| 2.5 * x), &b);
        assert!((exact.mean - 2.5).abs() <= ROUNDING && exact.stderr <= ROUNDING);
        // d sums to zero and is orthogonal to b: mean(a) = mean(b), r = 1.
        let d = [0.1, -0.1, -0.1, 0.1];
        let a: Vec<f64> = b.iter().zip(d).map(|(x, e)| x + e).collect();
        let paired = Estimate::paired_ratio(&a, &b);
        let by_hand = Estimate::from_replicates(&d.map(|e| e / 2.5)).stderr;
        assert!((paired.mean - 1.0).abs() <= ROUNDING, "{paired:?}");
        assert!(
            (paired.stderr - by_hand).abs() <= ROUNDING,
            "{paired:?} vs {by_hand}"
        );
        let independent = Estimate::from_replicates(&a).ratio(Estimate::from_replicates(&b));
        assert!(paired.stderr < 0.2 * independent.stderr, "{independent:?}");
    }

    /// For means of `R` replicates, the jackknife covariance is the sample
    /// covariance over `R`, and its diagonal is [`jackknife`]'s squared
    /// errors. Drawn with unit covariance (`p = 4`, `R = 12`), a fresh mean's
    /// chi-square against the estimated covariance, inflated by
    /// [`estimated_covariance_inflation`], averages `p` over 4000 trials
    /// (within four of its standard errors); uninflated it overshoots by
    /// `(R - 1) / (R - p - 2) = 11/6`, by more than ten.
    #[test]
    fn jackknife_covariance_with_its_inflation_gives_calibrated_chi_squares() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(55);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let (p, r, trials) = (4, 12, 4000);
        let inflation = estimated_covariance_inflation(r, p).unwrap();
        assert_eq!(estimated_covariance_inflation(6, p), None);
        let mut inflated = Vec::new();
        for trial in 0..trials {
            let draws: Vec<Vec<f64>> = (0..p)
                .map(|_| (0..r).map(|_| noise.sample(&mut rng)).collect())
                .collect();
            let leave_one_out: Vec<Vec<f64>> = draws
                .iter()
                .map(|x| {
                    let sum: f64 = x.iter().sum();
                    x.iter().map(|own| (sum - own) / (r - 1) as f64).collect()
                })
                .collect();
            let covariance = jackknife_covariance(&leave_one_out);
            if trial == 0 {
                let full: Vec<f64> = draws
                    .iter()
                    .map(|x| x.iter().sum::<f64>() / r as f64)
                    .collect();
                let errors = jackknife(&full, &transpose(&leave_one_out));
                for (i, error) in errors.iter().enumerate() {
                    assert!((covariance[i * p + i] - error.stderr.powi(2)).abs() < ROUNDING);
                }
            }
            let fresh: Vec<f64> = (0..p)
                .map(|_| noise.sample(&mut rng) / (r as f64).sqrt())
                .collect();
            let chi2 = inverse_quadratic_form(&covariance, &fresh).unwrap();
            inflated.push(chi2 / inflation);
        }
        let mean = Estimate::from_replicates(&inflated);
        assert!((mean.mean - p as f64).abs() < 4.0 * mean.stderr, "{mean:?}");
        let raw = mean.scaled(inflation);
        assert!((raw.mean - p as f64).abs() > 10.0 * raw.stderr, "{raw:?}");
    }

    /// Rows of `columns` become columns.
    fn transpose(columns: &[Vec<f64>]) -> Vec<Vec<f64>> {
        (0..columns[0].len())
            .map(|r| columns.iter().map(|c| c[r]).collect())
            .collect()
    }

    /// For even `dof = 2m`, `Q(m, x) = exp(-x) sum_{j<m} x^j / j!` exactly:
    /// the p-value against that closed form on both sides of `x = a + 1`
    /// (series and continued fraction).
    #[test]
    fn p_value_of_even_degrees_of_freedom_is_the_closed_form() {
        for dof in [2usize, 4, 6, 10, 40] {
            for chi2 in [0.1, 1.0, 3.0, 10.0, 30.0, 80.0, 200.0] {
                let x: f64 = 0.5 * chi2;
                let mut term = 1.0;
                let mut sum = 0.0;
                for j in 0..dof / 2 {
                    if j > 0 {
                        term *= x / j as f64;
                    }
                    sum += term;
                }
                let exact = libm::exp(-x) * sum;
                let p = ChiSquare { chi2, dof }.p_value();
                assert!(
                    (p - exact).abs() <= 1e-12 * exact.max(1e-300) || (p - exact).abs() < 1e-300,
                    "dof {dof}, chi2 {chi2}: {p} != {exact}"
                );
            }
        }
    }

    /// One degree of freedom: `P(chi2 >= 1) = P(|z| >= 1) = 0.3173105078629141`
    /// (erfc(1/sqrt 2)).
    #[test]
    fn p_text_says_no_test_and_bounds_an_underflow() {
        assert_eq!(
            ChiSquare { chi2: 1.0, dof: 2 }.p_text(),
            "no test (2 degrees of freedom)"
        );
        assert_eq!(ChiSquare { chi2: 1e5, dof: 10 }.p_text(), "< 1e-300");
        assert_eq!(
            ChiSquare {
                chi2: 10.0,
                dof: 10
            }
            .p_text(),
            "0.440"
        );
        assert_eq!(
            ChiSquare {
                chi2: 40.0,
                dof: 10
            }
            .p_text(),
            "1.7e-5"
        );
        assert_eq!(ChiSquare { chi2: 1e5, dof: 10 }.p_phrase(), "p < 1e-300");
        assert_eq!(
            ChiSquare {
                chi2: 10.0,
                dof: 10
            }
            .p_phrase(),
            "p = 0.440"
        );
    }

    #[test]
    fn p_value_of_one_degree_of_freedom_is_the_normal_tail() {
        let p = ChiSquare { chi2: 1.0, dof: 1 }.p_value();
        assert!((p - 0.317_310_507_862_914_1).abs() < 1e-13, "{p}");
    }

    /// Expected counts 1, 2, 3, 10, 4, 0.5: groups {1, 2, 3} (6), {10},
    /// {4, 0.5} (a short last group joins the one before: {10, 4, 0.5});
    /// counts that never reach the minimum make one group.
    #[test]
    fn sparse_bins_are_grouped_until_the_expected_count_is_reached() {
        let expected = [1.0, 2.0, 3.0, 10.0, 4.0, 0.5];
        assert_eq!(expected_groups(&expected, 5.0), vec![0..3, 3..6]);
        assert_eq!(expected_groups(&[1.0, 1.0], 5.0), vec![0..2]);
    }

    /// Masses as estimates per unit of `u` on bins of `width`.
    fn densities(masses: &[f64], width: f64) -> Vec<Estimate> {
        masses
            .iter()
            .map(|m| Estimate {
                mean: m / width,
                stderr: 0.0,
            })
            .collect()
    }

    /// One source, `p = (0.1, 0.6, 0.2, 0.05)` and 0.05 beyond, 200 objects
    /// (expected 20, 120, 40, 10 and 10 beyond), `c = 0.01`: the largest bin
    /// is left out together with what lies beyond, and the statistic is
    /// Pearson's over the complete partition {0}, {2}, {3}, {1 and beyond}:
    /// masses `(0.12, 0.55, 0.21, 0.08)` differ by `(0.02, 0.01, 0.03)` and
    /// `-0.06` there, `chi2 = (0.02^2/0.1 + 0.01^2/0.2 + 0.03^2/0.05 +
    /// 0.06^2/0.65) / 0.01`, 3 degrees of freedom.
    #[test]
    fn leaving_out_the_largest_group_is_pearson_over_the_complete_partition() {
        let width = 0.5;
        let p = vec![0.1, 0.6, 0.2, 0.05];
        let model = CountModel::new(vec![Multinomial {
            weight: 0.01,
            probabilities: p.clone(),
            trials: 200.0,
        }]);
        let md = densities(&[0.12, 0.55, 0.21, 0.08], width);
        let chi = model.chi_square(&md, &densities(&p, width), width, 5.0);
        let pearson = (0.02f64.powi(2) / 0.1
            + 0.01f64.powi(2) / 0.2
            + 0.03f64.powi(2) / 0.05
            + 0.06f64.powi(2) / 0.65)
            / 0.01;
        assert_eq!(chi.dof, 3);
        assert!(
            (chi.chi2 / pearson - 1.0).abs() < 1e-12,
            "{} vs {pearson}",
            chi.chi2
        );
    }

    /// Thermal-like source: `p = (0.01, 0.02, 0.01)` of 1000 objects, 960
    /// expected beyond the bins: every group is kept, and the inverse of `c
    /// (P - p p^T)` is `(P^-1 + 1 1^T / (1 - sum p)) / c` (Sherman-Morrison).
    /// A reference variance adds to the diagonal: with a reference error
    /// making the single bin's variance twice the model's, chi2 halves.
    #[test]
    fn beyond_the_bins_is_left_out_when_it_expects_the_most() {
        let width = 0.1;
        let (p, c) = ([0.01, 0.02, 0.01], 0.002);
        let model = CountModel::new(vec![Multinomial {
            weight: c,
            probabilities: p.to_vec(),
            trials: 1000.0,
        }]);
        let d = [0.003, -0.001, 0.002];
        let md: Vec<f64> = p.iter().zip(&d).map(|(p, d)| p + d).collect();
        let chi = model.chi_square(&densities(&md, width), &densities(&p, width), width, 5.0);
        let sum: f64 = d.iter().sum();
        let expected = (d.iter().zip(&p).map(|(d, p)| d * d / p).sum::<f64>()
            + sum * sum / (1.0 - p.iter().sum::<f64>()))
            / c;
        assert_eq!(chi.dof, 3);
        assert!(
            (chi.chi2 / expected - 1.0).abs() < 1e-12,
            "{} vs {expected}",
            chi.chi2
        );

        let one = CountModel::new(vec![Multinomial {
            weight: c,
            probabilities: vec![0.01],
            trials: 1000.0,
        }]);
        let model_variance = c * 0.01 * 0.99;
        let reference = [Estimate {
            mean: 0.01 / width,
            stderr: model_variance.sqrt() / width,
        }];
        let alone = one.chi_square(
            &densities(&[0.013], width),
            &densities(&[0.01], width),
            width,
            5.0,
        );
        let both = one.chi_square(&densities(&[0.013], width), &reference, width, 5.0);
        assert!((both.chi2 / alone.chi2 - 0.5).abs() < 1e-12);
        assert!((alone.chi2 - 0.003f64.powi(2) / model_variance).abs() < 1e-9);
    }

    /// Two estimators' difference: the sources of both, and per bin the
    /// fewer expected counts.
    #[test]
    fn a_difference_has_both_sources_and_the_fewer_counts() {
        let source = |weight: f64, trials: f64| Multinomial {
            weight,
            probabilities: vec![0.5, 0.25],
            trials,
        };
        let a = CountModel::new(vec![source(0.1, 10.0)]);
        let b = CountModel::new(vec![source(0.2, 40.0)]);
        let both = a.difference(&b);
        assert_eq!(both.sources, vec![source(0.1, 10.0), source(0.2, 40.0)]);
        assert_eq!(both.expected, vec![5.0, 2.5]);
        let covariance = both.covariance(&[0..1, 1..2]);
        let c = 0.1 + 0.2;
        assert!((covariance[0] - c * 0.25).abs() < 1e-15);
        assert!((covariance[1] + c * 0.125).abs() < 1e-15);
    }

    /// `Q_KS(1) = 0.26999967167735456` (the series to convergence); evenly
    /// spread values are as uniform as `n` values can be (`D = 1 / 2n`, p
    /// ~1), their squares are not (`D = 1/4` at `u = 1/2`).
    #[test]
    fn kolmogorov_smirnov_tells_uniform_from_not() {
        assert!((kolmogorov_tail(1.0) - 0.269_999_671_677_354_56).abs() < 1e-12);
        let even: Vec<f64> = (0..1000).map(|k| (f64::from(k) + 0.5) / 1000.0).collect();
        let (distance, p) = kolmogorov_smirnov_uniform(&even);
        assert!(
            (distance - 0.0005).abs() < 1e-12 && p > 0.999,
            "{distance} {p}"
        );
        let squares: Vec<f64> = even.iter().map(|u| u * u).collect();
        let (distance, p) = kolmogorov_smirnov_uniform(&squares);
        assert!(
            (distance - 0.25).abs() < 2e-3 && p < 1e-50,
            "{distance} {p}"
        );
    }

    /// Mean 2.5 and sample variance 5/3 of 1..=4: standard error sqrt(5/12).
    #[test]
    fn standard_error_of_four_replicates_is_the_closed_form() {
        let estimate = Estimate::from_replicates(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(estimate.mean, 2.5);
        assert!((estimate.stderr - (5.0f64 / 12.0).sqrt()).abs() < ROUNDING);
    }

    /// `(6 +- 0.6) / (3 +- 0.4)`: relative errors 1/10 and 2/15 add in
    /// quadrature to 1/6 of the ratio 2.
    #[test]
    fn ratio_adds_relative_errors_in_quadrature() {
        let ratio = Estimate {
            mean: 6.0,
            stderr: 0.6,
        }
        .ratio(Estimate {
            mean: 3.0,
            stderr: 0.4,
        });
        assert_eq!(ratio.mean, 2.0);
        assert!((ratio.stderr - 2.0 / 6.0).abs() < ROUNDING);
    }

    /// For the mean of replicates the jackknife error is the usual standard error.
    #[test]
    fn jackknife_of_a_mean_is_the_standard_error() {
        let values = [1.0, 4.0, 2.5, 3.0, 7.0];
        let replicates: Vec<Vec<f64>> = values.iter().map(|&v| vec![v]).collect();
        let jack = replicate_means(&replicates).values()[0];
        let usual = Estimate::from_replicates(&values);
        assert!((jack.stderr - usual.stderr).abs() < ROUNDING);
        assert_eq!(jack.mean, usual.mean);
    }

    /// A linear statistic `3 x - 2 y` of replicate means: its jackknife error
    /// is the standard error of the per-replicate statistic.
    #[test]
    fn jackknife_of_a_linear_statistic_is_its_standard_error() {
        let replicates = vec![
            vec![1.0, 0.5],
            vec![2.0, -1.0],
            vec![0.5, 0.25],
            vec![3.0, 2.0],
        ];
        let linear = |v: &Vec<f64>| 3.0 * v[0] - 2.0 * v[1];
        let jack = replicate_means(&replicates).scalar(linear);
        let direct =
            Estimate::from_replicates(&replicates.iter().map(linear).collect::<Vec<f64>>());
        assert!((jack.mean - direct.mean).abs() < ROUNDING);
        assert!((jack.stderr - direct.stderr).abs() < ROUNDING);
    }

    /// The full mean and every leave-one-out mean of three vectors.
    #[test]
    fn replicate_means_leave_each_replicate_out() {
        let replicates = vec![vec![1.0, 10.0], vec![2.0, 20.0], vec![6.0, 60.0]];
        let means = replicate_means(&replicates);
        assert_eq!(means.full, vec![3.0, 30.0]);
        assert_eq!(
            means.leave_one_out,
            vec![vec![4.0, 40.0], vec![3.5, 35.0], vec![1.5, 15.0]]
        );
    }

    /// Identical vectors have chi-square 0; the degrees of freedom count only
    /// the entries of the first with a nonzero error.
    #[test]
    fn chi_square_of_identical_vectors_is_zero() {
        let a = [
            Estimate {
                mean: 1.0,
                stderr: 0.1,
            },
            Estimate {
                mean: 2.0,
                stderr: 0.0,
            },
            Estimate {
                mean: -3.0,
                stderr: 0.2,
            },
        ];
        assert_eq!(chi_square(&a, &a), ChiSquare { chi2: 0.0, dof: 2 });
    }

    /// `(1 +- 1)` against `(3 +- 1)`: difference 2, combined variance 2,
    /// chi-square 2 on one degree of freedom.
    #[test]
    fn chi_square_of_one_entry_is_its_squared_pull() {
        let a = Estimate {
            mean: 1.0,
            stderr: 1.0,
        };
        let b = Estimate {
            mean: 3.0,
            stderr: 1.0,
        };
        let chi = chi_square(&[a], &[b]);
        assert_eq!(chi, ChiSquare { chi2: 2.0, dof: 1 });
        assert_eq!(chi.per_dof(), 2.0);
    }
}
