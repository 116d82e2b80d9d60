//! Launch distributions of thermal particles entering the observation region
//! (physics.md §3, step 2).

use std::f64::consts::PI;

use super::quasi_random::standard_normal_cdf;

/// Thermal velocity density `f0(u) = exp(-u^2/2) / sqrt(2 pi)` (per `v_th`).
pub fn thermal_density(u: f64) -> f64 {
    (-0.5 * u * u).exp() / (2.0 * PI).sqrt()
}

/// Launch rate `r(u') / rho` in units of `v_th`: the flux of thermal particles
/// through both ends of the observation region in the frame moving with `u'`,
/// `[2 exp(-u'^2/2) + sqrt(2 pi) u' erf(u'/sqrt 2)] / sqrt(2 pi)`, with
/// `erf(u'/sqrt 2) = 2 Phi(u') - 1`.
pub fn launch_rate(u_prime: f64) -> f64 {
    2.0 * thermal_density(u_prime) + u_prime * (2.0 * standard_normal_cdf(u_prime) - 1.0)
}

/// Exact inverse CDF of the launch speed `|u|` for `u' = 0`, whose density is
/// `|u| exp(-u^2/2)` on each side: `|u| = sqrt(-2 ln(1 - U))` for `U` uniform
/// in `[0, 1)` (numerics.md, "Sampling scenes"). Units: `v_th`.
pub fn thermal_launch_speed(uniform: f64) -> f64 {
    (-2.0 * (-uniform).ln_1p()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `r(u') = int f0(u + u') |u| du`, checked by quadrature; `r(0) = sqrt(2/pi)`.
    #[test]
    fn launch_rate_is_the_flux_integral() {
        assert!((launch_rate(0.0) - (2.0 / PI).sqrt()).abs() < 1e-15);
        for &u_prime in &[-2.5, -0.3, 0.7, 3.0] {
            let h = 1e-3;
            let flux: f64 = (-12_000..12_000)
                .map(|k| {
                    let u = h * (f64::from(k) + 0.5);
                    thermal_density(u + u_prime) * u.abs()
                })
                .sum::<f64>()
                * h;
            // Midpoint rule on a smooth integrand with a kink at 0: error ~h^2.
            assert!(
                (flux - launch_rate(u_prime)).abs() < 1e-6,
                "{u_prime}: {flux}"
            );
        }
    }

    /// The CDF of `|u| exp(-u^2/2)` is `1 - exp(-u^2/2)`: inverting it must
    /// return the quantile exactly.
    #[test]
    fn inverse_cdf_matches_rayleigh_quantiles() {
        for &u in &[0.01_f64, 0.5, 1.0, 2.0, 5.0] {
            let cdf = 1.0 - (-0.5 * u * u).exp();
            assert!((thermal_launch_speed(cdf) - u).abs() < 1e-12 * u.max(1.0) / u.min(1.0));
        }
    }
}
