//! `[engine]`: how three-body scenes are integrated.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, potential_named};
use crate::physics::potential::Potential;
use crate::physics::scene::{EngineSettings, Method};

/// `[engine]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct EngineConfig {
    /// Integration method.
    pub method: Method,
    /// Local error tolerance per step, in [1e-16, 1e-3].
    pub tolerance: f64,
    /// Tolerances of single potentials by id, overriding `tolerance` for
    /// every scene of that potential (`[engine.tolerance_per_potential]`,
    /// e.g. `"lj-0.05" = 1e-10`).
    pub tolerance_per_potential: BTreeMap<String, f64>,
    /// Step attempts before a scene counts as failed.
    pub max_steps: u32,
    /// Skip free flight analytically (exact along the asymptotes).
    pub free_flight: bool,
}

impl Default for EngineConfig {
    fn default() -> Self {
        EngineConfig {
            method: Method::Dprkn12,
            tolerance: 1e-12,
            tolerance_per_potential: BTreeMap::new(),
            max_steps: 100_000,
            free_flight: true,
        }
    }
}

impl EngineConfig {
    /// Checks the tolerances (each override naming a configured
    /// potential) and the step budget.
    pub(super) fn validate(&self, potentials: &[Potential]) -> Result<(), Invalid> {
        check_tolerance(self.tolerance, "engine.tolerance")?;
        for (id, &tolerance) in &self.tolerance_per_potential {
            let key = format!("engine.tolerance_per_potential.{id}");
            potential_named(id, potentials, key.clone())?;
            check_tolerance(tolerance, &key)?;
        }
        check(
            self.max_steps >= 1,
            "engine.max_steps",
            "must be at least 1",
        )
    }

    /// Engine settings of the scenes of `potential` as the physics sees
    /// them: its `tolerance_per_potential` entry, else `tolerance`.
    pub fn settings(&self, potential: &Potential) -> EngineSettings {
        let own = self.tolerance_per_potential.get(&potential.id());
        self.settings_at(own.copied().unwrap_or(self.tolerance))
    }

    /// The study-wide settings (`tolerance`), for benchmarks of potentials
    /// the study need not hold.
    pub fn study_settings(&self) -> EngineSettings {
        self.settings_at(self.tolerance)
    }

    fn settings_at(&self, tolerance: f64) -> EngineSettings {
        EngineSettings {
            method: self.method,
            tolerance,
            max_steps: self.max_steps,
            free_flight: self.free_flight,
        }
    }
}

/// Checks a tolerance given as `key`.
fn check_tolerance(tolerance: f64, key: &str) -> Result<(), Invalid> {
    check(
        (1e-16..=1e-3).contains(&tolerance),
        key,
        format!(
            "{tolerance} is outside [1e-16, 1e-3] (below 1e-16 no step meets it in double precision); 1e-12 is a good default"
        ),
    )
}
