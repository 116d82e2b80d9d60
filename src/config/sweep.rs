//! `[sweep]`: rates on a `u'` grid, the Fokker-Planck check and detailed balance.

use serde::{Deserialize, Serialize};

use super::KernelParams;
use super::check::{Invalid, MAX_LIST, check};
use super::collisions::{MAX_RANDOMIZATIONS, within_reach};
use crate::physics::sampling::LaunchProposal;

/// `[sweep]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SweepConfig {
    /// Run the sweep stage.
    pub enabled: bool,
    /// Smallest `u'` of the grid.
    pub u_prime_min: f64,
    /// Largest `u'` of the grid.
    pub u_prime_max: f64,
    /// Grid points (>= 3).
    pub points: u32,
    /// Separations `b - a` of the detailed-balance pairs (rounded to whole bins).
    pub balance_separations: Vec<f64>,
    /// Bin width of the detailed-balance kernels.
    pub balance_bin_width: f64,
    /// Launch-proposal spread of the sweep's own scenes (0: reuse the kernel's).
    pub launch_spread: f64,
    /// The sweep's own scenes draw this share of the kernel's points per
    /// randomization (`collisions.points` or its per-potential value).
    pub points_share: f64,
    /// Randomizations of the sweep's own scenes (`None`: the kernel's,
    /// `collisions.randomizations`). The balance pairs' errors come from their
    /// spread, and a pair whose spread one randomization carries is no
    /// evidence: with 8, Gaussian replicates already put over half of it in
    /// one (~`2 ln R / R`), with 32 a fifth.
    pub randomizations: Option<u32>,
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            enabled: true,
            u_prime_min: -3.0,
            u_prime_max: 3.0,
            points: 25,
            balance_separations: vec![0.01, 0.02, 0.04, 0.05],
            balance_bin_width: 0.005,
            launch_spread: 2.0,
            points_share: 1.0,
            randomizations: None,
        }
    }
}

/// Resolved parameters of a `sweep` instance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepParams {
    /// Kernel settings (potential, window, `L`, kick floor; `u'` and density unused).
    pub kernel: KernelParams,
    /// Smallest `u'`.
    pub u_prime_min: f64,
    /// Largest `u'`.
    pub u_prime_max: f64,
    /// Grid points.
    pub points: u32,
    /// Detailed-balance separations.
    pub balance_separations: Vec<f64>,
    /// Detailed-balance bin width.
    pub balance_bin_width: f64,
}

/// Largest `u'` points of the sweep.
pub const MAX_SWEEP_POINTS: u32 = 1001;

impl SweepConfig {
    /// The launch proposal that reaches every `u'` of the sweep and of the
    /// evolution grid: the kernel's, widened to the sweep's launch spread.
    pub(super) fn wide_launch(&self, launch: &LaunchProposal) -> LaunchProposal {
        LaunchProposal {
            spread: self.launch_spread.max(launch.spread),
            ..*launch
        }
    }

    /// Checks the `u'` grid (within reach of `launch`, the wide proposal) and
    /// the detailed-balance pairs.
    pub(super) fn validate(&self, launch: &LaunchProposal) -> Result<(), Invalid> {
        let sweep = self;
        check(
            sweep.u_prime_min.is_finite()
                && sweep.u_prime_max.is_finite()
                && sweep.u_prime_min < sweep.u_prime_max,
            "sweep.u_prime_max",
            format!(
                "must exceed sweep.u_prime_min ({} >= {})",
                sweep.u_prime_min, sweep.u_prime_max
            ),
        )?;
        check(
            within_reach(launch, sweep.u_prime_min) && within_reach(launch, sweep.u_prime_max),
            "sweep.u_prime_min",
            "the grid must lie within reach of the launch proposal (collisions.launch_shift +- (launch_spread + 3))",
        )?;
        check(
            (3..=MAX_SWEEP_POINTS).contains(&sweep.points),
            "sweep.points",
            format!(
                "{} is outside [3, {MAX_SWEEP_POINTS}]: at least 3 points are needed for derivatives",
                sweep.points
            ),
        )?;
        check(
            sweep.launch_spread.is_finite() && (0.0..=3.0).contains(&sweep.launch_spread),
            "sweep.launch_spread",
            format!("{} is outside [0, 3]", sweep.launch_spread),
        )?;
        check(
            sweep.points_share.is_finite() && sweep.points_share > 0.0 && sweep.points_share <= 1.0,
            "sweep.points_share",
            format!("{} is outside (0, 1]", sweep.points_share),
        )?;
        if let Some(randomizations) = sweep.randomizations {
            check(
                (2..=MAX_RANDOMIZATIONS).contains(&randomizations) && sweep.launch_spread > 0.0,
                "sweep.randomizations",
                format!(
                    "{randomizations} must lie in [2, {MAX_RANDOMIZATIONS}], and it needs the sweep's own scenes (sweep.launch_spread > 0)"
                ),
            )?;
        }
        check(
            sweep.balance_bin_width.is_finite() && sweep.balance_bin_width > 0.0,
            "sweep.balance_bin_width",
            format!("{} must be > 0", sweep.balance_bin_width),
        )?;
        check(
            !sweep.balance_separations.is_empty() && sweep.balance_separations.len() <= MAX_LIST,
            "sweep.balance_separations",
            format!(
                "lists {} separations: give 1 to {MAX_LIST}",
                sweep.balance_separations.len()
            ),
        )?;
        for (k, &separation) in sweep.balance_separations.iter().enumerate() {
            check(
                separation >= sweep.balance_bin_width && separation <= 0.5,
                format!("sweep.balance_separations[{k}]"),
                format!("{separation} must lie in [balance_bin_width, 0.5]"),
            )?;
        }
        Ok(())
    }

    /// Resolved parameters of the sweep with `kernel`'s settings, if enabled.
    pub fn params(&self, kernel: KernelParams) -> Option<SweepParams> {
        self.enabled.then(|| SweepParams {
            kernel,
            u_prime_min: self.u_prime_min,
            u_prime_max: self.u_prime_max,
            points: self.points,
            balance_separations: self.balance_separations.clone(),
            balance_bin_width: self.balance_bin_width,
        })
    }
}
