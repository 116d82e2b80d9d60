//! Rates of a Lennard-Jones gas in physical units from the study's theta
//! table (`ternary rate`): the table's rate constants, measured at a few
//! `theta = kT/eps`, interpolated to the gas's `theta` and turned into
//! `Gamma = a rho^2 l v_th` (physics.md §2), recombination and dissociation times.
//!
//! Owns the interpolation and its error; not the reading of the store
//! (`report::rates`) nor the units (`physics::units`). Pure math: no IO.
//! Scaled rates are in `rho^2 l v_th`; physical rates in 1/s.

use crate::config::MAX_GAS_DENSITY;
use crate::physics::potential::{Family, LennardJones};
use crate::physics::units::PhysicalGas;
use crate::stats::Estimate;

/// Relative distance within which a `theta` is a table row's own: the
/// precision to which `[[gas]]` matches `kt_ev / eps_ev` to a potential's
/// `theta` (config::gas).
pub const SAME_THETA: f64 = 1e-9;

/// Nanoseconds per second.
const NS_PER_S: f64 = 1e9;

/// The Lennard-Jones rows of a study's table, by ascending `theta`: one
/// column per rate constant. A further column (the dissociation rate
/// coefficient, when its stage exists) is one more field here, read by
/// `report::rates` and interpolated in [`gas_rates`].
#[derive(Clone, Debug, PartialEq)]
pub struct ThetaTable {
    /// `theta = kT/eps` of each row, ascending.
    pub thetas: Vec<f64>,
    /// `a_n` as the table gives it: the free-atom self variance rate at
    /// `u' = 0`, untruncated (converged), `rho^2 l v_th`.
    pub thermalization: Vec<Estimate>,
    /// The same rate counting only `|u - u'| <= 0.04`, the paper's
    /// definition (its N2 example), `rho^2 l v_th`.
    pub paper_thermalization: Vec<Estimate>,
    /// Recombination rate per atom averaged over thermal atoms (from
    /// detailed balance with dissociation, `3 K_b k_d`), `rho^2 l v_th`.
    pub recombination: Vec<Estimate>,
    /// Dissociation rate `k_d` of a bound pair by thermal atoms, per pair,
    /// `rho v_th`.
    pub dissociation: Vec<Estimate>,
}

/// An interpolated rate constant: its value, the table's standard error
/// carried through the interpolation, and the interpolation's own error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interpolated {
    /// The value.
    pub value: f64,
    /// Standard error from the rows' standard errors.
    pub statistical: f64,
    /// Error estimate of the interpolation (0 at a row).
    pub interpolation: f64,
}

impl Interpolated {
    /// The value with both errors combined in quadrature.
    pub fn estimate(&self) -> Estimate {
        Estimate {
            mean: self.value,
            stderr: libm::hypot(self.statistical, self.interpolation),
        }
    }

    /// `self` times an exact factor.
    fn scaled(self, factor: f64) -> Interpolated {
        Interpolated {
            value: self.value * factor,
            statistical: self.statistical * factor.abs(),
            interpolation: self.interpolation * factor.abs(),
        }
    }
}

/// A `theta` the table does not cover.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RateError {
    /// Outside the table's range: extrapolation refused.
    #[error(
        "theta = kT/eps = {theta} is outside the study's Lennard-Jones table, theta in [{min}, {max}] ({rows} rows), and is not extrapolated: list a theta beyond it under [potentials] lennard_jones and run, or change the temperature"
    )]
    OutsideTable {
        theta: f64,
        min: f64,
        max: f64,
        rows: usize,
    },
    /// A gas too dense for three-body collisions alone.
    #[error(
        "rho l = {scaled_density:.4e} is above {MAX_GAS_DENSITY}: the three-body rates describe dilute gases (rho l << 1)"
    )]
    Dense { scaled_density: f64 },
    /// A table without Lennard-Jones rows.
    #[error(
        "the study's table has no Lennard-Jones rows: list some under [potentials] lennard_jones"
    )]
    NoRows,
}

