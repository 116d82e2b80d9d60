//! `[kernel]`: the kernel's targets `(u', density)`, bins and shape fit.

use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use super::check::{Invalid, MAX_LIST, check};
use super::collisions::{REWEIGHTING_REACH, within_reach};
use crate::physics::potential::Potential;
use crate::physics::sampling::LaunchProposal;

use crate::kernel::Target;
pub use crate::thresholds::DEFAULT_KICK_FLOOR;

/// Widest velocity window (`v_th`): `u' +- 6`, beyond the largest launch
/// speed the point sets draw (6.8 `v_th`) from any `u'` within reach.
pub const MAX_WINDOW: f64 = 12.0;

/// Exactly two numbers `[min, max]` (a third was silently dropped).
fn two_numbers<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<[f64; 2], D::Error> {
    use serde::de::Error;
    let values = Vec::<f64>::deserialize(deserializer)?;
    <[f64; 2]>::try_from(values.as_slice())
        .map_err(|_| D::Error::invalid_length(values.len(), &"two numbers [min, max]"))
}

/// `[kernel]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct KernelConfig {
    /// Velocities `u'` of the special particle (units of `v_th`).
    pub u_prime: Vec<f64>,
    /// Densities `rho * l`; 0 is the dilute limit.
    pub density: Vec<f64>,
    /// Total width of the velocity window around `u'`.
    pub window: f64,
    /// Histogram bin width.
    pub bin_width: f64,
    /// Observation region length `L` (in `l`), for the finite-density weight.
    pub launch_length: f64,
    /// Velocity changes up to this size (`v_th`) count as zero (engine error floor).
    pub kick_floor: f64,
    /// Range of `|u - u'|` of the shape fit, `[min, max]` (exactly two numbers).
    #[serde(deserialize_with = "two_numbers")]
    pub fit_range: [f64; 2],
    /// Truncation half-widths `X` (`v_th`) added to the `moments` grid, e.g.
    /// the paper's `X = 0.04` (its Table I).
    pub truncations: Vec<f64>,
}

/// The paper's truncation: its kernel moments (Table I) count `|u - u'| <= 0.04` only.
pub const PAPER_TRUNCATION: f64 = 0.04;

impl Default for KernelConfig {
    fn default() -> Self {
        KernelConfig {
            u_prime: vec![0.0],
            density: vec![0.0],
            window: 0.2,
            bin_width: 0.1 / 2000.0,
            launch_length: 90.0,
            kick_floor: DEFAULT_KICK_FLOOR,
            fit_range: [2e-4, 0.05],
            truncations: vec![PAPER_TRUNCATION],
        }
    }
}

/// Resolved parameters of a `fit` instance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FitParams {
    /// The kernel it fits.
    pub kernel: KernelParams,
    /// Smallest `|u - u'|` fitted.
    pub range_min: f64,
    /// Largest `|u - u'|` fitted.
    pub range_max: f64,
    /// Largest `|u - u'|` of the fit under the paper's protocol: its truncation.
    pub paper_range_max: f64,
}

/// Resolved parameters of a `kernel` or `moments` instance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct KernelParams {
    /// The potential (identifies the input).
    pub potential: Potential,
    /// `u'`.
    pub u_prime: f64,
    /// `rho * l`.
    pub density: f64,
    /// Window width.
    pub window: f64,
    /// Bin width.
    pub bin_width: f64,
    /// `L`.
    pub launch_length: f64,
    /// Velocity changes up to this size count as zero.
    pub kick_floor: f64,
}

impl KernelParams {
    /// The `u'`, density, observation length and kick floor the events are
    /// reweighted to.
    pub fn target(&self) -> Target {
        Target {
            u_prime: self.u_prime,
            density: self.density,
            launch_length: self.launch_length,
            kick_floor: self.kick_floor,
        }
    }

    /// The window's edge: the largest `|u - u'|` the kernel's window holds,
    /// half the window, `v_th`. Kicks reach past it: an inverse power law's
    /// rarely (`n = 6`: up to ~0.12 `v_th` from launches near 4 `v_th`, 1.5e-4
    /// of `a_6` beyond 0.1), a well's free atoms often (Lennard-Jones at
    /// `theta = 0.1`: `a(X)` grows 16-fold from `X = 0.1` and levels off near
    /// `X = 1.6`), so `a_n` is read untruncated.
    pub fn edge(&self) -> f64 {
        0.5 * self.window
    }
}

/// Largest histogram bins of a kernel or an early evolution.
pub const MAX_BINS: f64 = 1e6;

impl KernelConfig {
    /// The window's edge, half the window (`v_th`), as every kernel of the
    /// study resolves it ([`KernelParams::edge`]).
    pub fn edge(&self) -> f64 {
        0.5 * self.window
    }

