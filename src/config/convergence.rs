//! `[convergence]`: `a_n` under varied numerical settings.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, check_length, check_unique};
use super::{CollisionsConfig, CollisionsParams, EngineConfig, KernelConfig, KernelParams};
use crate::physics::potential::Potential;

/// `[convergence]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConvergenceConfig {
    /// Run the convergence stage.
    pub enabled: bool,
    /// Exponent `n` of the inverse power law studied (must be configured).
    pub inverse_power: f64,
    /// Densities `rho l` (finite-density correction).
    pub densities: Vec<f64>,
    /// Offset bounds `B`: only `|tau| <= B T` counts.
    pub offset_bounds: Vec<f64>,
    /// Integrator tolerances (scenes re-integrated at the same points).
    pub tolerances: Vec<f64>,
    /// Share of the launch pairs re-integrated at each tolerance (the leading
    /// ones of every randomization and stratum; the shift is paired with the
    /// default on the same pairs).
    pub tolerance_share: f64,
    /// Bin widths of the binned `a_n`.
    pub bin_widths: Vec<f64>,
}

impl Default for ConvergenceConfig {
    fn default() -> Self {
        ConvergenceConfig {
            enabled: false,
            inverse_power: 6.0,
            densities: vec![5e-5, 5e-4, 5e-3],
            offset_bounds: vec![1.5, 3.0, 10.0, 30.0, 100.0],
            tolerances: vec![1e-10, 1e-11, 1e-13],
            tolerance_share: 0.125,
            bin_widths: vec![5e-5, 2e-4, 1e-3, 4e-3],
        }
    }
}

/// Resolved parameters of the `convergence` stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConvergenceParams {
    /// Default kernel settings of the potential (u' = 0, dilute).
    pub kernel: KernelParams,
    /// Densities.
    pub densities: Vec<f64>,
    /// Offset bounds in collision times.
    pub offset_bounds: Vec<f64>,
    /// Tolerances.
    pub tolerances: Vec<f64>,
    /// Bin widths.
    pub bin_widths: Vec<f64>,
}

/// What the convergence study needs of the other sections.
pub(super) struct Context<'a> {
    /// The configured potentials.
    pub potentials: &'a [Potential],
    /// `[collisions]`.
    pub collisions: &'a CollisionsConfig,
    /// `[kernel]`.
    pub kernel: &'a KernelConfig,
    /// The study's engine.
    pub engine: &'a EngineConfig,
}

/// The convergence stage's parameters and the collisions it re-integrates at
/// each varied tolerance.
type Resolved = (ConvergenceParams, Vec<CollisionsParams>);

impl ConvergenceConfig {
    /// Checks the studied potential and the varied settings, and resolves the
    /// stage's parameters, if enabled.
    pub(super) fn resolve(&self, context: &Context) -> Result<Option<Resolved>, Invalid> {
        if !self.enabled {
            return Ok(None);
        }
        let potential = Potential::inverse_power(self.inverse_power);
        check(
            context.potentials.contains(&potential),
            "convergence.inverse_power",
            format!(
                "n = {} is not among potentials.inverse_power",
                self.inverse_power
            ),
        )?;
        let lists: [(&str, &Vec<f64>, f64, f64); 4] = [
            ("densities", &self.densities, 0.0, 0.1),
            ("offset_bounds", &self.offset_bounds, 1e-3, 1e6),
            ("tolerances", &self.tolerances, 1e-16, 1e-3),
            ("bin_widths", &self.bin_widths, 1e-7, context.kernel.edge()),
        ];
        for (name, values, low, high) in lists {
            check_length(values, &format!("convergence.{name}"))?;
            for (k, &value) in values.iter().enumerate() {
                check(
                    value.is_finite() && value > low && value <= high,
                    format!("convergence.{name}[{k}]"),
                    format!("{value} is outside ({low}, {high}]"),
                )?;
            }
        }
        check_unique(&self.tolerances, |k| format!("convergence.tolerances[{k}]"))?;
        check(
            self.tolerance_share > 0.0 && self.tolerance_share <= 1.0,
            "convergence.tolerance_share",
            format!("{} is outside (0, 1]", self.tolerance_share),
        )?;
        let variants = self
            .tolerances
            .iter()
            .map(|&tolerance| {
                let mut params = context
                    .collisions
                    .params(potential, context.engine.settings(&potential));
                params.engine.tolerance = tolerance;
                params.launch_share = (self.tolerance_share < 1.0).then_some(self.tolerance_share);
                params
            })
            .collect();
        let params = ConvergenceParams {
            kernel: context.kernel.params(potential, 0.0, 0.0),
            densities: self.densities.clone(),
            offset_bounds: self.offset_bounds.clone(),
            tolerances: self.tolerances.clone(),
            bin_widths: self.bin_widths.clone(),
        };
        Ok(Some((params, variants)))
    }
}