/// `values` (one per `thetas`, ascending) at `theta`.
///
/// At a row (within [`SAME_THETA`]) the row's own value and error. Between
/// rows `i` and `i + 1`: linear in `(ln theta, ln a)`, a power law through
/// the two neighbours, with `t = ln(theta/theta_i) / ln(theta_(i+1)/theta_i)`,
/// `ln a = (1 - t) ln a_i + t ln a_(i+1)`, and the statistical error
/// `a sqrt((1 - t)^2 (s_i/a_i)^2 + t^2 (s_(i+1)/a_(i+1))^2)` (rows
/// independent). A pair with a zero value (no recombination seen) is
/// interpolated linearly in `(ln theta, a)` instead. The interpolation
/// error is `|quadratic - linear|` at `theta`, the quadratic through the two
/// neighbours and the next row nearer in `ln theta` (in the same
/// coordinates); with only two rows, `2 t (1 - t) |a_(i+1) - a_i|` (half the
/// change between the rows midway, zero at them). A power law is therefore
/// reproduced exactly when three rows exist. A `theta` outside
/// `[min, max]` is refused.
pub fn interpolate(
    thetas: &[f64],
    values: &[Estimate],
    theta: f64,
) -> Result<Interpolated, RateError> {
    let (Some(&min), Some(&max)) = (thetas.first(), thetas.last()) else {
        return Err(RateError::NoRows);
    };
    if let Some(row) = thetas
        .iter()
        .position(|&t| (theta / t - 1.0).abs() <= SAME_THETA)
    {
        return Ok(Interpolated {
            value: values[row].mean,
            statistical: values[row].stderr,
            interpolation: 0.0,
        });
    }
    if !(min..=max).contains(&theta) {
        return Err(RateError::OutsideTable {
            theta,
            min,
            max,
            rows: thetas.len(),
        });
    }
    let below = thetas.iter().rposition(|&t| t < theta).unwrap_or(0);
    let pair = [below, below + 1];
    let logarithmic = pair.iter().all(|&k| values[k].mean > 0.0);
    let x = |k: usize| libm::log(thetas[k]);
    let y = |k: usize| {
        if logarithmic {
            libm::log(values[k].mean)
        } else {
            values[k].mean
        }
    };
    let at = libm::log(theta);
    let t = (at - x(below)) / (x(below + 1) - x(below));
    let linear = (1.0 - t) * y(below) + t * y(below + 1);
    let value = if logarithmic {
        libm::exp(linear)
    } else {
        linear
    };
    let relative = |k: usize| {
        if logarithmic {
            values[k].stderr / values[k].mean
        } else {
            values[k].stderr
        }
    };
    let spread = libm::hypot((1.0 - t) * relative(below), t * relative(below + 1));
    let statistical = if logarithmic { value * spread } else { spread };
    let third = third_row(thetas, pair, at).filter(|&k| !logarithmic || values[k].mean > 0.0);
    let interpolation = match third {
        Some(k) => {
            let quadratic = lagrange(
                [x(below), x(below + 1), x(k)],
                [y(below), y(below + 1), y(k)],
                at,
            );
            let curved = if logarithmic {
                libm::exp(quadratic)
            } else {
                quadratic
            };
            (curved - value).abs()
        }
        None => 2.0 * t * (1.0 - t) * (values[below + 1].mean - values[below].mean).abs(),
    };
    Ok(Interpolated {
        value,
        statistical,
        interpolation,
    })
}

/// The row next to `pair` (outside it) nearer to `at` in `ln theta`.
fn third_row(thetas: &[f64], pair: [usize; 2], at: f64) -> Option<usize> {
    let distance = |k: usize| (libm::log(thetas[k]) - at).abs();
    let left = pair[0].checked_sub(1);
    let right = Some(pair[1] + 1).filter(|&k| k < thetas.len());
    match (left, right) {
        (Some(l), Some(r)) => Some(if distance(l) <= distance(r) { l } else { r }),
        (one, None) | (None, one) => one,
    }
}

/// The quadratic through `(x_k, y_k)` at `at` (Lagrange form).
fn lagrange(x: [f64; 3], y: [f64; 3], at: f64) -> f64 {
    (0..3)
        .map(|k| {
            let [a, b] = [(k + 1) % 3, (k + 2) % 3];
            y[k] * (at - x[a]) * (at - x[b]) / ((x[k] - x[a]) * (x[k] - x[b]))
        })
        .sum()
}

/// A gas's rates: its `theta`, `rho l`, the rate unit and each rate
/// constant at its `theta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GasRates {
    /// `theta = kT/eps`.
    pub theta: f64,
    /// Scaled density `rho l` (`l = l0 (eps/kT)^(1/6)`).
    pub scaled_density: f64,
    /// `rho^2 l v_th`, 1/s.
    pub rate_unit_per_s: f64,
    /// Free-atom thermalization constant `a`, `rho^2 l v_th`.
    pub thermalization: Interpolated,
    /// The paper's `a` (`|u - u'| <= 0.04`), `rho^2 l v_th`.
    pub paper_thermalization: Interpolated,
    /// Thermal recombination rate per atom, `rho^2 l v_th`.
    pub recombination: Interpolated,
    /// Dissociation rate of a bound pair, per pair, `rho v_th`.
    pub dissociation: Interpolated,
}

impl GasRates {
    /// A rate constant in 1/s: `Gamma = a rho^2 l v_th` (physics.md §2).
    pub fn per_second(&self, constant: Interpolated) -> Interpolated {
        constant.scaled(self.rate_unit_per_s)
    }

