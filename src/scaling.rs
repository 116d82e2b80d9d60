//! The scaling law of the thermalization rate measured (physics.md §7):
//! `Gamma = a_n rho^2 l v_th` with `l ~ T^(-1/n)` and `v_th ~ T^(1/2)` gives
//! `Gamma ~ rho^2 T^(1/2 - 1/n)`. Rates measured at several densities and
//! temperatures (e.g. molecular dynamics of rings) are fitted by
//! `ln Gamma = c + p ln rho + q ln T`, weighted least squares in `ln Gamma`
//! with weights `(Gamma / stderr)^2` (independent rates); the exponents' errors
//! are the fit's covariance, and the chi-square of the fit tests the power
//! law itself when there are more rates than three.
//! The same fit, generalized to correlated rates (least squares on rows
//! whitened by the Cholesky factor of the covariance of `ln rate`), gives
//! the near-integrable law of the rates of `r^-n` as `n -> 2+`
//! ([`fit_near_integrable`]), whose rates share their launch draws.
//! Pure math: no IO.

use crate::linalg::Cholesky;
use crate::stats::{ChiSquare, Estimate};

/// One measured rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredRate {
    /// Density `rho` (any unit: only ratios enter the exponents).
    pub density: f64,
    /// Temperature `kT` (any unit).
    pub temperature: f64,
    /// The rate with its standard error (any unit).
    pub rate: Estimate,
}

/// The fitted power law `Gamma ~ rho^p T^q`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLaw {
    /// Density exponent `p` (2 for three-body collisions).
    pub density_exponent: Estimate,
    /// Temperature exponent `q` (`1/2 - 1/n` for an inverse power law).
    pub temperature_exponent: Estimate,
    /// Chi-square of the fit, `rates - 3` degrees of freedom (0 when the
    /// three parameters are fixed by three rates).
    pub goodness: ChiSquare,
}

/// Fits `ln Gamma = c + p ln rho + q ln T` to `rates`; `None` when the rates
/// do not span two densities and two temperatures independently (the normal
/// equations are singular) or a rate is not positive with a positive error.
pub fn fit_power_law(rates: &[MeasuredRate]) -> Option<PowerLaw> {
    let basis: Vec<[f64; 3]> = rates
        .iter()
        .map(|r| [1.0, libm::log(r.density), libm::log(r.temperature)])
        .collect();
    let estimates: Vec<Estimate> = rates.iter().map(|r| r.rate).collect();
    let fit = fit_log_linear(&basis, &LogRates::independent(&estimates))?;
    Some(PowerLaw {
        density_exponent: fit.coefficients[1],
        temperature_exponent: fit.coefficients[2],
        goodness: fit.goodness,
    })
}

/// The near-integrable law of a rate of the inverse power law `r^-n` close
/// to the Calogero point `n = 2`, where every collision only permutes the
/// velocities: `rate = A (n - 2)^p exp(q (n - 2))`. First-order perturbation
/// theory in `n - 2` makes every kick `O(n - 2)`, so every rate (the variance
/// rate, the gaps) has `p = 2` and every ratio of rates `p = 0`; `q` absorbs
/// the next order.
///
/// Rates that share their launch draws are known far better relative to
/// each other than each on its own, and then the law's truncation shows:
/// the exponent of the law with one more order, `exp(q (n - 2) + s (n -
/// 2)^2)`, moves `p` by more than its error. That shift is the truncation's
/// error of `p` ([`NearIntegrableLaw::exponent_with_truncation`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearIntegrableLaw {
    /// The amplitude `A` (the rate's unit), error from that of `ln A`.
    pub amplitude: Estimate,
    /// The exponent `p`.
    pub exponent: Estimate,
    /// The correction `q`.
    pub correction: Estimate,
    /// Chi-square of the fit, `rates - 3` degrees of freedom.
    pub goodness: ChiSquare,
    /// `p` of the law with the next order `s (n - 2)^2`, from the same
    /// rates (`rates - 4` degrees of freedom; `None` when that fit is
    /// singular).
    pub next_order_exponent: Option<Estimate>,
}

impl NearIntegrableLaw {
    /// `p` with the truncation's error added in quadrature to the
    /// statistical one: `|p - p_next|`, the shift of `p` when the next order
    /// enters (no truncation error when the next order cannot be fitted).
    pub fn exponent_with_truncation(&self) -> Estimate {
        let shift = self
            .next_order_exponent
            .map_or(0.0, |next| next.mean - self.exponent.mean);
        Estimate {
            mean: self.exponent.mean,
            stderr: libm::hypot(self.exponent.stderr, shift),
        }
    }
}

