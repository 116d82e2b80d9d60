//! `[engine]`: how three-body scenes are integrated.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check};
use crate::physics::scene::{EngineSettings, Method};

/// `[engine]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct EngineConfig {
    /// Integration method.
    pub method: Method,
    /// Local error tolerance per step, in (0, 1e-3].
    pub tolerance: f64,
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
            max_steps: 100_000,
            free_flight: true,
        }
    }
}

impl EngineConfig {
    /// Checks the tolerance and the step budget.
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        check(
            (1e-16..=1e-3).contains(&self.tolerance),
            "engine.tolerance",
            format!(
                "{} is outside [1e-16, 1e-3] (below 1e-16 no step meets it in double precision); 1e-12 is a good default",
                self.tolerance
            ),
        )?;
        check(
            self.max_steps >= 1,
            "engine.max_steps",
            "must be at least 1",
        )
    }

    /// Engine settings as the physics sees them.
    pub fn settings(&self) -> EngineSettings {
        EngineSettings {
            method: self.method,
            tolerance: self.tolerance,
            max_steps: self.max_steps,
            free_flight: self.free_flight,
        }
    }
}