    /// A pair's rate constant in `rho v_th` (one atom at a time meets it)
    /// in 1/s: `k rho v_th = k (rho^2 l v_th) / (rho l)`.
    pub fn per_pair_per_second(&self, constant: Interpolated) -> Interpolated {
        constant.scaled(self.rate_unit_per_s / self.scaled_density)
    }
}

/// The rates of `gas`, a Lennard-Jones gas, from `table` at its
/// `theta = kT/eps`; refused outside the table and above `rho l = 0.1`
/// (as a `[[gas]]` is).
pub fn gas_rates(table: &ThetaTable, gas: &PhysicalGas) -> Result<GasRates, RateError> {
    let theta = gas.kt_ev / gas.eps_ev;
    let exponent = LennardJones { theta }.length_exponent();
    let scaled_density = gas.scaled_density(exponent);
    if scaled_density > MAX_GAS_DENSITY {
        return Err(RateError::Dense { scaled_density });
    }
    let at = |values: &[Estimate]| interpolate(&table.thetas, values, theta);
    Ok(GasRates {
        theta,
        scaled_density,
        rate_unit_per_s: gas.rate_per_ns(1.0, exponent) * NS_PER_S,
        thermalization: at(&table.thermalization)?,
        paper_thermalization: at(&table.paper_thermalization)?,
        recombination: at(&table.recombination)?,
        dissociation: at(&table.dissociation)?,
    })
}

/// `1 / rate` with the rate's error carried to first order
/// (`s / rate^2`); a zero rate has no time: infinite, without error.
pub fn time_of(rate: Estimate) -> Estimate {
    if rate.mean == 0.0 {
        return Estimate {
            mean: f64::INFINITY,
            stderr: f64::NAN,
        };
    }
    Estimate {
        mean: 1.0 / rate.mean,
        stderr: rate.stderr / rate.mean.powi(2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact(values: impl IntoIterator<Item = f64>) -> Vec<Estimate> {
        values
            .into_iter()
            .map(|mean| Estimate { mean, stderr: 0.0 })
            .collect()
    }

    /// `a = c theta^p` on four rows: log-log interpolation (and its quadratic
    /// error estimate) reproduce it between any two, to rounding.
    #[test]
    fn a_power_law_in_theta_is_reproduced_exactly() {
        let thetas = [0.1, 0.3, 0.8, 10.0];
        let law = |theta: f64| 3e-4 * libm::pow(theta, -0.7);
        let values = exact(thetas.map(law));
        for theta in [0.1, 0.1052, 0.2, 0.5, 0.8, 3.0, 9.99] {
            let got = interpolate(&thetas, &values, theta).unwrap();
            assert!(
                (got.value / law(theta) - 1.0).abs() < 1e-13,
                "{theta}: {got:?}"
            );
            assert!(got.interpolation <= 1e-13 * got.value, "{theta}: {got:?}");
        }
    }

    /// Relative errors at the two neighbours combine with weights `1 - t`
    /// and `t`; midway in `ln theta` both weigh 1/2. At a row: its own.
    #[test]
    fn statistical_error_follows_the_weights() {
        let thetas = [1.0, 4.0];
        let values = vec![
            Estimate {
                mean: 1.0,
                stderr: 0.03,
            },
            Estimate {
                mean: 4.0,
                stderr: 0.16,
            },
        ];
        let mid = interpolate(&thetas, &values, 2.0).unwrap();
        assert!((mid.value - 2.0).abs() < 1e-14);
        let expected = 2.0 * libm::hypot(0.5 * 0.03, 0.5 * 0.04);
        assert!((mid.statistical - expected).abs() < 1e-14, "{mid:?}");
        // Two rows only: half the change midway.
        assert!((mid.interpolation - 1.5).abs() < 1e-14, "{mid:?}");
        let row = interpolate(&thetas, &values, 4.0 * (1.0 + 1e-12)).unwrap();
        assert_eq!(
            (row.value, row.statistical, row.interpolation),
            (4.0, 0.16, 0.0)
        );
    }

    #[test]
    fn a_theta_outside_the_table_is_refused_with_its_range() {
        let thetas = [0.1, 0.8];
        let values = exact([1.0, 2.0]);
        let error = interpolate(&thetas, &values, 0.05).unwrap_err();
        assert_eq!(
            error,
            RateError::OutsideTable {
                theta: 0.05,
                min: 0.1,
                max: 0.8,
                rows: 2
            }
        );
        assert!(error.to_string().contains("[0.1, 0.8]"), "{error}");
        assert!(interpolate(&thetas, &values, 0.81).is_err());
        assert_eq!(interpolate(&[], &[], 1.0), Err(RateError::NoRows));
    }

    /// A zero (no recombination seen) is interpolated linearly in `a`.
    #[test]
    fn a_zero_row_interpolates_linearly() {
        let got = interpolate(&[1.0, 100.0], &exact([2.0, 0.0]), 10.0).unwrap();
        assert!((got.value - 1.0).abs() < 1e-14, "{got:?}");
    }
}
