//! The special particle's kernel against relaxation to `f0` (physics.md §3,
//! §8): its drift and variance rates per replicate, the Fokker-Planck
//! stationarity of `f0` under them, and detailed balance of the self kernel
//! between two velocities. Every uncertainty is the spread of per-replicate
//! values (differences taken replicate by replicate, so the correlation of
//! quantities from the same events is kept).
//!
//! Fokker-Planck reading: with drift `D1(u)` and variance rate `D2(u)`, zero
//! probability flux in the state `f0` requires `D1 f0 = 1/2 d(D2 f0)/du`, i.e.
//! `D1 = (D2' - u D2) / 2`. Higher Kramers-Moyal terms (third moment of kicks
//! of ~0.02 v_th) are not included, so differences of a few percent of `D1`
//! are expected.
//!
//! Owns the arithmetic of the checks, not the choice of grid, separations or
//! bins (the `sweep` stage's parameters). Units: rates in `rho^2 l v_th`,
//! velocities in `v_th`.

use super::{Draws, Event, Target, moments, self_bin};
use crate::binning::Bins;
use crate::linalg::spline_slopes;
use crate::physics::launch::thermal_density;
use crate::stats::Estimate;
use crate::thresholds::DOMINATED_SHARE;

/// Self drift `D1 = d<u - u'>/dt` and variance rate `D2 = d<(u - u')^2>/dt`
/// of the special particle at one `u'`, kicks within a truncation, one value
/// per replicate, `rho^2 l v_th`.
#[derive(Clone, Debug, PartialEq)]
pub struct SelfRates {
    /// `D1` per replicate.
    pub drift: Vec<f64>,
    /// `D2` per replicate (`a_n` at `u' = 0` in the dilute limit).
    pub variance: Vec<f64>,
}

/// The special particle's rates at `target`, counting kicks `|u - u'| <= truncation`.
pub fn self_rates(events: &[Event], target: &Target, truncation: f64, draws: &Draws) -> SelfRates {
    let sums = moments(events, target, &[truncation], draws);
    SelfRates {
        drift: sums.iter().map(|r| r[0].self_drift).collect(),
        variance: sums.iter().map(|r| r[0].self_variance).collect(),
    }
}

/// The Fokker-Planck check at one grid point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FokkerPlanckPoint {
    /// Measured drift `D1`.
    pub drift: Estimate,
    /// Measured variance rate `D2`.
    pub variance: Estimate,
    /// `(D2' - u D2) / 2`: the drift for which `f0` is stationary.
    pub predicted_drift: Estimate,
    /// `(D1 - predicted) / its standard error`, per-replicate differences.
    pub z: f64,
}

/// The Fokker-Planck check at every point of `grid` (ascending `u'`, at least
/// three points), `rates[k]` measured at `grid[k]`: `D2'` per replicate from
/// the not-a-knot cubic spline through that replicate's `D2` on the whole
/// grid ([`spline_slopes`]), so the replicates' spread carries the
/// derivative's noise. On the default grid (step 0.25) its truncation error is
/// below a tenth of the statistical error everywhere; central differences,
/// `O(h^2 D2''' / 6)`, reached 4.5 times it at `u' = -0.25` for n = 6.
pub fn fokker_planck_check(grid: &[f64], rates: &[SelfRates]) -> Vec<FokkerPlanckPoint> {
    let predicted = stationary_drifts(grid, rates);
    grid.iter()
        .enumerate()
        .map(|(k, _)| {
            let residual: Vec<f64> = (0..predicted[k].len())
                .map(|r| rates[k].drift[r] - predicted[k][r])
                .collect();
            let [drift, variance, predicted_drift, residual] = [
                &rates[k].drift,
                &rates[k].variance,
                &predicted[k],
                &residual,
            ]
            .map(|v| Estimate::from_replicates(v));
            FokkerPlanckPoint {
                drift,
                variance,
                predicted_drift,
                z: residual.z(),
            }
        })
        .collect()
}

/// `(D2' - u D2) / 2` at every point of `grid` (`[k][replicate]`), `D2'` per
/// replicate from the not-a-knot cubic spline through that replicate's `D2`
/// on the whole grid.
fn stationary_drifts(grid: &[f64], rates: &[SelfRates]) -> Vec<Vec<f64>> {
    let replicates = rates[0].variance.len();
    let slopes: Vec<Vec<f64>> = (0..replicates)
        .map(|r| {
            let variance: Vec<f64> = rates.iter().map(|rate| rate.variance[r]).collect();
            spline_slopes(grid, &variance)
        })
        .collect();
    grid.iter()
        .enumerate()
        .map(|(k, &u)| {
            (0..replicates)
                .map(|r| 0.5 * (slopes[r][k] - u * rates[k].variance[r]))
                .collect()
        })
        .collect()
}

