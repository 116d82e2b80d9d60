//! Launch distributions of thermal particles entering the observation region
//! (physics.md §3, step 2).

use std::f64::consts::PI;

use super::quasi_random::standard_normal_cdf;

/// Thermal velocity density `f0(u) = exp(-u^2/2) / sqrt(2 pi)` (per `v_th`).
pub fn thermal_density(u: f64) -> f64 {
    libm::exp(-0.5 * u * u) / (2.0 * PI).sqrt()
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
    (-2.0 * libm::log1p(-uniform)).sqrt()
}

/// Normalization `Z(b) = int_0^inf v exp(-(v + b)^2 / 2) dv
/// = exp(-b^2/2) - b sqrt(2 pi) Phi(-b)` of the shifted launch-speed density.
fn shifted_normalization(shift: f64) -> f64 {
    libm::exp(-0.5 * shift * shift) - shift * (2.0 * PI).sqrt() * standard_normal_cdf(-shift)
}

/// Density of a launch speed `v = |u| > 0` on one side of the special particle
/// moving with `u'`: `v exp(-(v + b)^2/2) / Z(b)` with `b = sign(u) u'`, the
/// shape of `f0(u + u') |u|` on that side (physics.md §3). `b = 0` is the
/// Rayleigh density of [`thermal_launch_speed`].
pub fn shifted_speed_density(speed: f64, shift: f64) -> f64 {
    speed * libm::exp(-0.5 * (speed + shift).powi(2)) / shifted_normalization(shift)
}

/// Cumulative distribution of [`shifted_speed_density`]:
/// `[exp(-b^2/2) - exp(-(v+b)^2/2) - b sqrt(2 pi) (Phi(v+b) - Phi(b))] / Z(b)`.
fn shifted_speed_cdf(speed: f64, shift: f64) -> f64 {
    let gaussian = libm::exp(-0.5 * shift * shift) - libm::exp(-0.5 * (speed + shift).powi(2));
    let drift = shift
        * (2.0 * PI).sqrt()
        * (standard_normal_cdf(-shift) - standard_normal_cdf(-(speed + shift)));
    (gaussian - drift) / shifted_normalization(shift)
}

/// Inverse of the shifted launch-speed CDF (safeguarded Newton iteration on a
/// bracket; exact to ~1e-13 relative for `|b| <= 3`, where `Z(b)` loses at most
/// one digit to cancellation).
pub fn shifted_launch_speed(uniform: f64, shift: f64) -> f64 {
    if shift == 0.0 {
        return thermal_launch_speed(uniform);
    }
    let (mut low, mut high) = (0.0, 1.0 + shift.abs());
    while shifted_speed_cdf(high, shift) < uniform {
        (low, high) = (high, 2.0 * high);
    }
    let mut speed = thermal_launch_speed(uniform).clamp(low, high);
    for _ in 0..100 {
        let residual = shifted_speed_cdf(speed, shift) - uniform;
        if residual > 0.0 {
            high = speed
        } else {
            low = speed
        }
        let newton = speed - residual / shifted_speed_density(speed, shift);
        let next = if newton > low && newton < high {
            newton
        } else {
            0.5 * (low + high)
        };
        if (next - speed).abs() <= 1e-15 * speed {
            return next;
        }
        speed = next;
    }
    speed
}

/// Inverse CDF of the shifted launch-speed density truncated to speeds at or
/// above `floor` (`v_th`): the launch density's own map on the part of its
/// range above `floor`, `v = F^-1(F(floor) + U (1 - F(floor)))`; at `floor = 0`
/// exactly [`shifted_launch_speed`] (`F(0) = 0`).
pub fn shifted_launch_speed_above(uniform: f64, shift: f64, floor: f64) -> f64 {
    let below = shifted_speed_cdf(floor, shift);
    shifted_launch_speed(below + uniform * (1.0 - below), shift)
}

/// Density of [`shifted_launch_speed_above`] at `speed >= floor`:
/// [`shifted_speed_density`] over the probability above `floor` (`1 / v_th`);
/// at `floor = 0` exactly that density.
pub fn shifted_speed_density_above(speed: f64, shift: f64, floor: f64) -> f64 {
    shifted_speed_density(speed, shift) / (1.0 - shifted_speed_cdf(floor, shift))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The truncated map draws only speeds above the floor, with the
    /// truncated density: the fraction of a fine coordinate grid mapped below
    /// `v` is the density's integral from the floor to `v`.
    #[test]
    fn truncated_launch_speeds_follow_their_density() {
        let (floor, grid) = (0.1, 100_000);
        for &shift in &[-3.0, 0.0, 0.5] {
            let speeds: Vec<f64> = (0..grid)
                .map(|k| {
                    shifted_launch_speed_above((f64::from(k) + 0.5) / f64::from(grid), shift, floor)
                })
                .collect();
            assert!(speeds.iter().all(|&v| v >= floor));
            for v in [0.15, 0.5, 2.0] {
                let fraction = speeds.iter().filter(|&&s| s <= v).count() as f64 / f64::from(grid);
                let h = 1e-5;
                let steps = ((v - floor) / h) as u32;
                let integral: f64 = (0..steps)
                    .map(|k| {
                        shifted_speed_density_above(floor + h * (f64::from(k) + 0.5), shift, floor)
                    })
                    .sum::<f64>()
                    * h;
                assert!(
                    (fraction - integral).abs() < 3e-5,
                    "{shift} {v}: {fraction} vs {integral}"
                );
            }
        }
    }

    /// The shifted density is normalized, has the target shape, and the inverse
    /// CDF inverts it.
    #[test]
    fn shifted_launch_speeds_follow_their_density() {
        for &shift in &[-3.0, -0.5, 0.5, 3.0] {
            let h = 1e-4;
            let total: f64 = (0..200_000)
                .map(|k| shifted_speed_density(h * (f64::from(k) + 0.5), shift))
                .sum::<f64>()
                * h;
            assert!((total - 1.0).abs() < 1e-7, "{shift}: {total}");
            for &uniform in &[1e-6, 0.1, 0.5, 0.9, 0.999_999] {
                let speed = shifted_launch_speed(uniform, shift);
                assert!(
                    (shifted_speed_cdf(speed, shift) - uniform).abs() < 1e-13,
                    "{shift} {uniform}"
                );
            }
            let ratio = shifted_speed_density(1.3, shift) / shifted_speed_density(0.4, shift);
            let expected =
                (1.3 * thermal_density(1.3 + shift)) / (0.4 * thermal_density(0.4 + shift));
            assert!((ratio / expected - 1.0).abs() < 1e-13);
        }
    }

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
            let cdf = 1.0 - libm::exp(-0.5 * u * u);
            assert!((thermal_launch_speed(cdf) - u).abs() < 1e-12 * u.max(1.0) / u.min(1.0));
        }
    }
}
