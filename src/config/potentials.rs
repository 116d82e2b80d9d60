//! `[potentials]`: the pair potentials of the study.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, check_unique, compact};
use crate::physics::potential::Potential;

/// `[potentials]`: one potential per listed value.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PotentialsConfig {
    /// Exponents `n > 1` of inverse power laws `U = eps (l0/d)^n`.
    #[serde(default)]
    pub inverse_power: Vec<f64>,
    /// `theta = kT/eps > 0` of Lennard-Jones potentials.
    #[serde(default)]
    pub lennard_jones: Vec<f64>,
}

impl PotentialsConfig {
    /// One potential per listed value, inverse power laws first, in file order.
    fn list(&self) -> Vec<Potential> {
        let inverse = self
            .inverse_power
            .iter()
            .map(|&n| Potential::inverse_power(n));
        let lj = self
            .lennard_jones
            .iter()
            .map(|&theta| Potential::lennard_jones(theta));
        inverse.chain(lj).collect()
    }
}

/// Largest inverse-power exponent `n`.
pub const MAX_EXPONENT: f64 = 100.0;

/// Range of Lennard-Jones `theta = kT/eps`: below it nearly every pair is
/// bound, above it the well does not matter. With `n` in `(1, MAX_EXPONENT]`
/// this bounds every potential id (which names files) to 24 characters.
pub const THETA_RANGE: [f64; 2] = [1e-3, 1e3];

impl PotentialsConfig {
    /// Checks every value and returns the potentials, inverse power laws
    /// first, in file order.
    pub(super) fn resolve(&self) -> Result<Vec<Potential>, Invalid> {
        let potentials = self;
        check(
            !potentials.inverse_power.is_empty() || !potentials.lennard_jones.is_empty(),
            "potentials",
            "lists no potential: give `inverse_power = [6]` or `lennard_jones = [1.0]`",
        )?;
        for (k, &n) in potentials.inverse_power.iter().enumerate() {
            check(
                n > 1.0 && n <= MAX_EXPONENT,
                format!("potentials.inverse_power[{k}]"),
                format!(
                    "n = {} is outside (1, {MAX_EXPONENT}] (the potential tail must be integrable; steeper walls are hard spheres)",
                    compact(n)
                ),
            )?;
        }
        for (k, &theta) in potentials.lennard_jones.iter().enumerate() {
            check(
                (THETA_RANGE[0]..=THETA_RANGE[1]).contains(&theta),
                format!("potentials.lennard_jones[{k}]"),
                format!(
                    "theta = kT/eps = {} is outside [{}, {}]",
                    compact(theta),
                    THETA_RANGE[0],
                    THETA_RANGE[1]
                ),
            )?;
        }
        check_unique(&potentials.inverse_power, |k| {
            format!("potentials.inverse_power[{k}]")
        })?;
        check_unique(&potentials.lennard_jones, |k| {
            format!("potentials.lennard_jones[{k}]")
        })?;
        Ok(self.list())
    }
}