/// Positive rates with the covariance of their natural logarithms.
#[derive(Clone, Debug, PartialEq)]
pub struct LogRates {
    /// The rates (any unit).
    pub rates: Vec<f64>,
    /// `Cov(ln rate_i, ln rate_j)`, row-major `n x n` (dimensionless: the
    /// relative errors and their correlations).
    pub log_covariance: Vec<f64>,
}

impl LogRates {
    /// Independent rates: `Var(ln rate) = (stderr / rate)^2` to first order,
    /// no covariance.
    pub fn independent(rates: &[Estimate]) -> LogRates {
        let n = rates.len();
        let mut log_covariance = vec![0.0; n * n];
        for (i, rate) in rates.iter().enumerate() {
            log_covariance[i * n + i] = (rate.stderr / rate.mean).powi(2);
        }
        LogRates {
            rates: rates.iter().map(|r| r.mean).collect(),
            log_covariance,
        }
    }
}

/// Fits `ln rate = ln A + p ln(n - 2) + q (n - 2)` to the rates at `excess`
/// (`n - 2`, one per rate) by generalized least squares with their
/// covariance; `None` under the conditions of `fit_log_linear` or when an
/// `n - 2` is not positive.
pub fn fit_near_integrable(excess: &[f64], rates: &LogRates) -> Option<NearIntegrableLaw> {
    if excess.iter().any(|x| *x <= 0.0) {
        return None;
    }
    let basis: Vec<[f64; 3]> = excess.iter().map(|&x| [1.0, libm::log(x), x]).collect();
    let fit = fit_log_linear(&basis, rates)?;
    let next_order: Vec<[f64; 4]> = excess
        .iter()
        .map(|&x| [1.0, libm::log(x), x, x * x])
        .collect();
    let next_order_exponent = fit_log_linear(&next_order, rates).map(|f| f.coefficients[1]);
    let log_amplitude = fit.coefficients[0];
    let amplitude = libm::exp(log_amplitude.mean);
    Some(NearIntegrableLaw {
        amplitude: Estimate {
            mean: amplitude,
            stderr: amplitude * log_amplitude.stderr,
        },
        exponent: fit.coefficients[1],
        correction: fit.coefficients[2],
        goodness: fit.goodness,
        next_order_exponent,
    })
}

/// A least-squares fit of `ln rate` on `K` basis functions.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LogLinearFit<const K: usize> {
    /// The coefficients with their errors from the fit's covariance.
    coefficients: [Estimate; K],
    /// Chi-square, `rates - K` degrees of freedom (0 when `K` rates fix the
    /// coefficients).
    goodness: ChiSquare,
}

/// Fits `ln rate = sum_k c_k b_k` (one basis row `b` per rate) by
/// generalized least squares: with `C = L L^T` the covariance of `ln rate`,
/// ordinary least squares on the whitened rows `L^(-1) b` and `L^(-1) ln
/// rate`, whose errors are independent with unit variance; the coefficients'
/// covariance is `N^(-1)`, `N = B^T C^(-1) B`, and `chi2 = r^T C^(-1) r` of
/// the residuals `r`. For independent rates, weights `(rate / stderr)^2`.
/// `None` when a rate is not positive and finite, the covariance is not
/// positive definite, or the normal equations are singular.
fn fit_log_linear<const K: usize>(basis: &[[f64; K]], rates: &LogRates) -> Option<LogLinearFit<K>> {
    if rates.rates.iter().any(|r| !r.is_finite() || *r <= 0.0) {
        return None;
    }
    let factor = Cholesky::of(&rates.log_covariance, rates.rates.len())?;
    let logs: Vec<f64> = rates.rates.iter().map(|&r| libm::log(r)).collect();
    let values = factor.whiten(&logs);
    let columns: Vec<Vec<f64>> = (0..K)
        .map(|k| factor.whiten(&basis.iter().map(|b| b[k]).collect::<Vec<f64>>()))
        .collect();
    let normal: Vec<f64> = (0..K * K)
        .map(|ij| dot(&columns[ij / K], &columns[ij % K]))
        .collect();
    let right: Vec<f64> = columns.iter().map(|c| dot(c, &values)).collect();
    let normal = Cholesky::of(&normal, K)?;
    let parameters = normal.solve(&right);
    let mut coefficients = [Estimate {
        mean: 0.0,
        stderr: 0.0,
    }; K];
    for (k, coefficient) in coefficients.iter_mut().enumerate() {
        let mut unit = [0.0; K];
        unit[k] = 1.0;
        *coefficient = Estimate {
            mean: parameters[k],
            stderr: normal.solve(&unit)[k].sqrt(),
        };
    }
    let chi2 = (0..values.len())
        .map(|row| {
            let fitted: f64 = (0..K).map(|k| columns[k][row] * parameters[k]).sum();
            (values[row] - fitted).powi(2)
        })
        .sum();
    Some(LogLinearFit {
        coefficients,
        goodness: ChiSquare {
            chi2,
            dof: basis.len().saturating_sub(K),
        },
    })
}