    /// Checks the targets (within reach of the launch proposal), the bins and the fit range.
    pub(super) fn validate(&self, launch: &LaunchProposal) -> Result<(), Invalid> {
        let kernel = self;
        check(
            !kernel.u_prime.is_empty() && kernel.u_prime.len() <= MAX_LIST,
            "kernel.u_prime",
            format!(
                "lists {} velocities: give 1 to {MAX_LIST}",
                kernel.u_prime.len()
            ),
        )?;
        for (k, &u) in kernel.u_prime.iter().enumerate() {
            check(
                u.is_finite() && within_reach(launch, u),
                format!("kernel.u_prime[{k}]"),
                format!(
                    "{u} is beyond the reach of the launch proposal (launch_shift {} +- (launch_spread {} + {REWEIGHTING_REACH})): widen launch_spread",
                    launch.shift, launch.spread
                ),
            )?;
        }
        check(
            !kernel.density.is_empty() && kernel.density.len() <= MAX_LIST,
            "kernel.density",
            format!(
                "lists {} densities: give 1 to {MAX_LIST}",
                kernel.density.len()
            ),
        )?;
        for (k, &density) in kernel.density.iter().enumerate() {
            check(
                density.is_finite() && (0.0..=0.1).contains(&density),
                format!("kernel.density[{k}]"),
                format!("rho*l = {density} is outside [0, 0.1] (the model is for dilute gases)"),
            )?;
        }
        check(
            kernel.bin_width.is_finite() && kernel.bin_width > 0.0,
            "kernel.bin_width",
            format!("{} must be > 0", kernel.bin_width),
        )?;
        check(
            kernel.window.is_finite() && kernel.window > 0.0 && kernel.window <= MAX_WINDOW,
            "kernel.window",
            format!(
                "{} is outside (0, {MAX_WINDOW}] (every velocity the launches reach)",
                kernel.window
            ),
        )?;
        check(
            kernel.window >= 3.0 * kernel.bin_width,
            "kernel.bin_width",
            format!(
                "{} is wider than a third of kernel.window = {}: the window holds at least 3 bins",
                kernel.bin_width, kernel.window
            ),
        )?;
        check(
            kernel.window / kernel.bin_width <= MAX_BINS,
            "kernel.bin_width",
            "more than a million bins: widen the bins or narrow the window",
        )?;
        check(
            kernel.launch_length.is_finite() && kernel.launch_length > 0.0,
            "kernel.launch_length",
            format!("L = {} must be > 0", kernel.launch_length),
        )?;
        check(
            kernel.truncations.len() <= MAX_LIST,
            "kernel.truncations",
            format!(
                "lists {} truncations: give at most {MAX_LIST}",
                kernel.truncations.len()
            ),
        )?;
        for (k, &x) in kernel.truncations.iter().enumerate() {
            check(
                x.is_finite() && x > 0.0 && x <= kernel.edge(),
                format!("kernel.truncations[{k}]"),
                format!(
                    "X = {x} must be in (0, kernel.window / 2 = {}]",
                    kernel.edge()
                ),
            )?;
        }
        check(
            kernel.kick_floor >= 0.0 && kernel.kick_floor < 0.5 * kernel.bin_width,
            "kernel.kick_floor",
            format!("{} must lie in [0, bin_width/2)", kernel.kick_floor),
        )?;
        let [low, high] = kernel.fit_range;
        check(
            low > 0.0 && low < high && high <= kernel.edge() && low < PAPER_TRUNCATION,
            "kernel.fit_range",
            format!(
                "[{low}, {high}] must satisfy 0 < min < max <= window/2 and min < {PAPER_TRUNCATION} (the paper's truncation, where its protocol's fit ends)"
            ),
        )
    }

    /// Every `(u', density)` the kernel is evaluated at, with `(0, 0)` (which
    /// defines `a_n`) always first.
    pub fn targets(&self) -> Vec<(f64, f64)> {
        let mut targets = vec![(0.0, 0.0)];
        // Bit patterns of the pairs so far (`+ 0.0` makes -0 and 0 one).
        let mut seen = BTreeSet::from([(0f64.to_bits(), 0f64.to_bits())]);
        for &u in &self.u_prime {
            for &density in &self.density {
                if seen.insert(((u + 0.0).to_bits(), (density + 0.0).to_bits())) {
                    targets.push((u, density));
                }
            }
        }
        targets
    }

    /// Resolved kernel parameters of `potential` at `(u', density)`.
    pub fn params(&self, potential: Potential, u_prime: f64, density: f64) -> KernelParams {
        KernelParams {
            potential,
            u_prime,
            density,
            window: self.window,
            bin_width: self.bin_width,
            launch_length: self.launch_length,
            kick_floor: self.kick_floor,
        }
    }

    /// Resolved parameters of the shape fit of a kernel.
    pub fn fit(&self, kernel: KernelParams) -> FitParams {
        let [range_min, range_max] = self.fit_range;
        FitParams {
            kernel,
            range_min,
            range_max,
            paper_range_max: PAPER_TRUNCATION,
        }
    }
}
