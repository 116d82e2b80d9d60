//! `[limits]`: the largest study `run` and `slurm submit` start without
//! `--i-know`, by the plan's estimate of CPU time and store size.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, positive};

/// `[limits]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsConfig {
    /// Largest estimated CPU time of the whole study, hours.
    pub cpu_hours: f64,
    /// Largest estimated store size of the whole study, GB.
    pub store_gb: f64,
}

impl Default for LimitsConfig {
    /// A thousand CPU-hours (a few days of a 16-core node; the default
    /// study takes a quarter to half of one CPU-hour) and 100 GB (the
    /// publication settings write ~10 GB).
    fn default() -> Self {
        LimitsConfig {
            cpu_hours: 1000.0,
            store_gb: 100.0,
        }
    }
}

impl LimitsConfig {
    /// Both limits are finite and positive.
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        check(
            positive(self.cpu_hours),
            "limits.cpu_hours",
            format!("{} must be a finite number > 0", self.cpu_hours),
        )?;
        check(
            positive(self.store_gb),
            "limits.store_gb",
            format!("{} must be a finite number > 0", self.store_gb),
        )
    }
}
