//! `[spectrum]`: the relaxation spectrum of the linearized three-body
//! collision operator and of the tagged particle's generator, per potential.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check};
use super::evolve::check_grid;
use super::{KernelConfig, KernelParams};
use crate::physics::potential::Potential;
use crate::physics::sampling::LaunchProposal;

/// `[spectrum]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpectrumConfig {
    /// Run the spectrum stage for every potential.
    pub enabled: bool,
    /// The grid spans `[-velocity_range, velocity_range]`, `v_th`. The
    /// slowest modes reach far into the tails (a third of their norm lies
    /// beyond `|u| = 2.5`): for `n = 6` the gaps move 2% from 4 to 5
    /// (docs/spectrum.md).
    pub velocity_range: f64,
    /// Node spacing, `v_th`. The detailed-balance estimator's rates move
    /// 0.5% from 0.1 to 0.025 (`n = 6`); the columns' need 0.05 or finer
    /// (docs/spectrum.md, "Two estimators").
    pub grid_step: f64,
    /// Slowest modes whose shapes `g(u)` are written, per generator.
    pub modes: u32,
    /// The `near_integrable` stage fits how the rates vanish as `n -> 2+`
    /// over the inverse power laws with `2 < n <=` this (at least four).
    /// Its law `A (n - 2)^p exp(q (n - 2))` holds to `n = 2.5` within the
    /// rates' 0.2%; out to `n = 3` the next order shows (docs/spectrum.md).
    pub near_integrable_max_n: f64,
    /// How the generators are estimated from the scenes.
    pub estimator: SpectrumEstimator,
}

/// How the `spectrum` stage estimates the generators from the scenes
/// (`evolve::operator`).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SpectrumEstimator {
    /// `evolve`'s: each column the kernel of the special particle at its node,
    /// symmetrized with `f0` (detailed balance holds only on average: noise
    /// gives growing modes).
    Columns,
    /// The Dirichlet form `-c sum mu Delta Delta^T` that detailed balance
    /// makes of it: symmetric and negative semi-definite for every sample,
    /// and noise proportional to the rates where the scattering is nearly
    /// integrable.
    DetailedBalance,
}

impl Default for SpectrumConfig {
    fn default() -> Self {
        SpectrumConfig {
            enabled: true,
            velocity_range: 5.0,
            grid_step: 0.1,
            modes: 4,
            near_integrable_max_n: 2.5,
            estimator: SpectrumEstimator::DetailedBalance,
        }
    }
}

/// Largest `spectrum.modes`.
pub const MAX_SPECTRUM_MODES: u32 = 50;

/// Resolved parameters of one `spectrum` instance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpectrumParams {
    /// Kernel settings at `u' = 0`, dilute (potential, kick floor).
    pub kernel: KernelParams,
    /// Grid half-range, `v_th`.
    pub velocity_range: f64,
    /// Grid step, `v_th`.
    pub grid_step: f64,
    /// Shapes written per generator.
    pub modes: u32,
    /// How the generators are estimated.
    pub estimator: SpectrumEstimator,
}

impl SpectrumConfig {
    /// Checks the grid (as `[evolve]`'s: within reach of the wide launch
    /// proposal `wide`) and the number of shapes.
    pub(super) fn validate(&self, wide: &LaunchProposal) -> Result<(), Invalid> {
        check_grid("spectrum", self.velocity_range, self.grid_step, wide)?;
        check(
            self.near_integrable_max_n > 2.0 && self.near_integrable_max_n.is_finite(),
            "spectrum.near_integrable_max_n",
            format!("{} is not a finite n above 2", self.near_integrable_max_n),
        )?;
        check(
            (1..=MAX_SPECTRUM_MODES).contains(&self.modes),
            "spectrum.modes",
            format!("{} is outside [1, {MAX_SPECTRUM_MODES}]", self.modes),
        )
    }

    /// Whether the `near_integrable` fit takes `potential` (with a spectrum):
    /// an inverse power law with `2 < n <= near_integrable_max_n`.
    pub fn near_integrable(&self, potential: Potential) -> bool {
        let family = potential.family();
        family.theta().is_none()
            && family
                .length_exponent()
                .is_some_and(|n| n > 2.0 && n <= self.near_integrable_max_n)
    }

    /// The spectrum of `potential`, if enabled.
    pub fn params(&self, kernel: &KernelConfig, potential: Potential) -> Option<SpectrumParams> {
        self.enabled.then(|| SpectrumParams {
            kernel: kernel.params(potential, 0.0, 0.0),
            velocity_range: self.velocity_range,
            grid_step: self.grid_step,
            modes: self.modes,
            estimator: self.estimator,
        })
    }
}