/// The joint test of Fokker-Planck stationarity over the points of `grid`
/// at `u' < 0` (every scene enters with its mirror image, so the points at
/// `u' > 0` repeat their evidence; at `u' = 0` both drifts vanish).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointStationarity {
    /// Points joined.
    pub points: usize,
    /// `sum s (D1 - P) / sum |P|` over the points, `P = (D2' - u D2) / 2`
    /// the stationarity drift and `s` its sign, `P` and `s` from all
    /// replicates (a fixed scale), `D1 - P` per replicate, so that its
    /// spread over replicates carries every correlation between points that
    /// share scenes: the drift's relative excess along the stationarity
    /// drift. 0 under stationarity; below 0 the measured drift is weaker than
    /// stationarity requires.
    pub relative_residual: Estimate,
    /// Share of its spread carried by one replicate.
    pub largest_share: f64,
}

/// [`JointStationarity`] of the rates `rates` measured on `grid` (ascending,
/// at least three points, two replicates).
pub fn joint_stationarity(grid: &[f64], rates: &[SelfRates]) -> JointStationarity {
    let predicted = stationary_drifts(grid, rates);
    let replicates = rates[0].drift.len();
    let joined: Vec<usize> = (0..grid.len()).filter(|&k| grid[k] < 0.0).collect();
    let mean: Vec<f64> = joined
        .iter()
        .map(|&k| predicted[k].iter().sum::<f64>() / replicates as f64)
        .collect();
    let scale: f64 = mean.iter().map(|p| p.abs()).sum();
    let per_replicate: Vec<f64> = (0..replicates)
        .map(|r| {
            let sum: f64 = joined
                .iter()
                .zip(&mean)
                .map(|(&k, p)| p.signum() * (rates[k].drift[r] - predicted[k][r]))
                .sum();
            sum / scale
        })
        .collect();
    JointStationarity {
        points: joined.len(),
        relative_residual: Estimate::from_replicates(&per_replicate),
        largest_share: largest_share(&per_replicate),
    }
}

/// Detailed balance of the self kernel between velocities `a` and `b`.
#[derive(Clone, Debug, PartialEq)]
pub struct Balance {
    /// `G_self(a -> b)`.
    pub forward: Estimate,
    /// `G_self(b -> a)`.
    pub backward: Estimate,
    /// `G(a -> b) / G(b -> a)`, its error from the replicates with the two
    /// kernels' correlation kept (both from the same scenes: `Estimate::paired_ratio`).
    pub ratio: Estimate,
    /// `f0(b) / f0(a)`: the ratio detailed balance requires.
    pub expected_ratio: f64,
    /// `(f0(a) G(a -> b) - f0(b) G(b -> a)) / its standard error`,
    /// per-replicate differences.
    pub imbalance_z: f64,
    /// Per replicate, the imbalance over the mean flow `(f0(a) G(a -> b) +
    /// f0(b) G(b -> a)) / 2`: the pair's part of a joint test.
    pub relative_imbalance: Vec<f64>,
    /// Share of the imbalance's spread over replicates carried by its most
    /// deviant replicate: ~`2 ln R / R` for Gaussian replicates, near 1 when
    /// one heavy scene makes the error (and the z-score means nothing).
    pub largest_share: f64,
}

impl Balance {
    /// Whether the pair's error is carried by one replicate (one scene).
    pub fn dominated(&self) -> bool {
        self.largest_share.is_nan() || self.largest_share > DOMINATED_SHARE
    }
}

/// Joint test of detailed balance over `pairs` (the same replicates): per
/// replicate the sum of the pairs' relative imbalances, whose spread over
/// replicates carries every correlation between pairs that share scenes;
/// its mean over its standard error is the joint z-score (0 +- 1 under
/// detailed balance).
pub fn joint_balance<'a>(pairs: impl Iterator<Item = &'a Balance>) -> JointBalance {
    let mut sums: Vec<f64> = Vec::new();
    for pair in pairs {
        if sums.is_empty() {
            sums = vec![0.0; pair.relative_imbalance.len()];
        }
        for (sum, value) in sums.iter_mut().zip(&pair.relative_imbalance) {
            *sum += value;
        }
    }
    if sums.len() < 2 {
        return JointBalance {
            imbalance: Estimate {
                mean: f64::NAN,
                stderr: f64::NAN,
            },
            largest_share: f64::NAN,
        };
    }
    JointBalance {
        imbalance: Estimate::from_replicates(&sums),
        largest_share: largest_share(&sums),
    }
}