/// `sum_i a_i b_i`.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rate(density: f64, temperature: f64, mean: f64, relative: f64) -> MeasuredRate {
        MeasuredRate {
            density,
            temperature,
            rate: Estimate {
                mean,
                stderr: relative * mean,
            },
        }
    }

    /// Rates that follow `rho^2 T^(1/3)` exactly give back the exponents with
    /// zero chi-square; with three rates (the paper's rings: rho, 2 rho at T,
    /// 2 rho at 8 T) the errors are those of two ratios, propagated by hand:
    /// `p = ln(G2 / G1) / ln 2`, `q = ln(G3 / G2) / ln 8`.
    #[test]
    fn exact_rates_give_the_exponents_with_propagated_errors() {
        let law = |rho: f64, t: f64| rho * rho * libm::cbrt(t);
        let rates = [
            rate(1.0, 1.0, law(1.0, 1.0), 0.05),
            rate(2.0, 1.0, law(2.0, 1.0), 0.04),
            rate(2.0, 8.0, law(2.0, 8.0), 0.03),
        ];
        let fit = fit_power_law(&rates).unwrap();
        assert!((fit.density_exponent.mean - 2.0).abs() < 1e-12, "{fit:?}");
        assert!((fit.temperature_exponent.mean - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(fit.goodness.dof, 0);
        let ln2 = core::f64::consts::LN_2;
        let p_error = libm::hypot(0.05, 0.04) / ln2;
        let q_error = libm::hypot(0.04, 0.03) / (3.0 * ln2);
        assert!(
            (fit.density_exponent.stderr / p_error - 1.0).abs() < 1e-9,
            "{fit:?}"
        );
        assert!((fit.temperature_exponent.stderr / q_error - 1.0).abs() < 1e-9);
    }

    /// A fourth rate off the power law shows in the chi-square; rates at one
    /// temperature cannot give a temperature exponent.
    #[test]
    fn a_rate_off_the_law_raises_chi_square_and_one_temperature_gives_none() {
        let law = |rho: f64, t: f64| rho * rho * libm::sqrt(t);
        let mut rates = vec![
            rate(1.0, 1.0, law(1.0, 1.0), 0.01),
            rate(2.0, 1.0, law(2.0, 1.0), 0.01),
            rate(2.0, 8.0, law(2.0, 8.0), 0.01),
            rate(4.0, 1.0, law(4.0, 1.0), 0.01),
        ];
        assert!(fit_power_law(&rates).unwrap().goodness.chi2 < 1e-20);
        rates[3].rate.mean *= 1.1;
        let fit = fit_power_law(&rates).unwrap();
        assert_eq!(fit.goodness.dof, 1);
        assert!(fit.goodness.chi2 > 10.0, "{fit:?}");
        let one_temperature: Vec<MeasuredRate> = rates
            .iter()
            .copied()
            .filter(|r| r.temperature == 1.0)
            .collect();
        assert_eq!(fit_power_law(&one_temperature), None);
    }

    /// The near-integrable law at `n - 2 = 0.05 .. 0.5`.
    fn near_integrable_law(excess: f64) -> f64 {
        3.0e-4 * excess * excess * libm::exp(-0.75 * excess)
    }

    /// Rates that follow the law exactly give back `A`, `p` and `q` with
    /// zero chi-square; an `n - 2` of zero has no logarithm.
    #[test]
    fn exact_near_integrable_rates_give_the_law() {
        let excess = [0.05, 0.1, 0.25, 0.5];
        let rates: Vec<Estimate> = excess
            .iter()
            .map(|&x| {
                let mean = near_integrable_law(x);
                Estimate {
                    mean,
                    stderr: 0.01 * mean,
                }
            })
            .collect();
        let rates = LogRates::independent(&rates);
        let law = fit_near_integrable(&excess, &rates).unwrap();
        assert!((law.exponent.mean - 2.0).abs() < 1e-9, "{law:?}");
        assert!((law.correction.mean + 0.75).abs() < 1e-9, "{law:?}");
        assert!((law.amplitude.mean / 3.0e-4 - 1.0).abs() < 1e-9, "{law:?}");
        assert_eq!(law.goodness.dof, 1);
        assert!(law.goodness.chi2 < 1e-12);
        let next = law.next_order_exponent.unwrap();
        assert!((next.mean - 2.0).abs() < 1e-9, "{law:?}");
        assert!((law.exponent_with_truncation().stderr / law.exponent.stderr - 1.0).abs() < 1e-6);
        assert_eq!(fit_near_integrable(&[0.0, 0.1, 0.25, 0.5], &rates), None);
    }

    /// Rates with an order the law lacks, `exp(0.5 (n - 2)^2)`, known to
    /// 1e-4: the law's chi-square rejects it and its `p` misses 2 by many
    /// errors; the next order's `p` is 2, and the truncation's error, added,
    /// covers the miss.
    #[test]
    fn the_truncation_error_covers_a_missing_order() {
        let excess = [0.05, 0.1, 0.25, 0.5, 1.0];
        let rates: Vec<Estimate> = excess
            .iter()
            .map(|&x| {
                let mean = near_integrable_law(x) * libm::exp(0.5 * x * x);
                Estimate {
                    mean,
                    stderr: 1e-4 * mean,
                }
            })
            .collect();
        let law = fit_near_integrable(&excess, &LogRates::independent(&rates)).unwrap();
        assert!(law.goodness.p_value() < 1e-6, "{law:?}");
        let miss = law.exponent.mean - 2.0;
        assert!(miss.abs() > 10.0 * law.exponent.stderr, "{law:?}");
        assert!((law.next_order_exponent.unwrap().mean - 2.0).abs() < 1e-9);
        let with_truncation = law.exponent_with_truncation();
        assert!(miss.abs() <= with_truncation.stderr, "{with_truncation:?}");
    }

    /// Pulls of the exponent, `(p - 2) / stderr`, and the mean chi-square of
    /// the fits of `sets` sets of rates at `n - 2 = 0.05 .. 1`, each `ln
    /// rate` the law's plus 1% Gaussian noise correlated by `rho` between
    /// rates (`0.01 (sqrt(rho) z_0 + sqrt(1 - rho) z_i)`), all fitted with
    /// the covariance `fitted`.
    fn drawn_fits(rho: f64, fitted: &[f64], sets: usize) -> (Vec<f64>, f64) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(35);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let excess = [0.05, 0.1, 0.25, 0.5, 1.0];
        let (mut pulls, mut chi2) = (Vec::new(), 0.0);
        for _ in 0..sets {
            let common = rho.sqrt() * noise.sample(&mut rng);
            let rates: Vec<f64> = excess
                .iter()
                .map(|&x| {
                    let own = (1.0 - rho).sqrt() * noise.sample(&mut rng);
                    near_integrable_law(x) * libm::exp(0.01 * (common + own))
                })
                .collect();
            let rates = LogRates {
                rates,
                log_covariance: fitted.to_vec(),
            };
            let fit = fit_near_integrable(&excess, &rates).unwrap();
            pulls.push((fit.exponent.mean - 2.0) / fit.exponent.stderr);
            chi2 += fit.goodness.chi2 / sets as f64;
        }
        (pulls, chi2)
    }

    /// `Cov(ln rate_i, ln rate_j) = 1e-4 (rho + (1 - rho) delta_ij)` over
    /// five rates.
    fn correlated(rho: f64) -> Vec<f64> {
        (0..25)
            .map(|k| 1e-4 * if k / 5 == k % 5 { 1.0 } else { rho })
            .collect()
    }

    /// The fit's errors are its estimates' spread: over 4000 sets of rates
    /// drawn with 1% errors about the law, independent or correlated by 0.9
    /// (rates that share their launch draws), the exponent's pulls have mean
    /// 0 and variance 1, and the chi-square averages its two degrees of
    /// freedom (each within four of its own standard errors), when the fit is
    /// given the covariance. Fitted as independent, the correlated rates give
    /// a chi-square of 2 (1 - rho) = 0.2 on average: the common part of their
    /// errors goes into `A`, where the fit cannot see it.
    #[test]
    fn near_integrable_errors_are_calibrated() {
        let sets = 4000;
        let n = sets as f64;
        for rho in [0.0, 0.9] {
            let (pulls, chi2) = drawn_fits(rho, &correlated(rho), sets);
            let pull = Estimate::from_replicates(&pulls);
            let mean = pull.mean;
            let variance = pulls.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / n;
            assert!(mean.abs() < 4.0 / n.sqrt(), "rho {rho}: pull mean {mean}");
            assert!(
                (variance - 1.0).abs() < 4.0 * (2.0 / n).sqrt(),
                "rho {rho}: pull variance {variance}"
            );
            // A chi-square with 2 degrees of freedom: mean 2, variance 4.
            assert!(
                (chi2 - 2.0).abs() < 4.0 * 2.0 / n.sqrt(),
                "rho {rho}: chi2 mean {chi2}"
            );
        }
        let (_, chi2) = drawn_fits(0.9, &correlated(0.0), sets);
        assert!(
            (chi2 - 0.2).abs() < 4.0 * 0.2 / n.sqrt(),
            "chi2 mean {chi2}"
        );
    }
}
