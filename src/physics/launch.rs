//! Launch distributions of thermal particles entering the observation region
//! (physics.md §3, step 2).

/// Exact inverse CDF of the launch speed `|u|` for `u' = 0`, whose density is
/// `|u| exp(-u^2/2)` on each side: `|u| = sqrt(-2 ln(1 - U))` for `U` uniform
/// in `[0, 1)` (numerics.md, "Sampling scenes"). Units: `v_th`.
pub fn thermal_launch_speed(uniform: f64) -> f64 {
    (-2.0 * (-uniform).ln_1p()).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

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