/// A joint detailed-balance test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointBalance {
    /// Sum over pairs of the relative imbalances: mean and standard error over replicates.
    pub imbalance: Estimate,
    /// Share of its spread carried by one replicate (the pairs share scenes,
    /// so one heavy scene can carry the sum though no single pair's error).
    pub largest_share: f64,
}

/// Share of `sum (x - mean)^2` carried by the most deviant `x` (NaN when all agree).
fn largest_share(values: &[f64]) -> f64 {
    let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
    let squares: Vec<f64> = values.iter().map(|x| (x - mean).powi(2)).collect();
    let total: f64 = squares.iter().sum();
    squares.iter().copied().fold(0.0, f64::max) / total
}

/// Detailed balance between `a` and `b = a + steps bins.width` from the
/// self kernel's bins `bins` (around each `u'`; `steps` off the centre):
/// `G_self(a -> b)` at `target(a)` from the events `there` against `G_self(b
/// -> a)` at `target(b)` from `back`, per replicate, in `rho^2 l v_th /
/// v_th`. `there` and `back` are the events, or the feeders
/// ([`self_bin_feeders`](super::self_bin_feeders)) of the bins `half_bins + steps` and `half_bins -
/// steps`; `draws` counts the whole set.
pub fn balance_between(
    (there, back): (&[Event], &[Event]),
    draws: &Draws,
    bins: &Bins,
    (a, steps): (f64, usize),
    target: impl Fn(f64) -> Target,
) -> Balance {
    let b = a + steps as f64 * bins.width;
    let kernel = |events: &[Event], from: f64, k: usize| -> Vec<f64> {
        self_bin(events, &target(from), bins, k, draws)
            .iter()
            .map(|v| v / bins.width)
            .collect()
    };
    let forward = kernel(there, a, bins.half_bins + steps);
    let backward = kernel(back, b, bins.half_bins - steps);
    detailed_balance(a, b, &forward, &backward)
}

