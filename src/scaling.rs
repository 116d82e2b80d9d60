//! The scaling law of the thermalization rate measured (physics.md §7):
//! `Gamma = a_n rho^2 l v_th` with `l ~ T^(-1/n)` and `v_th ~ T^(1/2)` gives
//! `Gamma ~ rho^2 T^(1/2 - 1/n)`. Rates measured at several densities and
//! temperatures (e.g. molecular dynamics of rings) are fitted by
//! `ln Gamma = c + p ln rho + q ln T`, weighted least squares in `ln Gamma`
//! with weights `(Gamma / stderr)^2` (independent rates); the exponents' errors
//! are the fit's covariance, and the chi-square of the fit tests the power
//! law itself when there are more rates than three.
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
    if rates
        .iter()
        .any(|r| r.rate.mean <= 0.0 || r.rate.stderr <= 0.0 || !r.rate.stderr.is_finite())
    {
        return None;
    }
    let rows: Vec<([f64; 3], f64, f64)> = rates
        .iter()
        .map(|r| {
            let basis = [1.0, libm::log(r.density), libm::log(r.temperature)];
            let weight = (r.rate.mean / r.rate.stderr).powi(2);
            (basis, libm::log(r.rate.mean), weight)
        })
        .collect();
    let mut normal = [[0.0; 3]; 3];
    let mut right = [0.0; 3];
    for (basis, value, weight) in &rows {
        for i in 0..3 {
            right[i] += weight * basis[i] * value;
            for j in 0..3 {
                normal[i][j] += weight * basis[i] * basis[j];
            }
        }
    }
    let parameters = solve3(&normal, &right)?;
    // Variances of p and q: the diagonal of the inverse normal matrix.
    let variance = |k: usize| {
        let mut unit = [0.0; 3];
        unit[k] = 1.0;
        solve3(&normal, &unit).map(|column| column[k])
    };
    let (density_variance, temperature_variance) = (variance(1)?, variance(2)?);
    if density_variance <= 0.0 || temperature_variance <= 0.0 {
        return None;
    }
    let chi2 = rows
        .iter()
        .map(|(basis, value, weight)| {
            let fitted: f64 = (0..3).map(|i| basis[i] * parameters[i]).sum();
            weight * (value - fitted).powi(2)
        })
        .sum();
    Some(PowerLaw {
        density_exponent: Estimate {
            mean: parameters[1],
            stderr: density_variance.sqrt(),
        },
        temperature_exponent: Estimate {
            mean: parameters[2],
            stderr: temperature_variance.sqrt(),
        },
        goodness: ChiSquare {
            chi2,
            dof: rates.len().saturating_sub(3),
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
}
