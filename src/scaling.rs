//! The scaling law of the thermalization rate measured (physics.md §7):
//! `Gamma = a_n rho^2 l v_th` with `l ~ T^(-1/n)` and `v_th ~ T^(1/2)` gives
//! `Gamma ~ rho^2 T^(1/2 - 1/n)`. Rates measured at several densities and
//! temperatures (e.g. molecular dynamics of rings) are fitted by
//! `ln Gamma = c + p ln rho + q ln T`, weighted least squares in `ln Gamma`
//! with weights `(Gamma / stderr)^2` (independent rates); the exponents' errors
//! are the fit's covariance, and the chi-square of the fit tests the power
//! law itself when there are more rates than three.
//! The same weighted fit gives the near-integrable law of the rates of
//! `r^-n` as `n -> 2+` ([`fit_near_integrable`]).
//! Pure math: no IO.

use crate::linalg::solve3;
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
    let rows: Vec<([f64; 3], Estimate)> = rates
        .iter()
        .map(|r| {
            let basis = [1.0, libm::log(r.density), libm::log(r.temperature)];
            (basis, r.rate)
        })
        .collect();
    let fit = fit_log_linear(&rows)?;
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
}

/// Fits `ln rate = ln A + p ln(n - 2) + q (n - 2)` to `(n - 2, rate)` pairs
/// (independent rates, weights `(rate / stderr)^2`); `None` under the
/// conditions of [`fit_log_linear`] or when an `n - 2` is not positive.
pub fn fit_near_integrable(rates: &[(f64, Estimate)]) -> Option<NearIntegrableLaw> {
    if rates.iter().any(|(excess, _)| *excess <= 0.0) {
        return None;
    }
    let rows: Vec<([f64; 3], Estimate)> = rates
        .iter()
        .map(|&(excess, rate)| ([1.0, libm::log(excess), excess], rate))
        .collect();
    let fit = fit_log_linear(&rows)?;
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
    })
}

/// A weighted least-squares fit of `ln rate` on three basis functions.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LogLinearFit {
    /// The coefficients with their errors from the fit's covariance.
    coefficients: [Estimate; 3],
    /// Chi-square, `rates - 3` degrees of freedom (0 when three rates fix
    /// the three coefficients).
    goodness: ChiSquare,
}

/// Fits `ln rate = sum_k c_k b_k` to `(b, rate)` rows, weights
/// `(rate / stderr)^2`; `None` when the normal equations are singular or a
/// rate is not positive with a positive, finite error.
fn fit_log_linear(rows: &[([f64; 3], Estimate)]) -> Option<LogLinearFit> {
    if rows
        .iter()
        .any(|(_, r)| r.mean <= 0.0 || r.stderr <= 0.0 || !r.stderr.is_finite())
    {
        return None;
    }
    let weighted: Vec<([f64; 3], f64, f64)> = rows
        .iter()
        .map(|(basis, r)| (*basis, libm::log(r.mean), (r.mean / r.stderr).powi(2)))
        .collect();
    let mut normal = [[0.0; 3]; 3];
    let mut right = [0.0; 3];
    for (basis, value, weight) in &weighted {
        for i in 0..3 {
            right[i] += weight * basis[i] * value;
            for j in 0..3 {
                normal[i][j] += weight * basis[i] * basis[j];
            }
        }
    }
    let parameters = solve3(&normal, &right)?;
    // Variances: the diagonal of the inverse normal matrix.
    let mut coefficients = [Estimate {
        mean: 0.0,
        stderr: 0.0,
    }; 3];
    for (k, coefficient) in coefficients.iter_mut().enumerate() {
        let mut unit = [0.0; 3];
        unit[k] = 1.0;
        let variance = solve3(&normal, &unit)?[k];
        if variance <= 0.0 {
            return None;
        }
        *coefficient = Estimate {
            mean: parameters[k],
            stderr: variance.sqrt(),
        };
    }
    let chi2 = weighted
        .iter()
        .map(|(basis, value, weight)| {
            let fitted: f64 = (0..3).map(|i| basis[i] * parameters[i]).sum();
            weight * (value - fitted).powi(2)
        })
        .sum();
    Some(LogLinearFit {
        coefficients,
        goodness: ChiSquare {
            chi2,
            dof: rows.len().saturating_sub(3),
        },
    })
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
        let rates: Vec<(f64, Estimate)> = [0.05, 0.1, 0.25, 0.5]
            .into_iter()
            .map(|x| {
                let mean = near_integrable_law(x);
                (
                    x,
                    Estimate {
                        mean,
                        stderr: 0.01 * mean,
                    },
                )
            })
            .collect();
        let law = fit_near_integrable(&rates).unwrap();
        assert!((law.exponent.mean - 2.0).abs() < 1e-9, "{law:?}");
        assert!((law.correction.mean + 0.75).abs() < 1e-9, "{law:?}");
        assert!((law.amplitude.mean / 3.0e-4 - 1.0).abs() < 1e-9, "{law:?}");
        assert_eq!(law.goodness.dof, 1);
        assert!(law.goodness.chi2 < 1e-12);
        let mut at_zero = rates.clone();
        at_zero[0].0 = 0.0;
        assert_eq!(fit_near_integrable(&at_zero), None);
    }

    /// The fit's errors are its estimates' spread: over 4000 sets of rates
    /// drawn with Gaussian 1% errors about the law, the exponent's pulls
    /// `(p - 2) / stderr` have mean 0 and variance 1, and the chi-square
    /// averages its two degrees of freedom (each within four of its own
    /// standard errors).
    #[test]
    fn near_integrable_errors_are_calibrated() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(35);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let sets = 4000;
        let (mut pulls, mut chi2) = (Vec::new(), 0.0);
        for _ in 0..sets {
            let rates: Vec<(f64, Estimate)> = [0.05, 0.1, 0.25, 0.5, 1.0]
                .into_iter()
                .map(|x| {
                    let (law, stderr) = (near_integrable_law(x), 0.01 * near_integrable_law(x));
                    let mean = law + stderr * noise.sample(&mut rng);
                    (x, Estimate { mean, stderr })
                })
                .collect();
            let fit = fit_near_integrable(&rates).unwrap();
            pulls.push((fit.exponent.mean - 2.0) / fit.exponent.stderr);
            chi2 += fit.goodness.chi2 / sets as f64;
        }
        let pull = Estimate::from_replicates(&pulls);
        let mean = pull.mean;
        let variance = pulls.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / sets as f64;
        let n = sets as f64;
        assert!(mean.abs() < 4.0 / n.sqrt(), "pull mean {mean}");
        assert!(
            (variance - 1.0).abs() < 4.0 * (2.0 / n).sqrt(),
            "pull variance {variance}"
        );
        // A chi-square with 2 degrees of freedom: mean 2, variance 4.
        assert!(
            (chi2 - 2.0).abs() < 4.0 * 2.0 / n.sqrt(),
            "chi2 mean {chi2}"
        );
    }
}