/// Detailed balance from the self kernel per replicate: `forward` =
/// `G_self(a -> b)`, `backward` = `G_self(b -> a)` (same units, e.g.
/// `rho^2 l v_th / v_th`).
pub fn detailed_balance(a: f64, b: f64, forward: &[f64], backward: &[f64]) -> Balance {
    let imbalance: Vec<f64> = forward
        .iter()
        .zip(backward)
        .map(|(x, y)| thermal_density(a) * x - thermal_density(b) * y)
        .collect();
    let share = largest_share(&imbalance);
    let ratio = Estimate::paired_ratio(forward, backward);
    let [forward, backward, total] = [forward, backward, &imbalance].map(Estimate::from_replicates);
    let flow = 0.5 * (thermal_density(a) * forward.mean + thermal_density(b) * backward.mean);
    Balance {
        forward,
        backward,
        ratio,
        expected_ratio: thermal_density(b) / thermal_density(a),
        imbalance_z: total.z(),
        relative_imbalance: imbalance.iter().map(|x| x / flow).collect(),
        largest_share: share,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(relative_imbalance: Vec<f64>) -> Balance {
        let flat = Estimate {
            mean: 1.0,
            stderr: 0.0,
        };
        Balance {
            forward: flat,
            backward: flat,
            ratio: flat,
            expected_ratio: 1.0,
            imbalance_z: 0.0,
            largest_share: largest_share(&relative_imbalance),
            relative_imbalance,
        }
    }

    /// Two pairs whose imbalances move together in every replicate count as
    /// one piece of evidence: the joint z equals each pair's own z (a sum
    /// treating them as independent would claim sqrt(2) more).
    #[test]
    fn joint_test_carries_the_correlation_of_pairs() {
        let replicates = vec![0.3, -0.1, 0.2, 0.4, -0.2, 0.1, 0.0, 0.5];
        let single = joint_balance([pair(replicates.clone())].iter())
            .imbalance
            .z();
        let both = joint_balance([pair(replicates.clone()), pair(replicates)].iter());
        assert!(
            (both.imbalance.z() - single).abs() < 1e-12,
            "{} vs {single}",
            both.imbalance.z()
        );
    }

    /// One replicate carrying everything: share (R - 1)/R, and the pair is no
    /// evidence; Gaussian-like replicates are.
    #[test]
    fn one_dominant_replicate_is_flagged() {
        let mut lone = vec![0.0; 16];
        lone[3] = 5.0;
        let dominated = pair(lone);
        assert!((dominated.largest_share - 15.0 / 16.0).abs() < 1e-12);
        assert!(dominated.dominated());
        let spread = pair(vec![0.3, -0.1, 0.2, 0.4, -0.2, 0.1, 0.0, 0.5, -0.3, 0.2]);
        assert!(!spread.dominated(), "{}", spread.largest_share);
    }

    /// Rounding of the spline's slopes of O(1) rates on a 0.25 grid.
    const ROUNDING: f64 = 1e-13;

    /// Replicate `r`'s amplitude: four replicates around 1.
    fn amplitude(r: usize) -> f64 {
        1.0 + 0.01 * (r as f64 - 1.5)
    }

    /// Rates `D1 = c_r drift(u)`, `D2 = c_r variance(u)` on a grid, four
    /// replicates of amplitude `c_r`.
    fn replicated_rates(
        grid: &[f64],
        variance: impl Fn(f64) -> f64,
        drift: impl Fn(f64) -> f64,
    ) -> Vec<SelfRates> {
        grid.iter()
            .map(|&u| SelfRates {
                drift: (0..4).map(|r| amplitude(r) * drift(u)).collect(),
                variance: (0..4).map(|r| amplitude(r) * variance(u)).collect(),
            })
            .collect()
    }

    /// `D2 = c_r (1 + u^2)` on a grid: the spline reproduces the quadratic,
    /// ends included, so the predicted drift is `c_r (u - u^3) / 2` at every point.
    fn rates_with_drift(grid: &[f64], drift: impl Fn(f64) -> f64) -> Vec<SelfRates> {
        replicated_rates(grid, |u| 1.0 + u * u, drift)
    }

    #[test]
    fn the_stationary_drift_of_a_quadratic_variance_rate_passes() {
        let grid: Vec<f64> = (0..9).map(|k| -1.0 + 0.25 * f64::from(k)).collect();
        let exact = |u: f64| 0.5 * (u - u * u * u);
        let points = fokker_planck_check(&grid, &rates_with_drift(&grid, exact));
        for (point, &u) in points.iter().zip(&grid) {
            let expected = Estimate::from_replicates(
                &(0..4).map(|r| amplitude(r) * exact(u)).collect::<Vec<_>>(),
            );
            assert!((point.predicted_drift.mean - expected.mean).abs() < ROUNDING);
            assert!((point.predicted_drift.stderr - expected.stderr).abs() < ROUNDING);
            assert_eq!(point.drift, expected);
        }
    }

    /// A drift of zero where `f0` needs `(u - u^3) / 2` fails by many
    /// standard errors wherever that drift is not zero.
    #[test]
    fn a_missing_drift_fails_the_check() {
        let grid: Vec<f64> = (0..9).map(|k| -1.0 + 0.25 * f64::from(k)).collect();
        let points = fokker_planck_check(&grid, &rates_with_drift(&grid, |_| 0.0));
        for (point, &u) in points.iter().zip(&grid) {
            if u.abs() > 0.1 && (u.abs() - 1.0).abs() > 0.1 {
                assert!(point.z.abs() > 10.0, "u = {u}: z = {}", point.z);
            }
        }
    }

    /// The joint test: the exact stationary drift gives a relative residual
    /// of 0 to rounding; a drift 2% weaker at every point, hidden in noise
    /// of 5% per point that is common to all points of a replicate (they
    /// share scenes), is found at -0.02 with the error of that common noise
    /// (0.05 / sqrt(R) over R replicates), not divided by the points' number.
    #[test]
    fn the_joint_stationarity_test_sees_a_common_deficit_with_its_correlated_error() {
        let grid: Vec<f64> = (0..9).map(|k| -1.0 + 0.25 * f64::from(k)).collect();
        let exact = |u: f64| 0.5 * (u - u * u * u);
        let joint = joint_stationarity(&grid, &rates_with_drift(&grid, exact));
        assert_eq!(joint.points, 4);
        assert!(joint.relative_residual.mean.abs() < ROUNDING);
        let noise = [0.05, -0.05, 0.05, -0.05];
        let mut rates = rates_with_drift(&grid, exact);
        for (rate, &u) in rates.iter_mut().zip(&grid) {
            for (r, drift) in rate.drift.iter_mut().enumerate() {
                *drift = amplitude(r) * exact(u) * (0.98 + noise[r]);
            }
        }
        let deficit = joint_stationarity(&grid, &rates).relative_residual;
        assert!((deficit.mean + 0.02).abs() < 0.005, "{deficit:?}");
        let common = Estimate::from_replicates(&noise);
        assert!(
            (deficit.stderr / common.stderr - 1.0).abs() < 0.1,
            "{deficit:?} {common:?}"
        );
    }

    /// Standard error of the Fokker-Planck residual `D1 - (D2' - u D2) / 2`
    /// in the default study (`pipeline.toml`: n = 6, 8 randomizations,
    /// sweep grid -3..3 in steps of 0.25) at `u' = -3, -2.75, ..., -0.25`,
    /// in units of `a_n` (`D2` at `u' = 0`), measured with central
    /// differences before the spline; the rows at `u' > 0` mirror these.
    const STUDY_RESIDUAL_ERROR: [f64; 12] = [
        5.7e-2, 2.5e-2, 1.7e-2, 1.7e-2, 1.35e-2, 1.1e-2, 9.4e-3, 8.1e-3, 6.6e-3, 4.9e-3, 3.2e-3,
        1.6e-3,
    ];

    /// A variance rate of the shape measured for n = 6 in units of `a_n`
    /// (within 0.01 of the default study's `D2 / a_n` for `|u'| <= 2`, 0.044
    /// at 3; minimum 0.79 near `|u'|` = 1.2, 1.89 at 3): `1 + u^2/10 - (u^2/2) exp(-u^2/2)`,
    /// and its derivative.
    fn variance_like_n6(u: f64) -> (f64, f64) {
        let gaussian = libm::exp(-0.5 * u * u);
        (
            1.0 + 0.1 * u * u - 0.5 * u * u * gaussian,
            0.2 * u + u * (0.5 * u * u - 1.0) * gaussian,
        )
    }

    /// On the sweep's default grid, the predicted drift of a variance rate
    /// shaped like the measured one, fed the exact stationary drift `(D2' -
    /// u D2) / 2`, is off by less than a tenth of the default study's
    /// statistical error at every `u'`: the derivative's truncation error
    /// moves no z-score by more than 0.1 (at `u' = 0` the residual vanishes
    /// by mirror symmetry, to rounding).
    #[test]
    fn the_derivative_error_is_a_tenth_of_the_statistical_error_on_the_default_grid() {
        let grid: Vec<f64> = (0..25).map(|k| -3.0 + 0.25 * f64::from(k)).collect();
        let exact = |u: f64| {
            let (variance, slope) = variance_like_n6(u);
            0.5 * (slope - u * variance)
        };
        let rates = replicated_rates(&grid, |u| variance_like_n6(u).0, exact);
        let mean_amplitude = (0..4).map(amplitude).sum::<f64>() / 4.0;
        let points = fokker_planck_check(&grid, &rates);
        let exceeding: Vec<String> = points
            .iter()
            .zip(&grid)
            .enumerate()
            .filter_map(|(k, (point, &u))| {
                let error = point.predicted_drift.mean - mean_amplitude * exact(u);
                let bound = match k.min(grid.len() - 1 - k) {
                    12 => ROUNDING,
                    mirrored => 0.1 * STUDY_RESIDUAL_ERROR[mirrored],
                };
                (error.abs() > bound).then(|| format!("u' = {u}: {error:.2e} > {bound:.2e}"))
            })
            .collect();
        assert!(
            exceeding.is_empty(),
            "truncation errors (a_n) above the bound: {exceeding:#?}"
        );
    }

    /// A self kernel in detailed balance, `G(a -> b) = f0(b) g` and
    /// `G(b -> a) = f0(a) g` with replicate noise in the symmetric `g`, has
    /// the thermal ratio `f0(b) / f0(a)`; one whose backward rate is 10%
    /// too large fails by many standard errors.
    #[test]
    fn a_balanced_kernel_has_the_thermal_ratio() {
        let (a, b) = (0.3, 0.8);
        let g = [1.0, 1.1, 0.9, 1.05];
        let forward: Vec<f64> = g.iter().map(|g| thermal_density(b) * g).collect();
        let backward: Vec<f64> = g.iter().map(|g| thermal_density(a) * g).collect();
        let balance = detailed_balance(a, b, &forward, &backward);
        let expected = libm::exp(-0.5 * (b * b - a * a));
        assert!((balance.expected_ratio / expected - 1.0).abs() < 1e-15);
        assert!((balance.ratio.mean / expected - 1.0).abs() < 1e-15);
        let heavier: Vec<f64> = backward.iter().map(|y| 1.1 * y).collect();
        let unbalanced = detailed_balance(a, b, &forward, &heavier);
        assert!(unbalanced.imbalance_z < -10.0, "{unbalanced:?}");
    }
}
