//! `[dissociation]`: collision-induced dissociation of bound pairs
//! (`A2 + A -> 3A`), for every potential whose family has a well.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check};
use super::collisions::MAX_RANDOMIZATIONS;
use crate::physics::potential::Potential;
use crate::physics::scene::EngineSettings;

/// `[dissociation]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct DissociationConfig {
    /// Run the dissociation stage (potentials with a well only).
    pub enabled: bool,
    /// Scenes per randomization: a power of two (complete scrambled Sobol' nets).
    pub points: u32,
    /// Independent randomizations (their spread is the standard error).
    pub randomizations: u32,
    /// Seed of the scrambles.
    pub seed: u64,
}

impl Default for DissociationConfig {
    fn default() -> Self {
        DissociationConfig {
            enabled: true,
            points: 4096,
            randomizations: 8,
            seed: 34,
        }
    }
}

/// Largest scenes per randomization (`2^20`: a few CPU-hours at `theta = 0.05`).
pub const MAX_DISSOCIATION_POINTS: u32 = 1 << 20;

/// Resolved parameters of one `dissociation` instance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DissociationParams {
    /// The potential (its family has a well).
    pub potential: Potential,
    /// Engine settings.
    pub engine: EngineSettings,
    /// Scenes per randomization.
    pub points: u32,
    /// Randomizations.
    pub randomizations: u32,
    /// Seed.
    pub seed: u64,
}

impl DissociationConfig {
    /// Checks the point count (a power of two within bounds) and the randomizations.
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        check(
            self.points.is_power_of_two() && self.points <= MAX_DISSOCIATION_POINTS,
            "dissociation.points",
            format!(
                "{} must be a power of two up to {MAX_DISSOCIATION_POINTS} (complete Sobol' nets)",
                self.points
            ),
        )?;
        check(
            (2..=MAX_RANDOMIZATIONS).contains(&self.randomizations),
            "dissociation.randomizations",
            format!(
                "{} is outside [2, {MAX_RANDOMIZATIONS}]: at least 2 are needed for a standard error",
                self.randomizations
            ),
        )
    }

    /// The dissociation of `potential`, if enabled and its family has a well.
    pub fn params(
        &self,
        potential: Potential,
        engine: EngineSettings,
    ) -> Option<DissociationParams> {
        (self.enabled && potential.family().has_well()).then_some(DissociationParams {
            potential,
            engine,
            points: self.points,
            randomizations: self.randomizations,
            seed: self.seed,
        })
    }
}
