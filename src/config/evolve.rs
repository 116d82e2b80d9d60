//! `[evolve]`: evolution of `h(u, t)` from `delta(u - u')` (physics.md §4).

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, check_length, positive, potential_named};
use super::collisions::{REWEIGHTING_REACH, within_reach};
use super::{GasParams, KernelConfig, KernelParams, MAX_BINS};
use crate::physics::potential::Potential;
use crate::physics::sampling::LaunchProposal;

/// `[evolve]`: evolution of `h(u, t)` from `delta(u - u')` (physics.md §4).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct EvolveConfig {
    /// Run the evolve stage.
    pub enabled: bool,
    /// Id of the configured potential (`ipp-6`).
    pub potential: String,
    /// Start velocity `u'` (a node of the grid: a multiple of `grid_step`).
    pub u_prime: f64,
    /// Times of the master-equation evolution, in units of `1/Gamma`.
    pub times: Vec<f64>,
    /// Times of the translation-invariant (convolution) evolution, `1/Gamma`.
    pub early_times: Vec<f64>,
    /// Output bin width of the early `h` (an odd multiple of `kernel.bin_width`).
    pub early_bin_width: f64,
    /// Half-width of the early `h` output around `u'`.
    pub early_range: f64,
    /// The master-equation grid spans `[-velocity_range, velocity_range]`.
    pub velocity_range: f64,
    /// Node spacing of the master-equation grid.
    pub grid_step: f64,
    /// A configured `[[gas]]` whose physical times `times_ns` are added.
    pub gas: Option<String>,
    /// Times in ns for `gas` (converted with its `rho^2 l v_th`).
    pub times_ns: Vec<f64>,
}

impl Default for EvolveConfig {
    fn default() -> Self {
        EvolveConfig {
            enabled: false,
            potential: "ipp-6".into(),
            u_prime: 0.0,
            times: vec![0.01, 0.1, 0.3, 1.0, 2.0, 4.0, 8.0],
            early_times: vec![1e-4, 1e-3, 1e-2],
            early_bin_width: 1.05e-3,
            early_range: 0.3,
            velocity_range: 4.0,
            grid_step: 0.05,
            gas: None,
            times_ns: Vec::new(),
        }
    }
}

/// Resolved parameters of the `evolve` stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EvolveParams {
    /// Kernel settings at `u'` (potential, window, bin width, kick floor).
    pub kernel: KernelParams,
    /// Master-equation times, `1/Gamma`.
    pub times: Vec<f64>,
    /// Convolution times, `1/Gamma`.
    pub early_times: Vec<f64>,
    /// Fine bins per early output bin (odd).
    pub early_rebin: u32,
    /// Half-width of the early output.
    pub early_range: f64,
    /// Grid half-range.
    pub velocity_range: f64,
    /// Grid step.
    pub grid_step: f64,
    /// Physical times: the gas, its times in ns, and the same in `1/(rho^2 l v_th)`.
    pub physical: Option<PhysicalTimes>,
}

/// Times of a gas in physical units.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhysicalTimes {
    /// Gas name.
    pub gas: String,
    /// Times, ns.
    pub times_ns: Vec<f64>,
    /// The same times in units of `1/(rho^2 l v_th)`.
    pub times_scaled: Vec<f64>,
}

/// Largest `evolve.velocity_range / evolve.grid_step` (801 nodes).
pub const MAX_EVOLVE_HALF_NODES: f64 = 400.0;

/// Latest time `evolve` propagates to, in `1/Gamma` (or, for `times_ns`, in
/// `1/(rho^2 l v_th)`): the slowest mode has decayed by `e^-400` long before.
pub const MAX_EVOLVE_TIME: f64 = 1e3;

/// What the evolve stage needs of the other sections.
pub(super) struct Context<'a> {
    /// The configured potentials.
    pub potentials: &'a [Potential],
    /// The resolved gases.
    pub gases: &'a [GasParams],
    /// `[kernel]`.
    pub kernel: &'a KernelConfig,
    /// The kernel's launch proposal.
    pub launch: &'a LaunchProposal,
    /// The wide launch proposal (the sweep's).
    pub wide: &'a LaunchProposal,
}

impl EvolveConfig {
    /// Checks the grid, the times and the gas, and resolves the stage's
    /// parameters, if enabled.
    pub(super) fn resolve(&self, context: &Context) -> Result<Option<EvolveParams>, Invalid> {
        if !self.enabled {
            return Ok(None);
        }
        let potential = potential_named(&self.potential, context.potentials, "evolve.potential")?;
        self.validate(context)?;
        let gas = self.gas(context.gases)?;
        let kernel = context.kernel.params(potential, self.u_prime, 0.0);
        let sorted = |times: &[f64]| {
            let mut sorted = times.to_vec();
            sorted.sort_by(f64::total_cmp);
            sorted.dedup();
            sorted
        };
        let physical = gas.map(|gas| {
            let times_ns = sorted(&self.times_ns);
            let unit = gas
                .gas
                .rate_per_ns(1.0, potential.family().length_exponent());
            PhysicalTimes {
                gas: gas.name.clone(),
                times_scaled: times_ns.iter().map(|t| t * unit).collect(),
                times_ns,
            }
        });
        if let Some(times) = &physical {
            let longest = times.times_scaled.iter().copied().fold(0.0, f64::max);
            check(
                longest <= MAX_EVOLVE_TIME,
                "evolve.times_ns",
                format!(
                    "{} ns is {longest:e} / (rho^2 l v_th) of `{}`, beyond {MAX_EVOLVE_TIME} (relaxed long before)",
                    times.times_ns.last().copied().unwrap_or_default(),
                    times.gas
                ),
            )?;
        }
        Ok(Some(EvolveParams {
            kernel,
            times: sorted(&self.times),
            early_times: sorted(&self.early_times),
            early_rebin: (self.early_bin_width / kernel.bin_width).round() as u32,
            early_range: self.early_range,
            velocity_range: self.velocity_range,
            grid_step: self.grid_step,
            physical,
        }))
    }

    /// The `[[gas]]` whose units convert `times_ns`, if any.
    fn gas<'a>(&self, gases: &'a [GasParams]) -> Result<Option<&'a GasParams>, Invalid> {
        let Some(name) = &self.gas else {
            check(
                self.times_ns.is_empty(),
                "evolve.times_ns",
                "needs evolve.gas (the gas whose units convert them)",
            )?;
            return Ok(None);
        };
        let gas = gases
            .iter()
            .find(|g| &g.name == name && g.potential.id() == self.potential);
        check(
            gas.is_some(),
            "evolve.gas",
            format!(
                "`{name}` is no gas.name of a [[gas]] with potential {} (those with it: {})",
                self.potential,
                gases
                    .iter()
                    .filter(|g| g.potential.id() == self.potential)
                    .map(|g| format!("`{}`", g.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )?;
        Ok(gas)
    }

    /// Checks the grid, the early bins and the times.
    fn validate(&self, context: &Context) -> Result<(), Invalid> {
        let evolve = self;
        let (launch, wide) = (context.launch, context.wide);
        check_grid("evolve", evolve.velocity_range, evolve.grid_step, wide)?;
        for (name, value) in [
            ("early_bin_width", evolve.early_bin_width),
            ("early_range", evolve.early_range),
        ] {
            check(
                positive(value),
                format!("evolve.{name}"),
                format!("{value} must be > 0"),
            )?;
        }
        check(
            evolve.early_range / evolve.early_bin_width <= MAX_BINS,
            "evolve.early_bin_width",
            "more than a million early bins: widen the bins or narrow evolve.early_range",
        )?;
        let nodes = evolve.u_prime / evolve.grid_step;
        check(
            evolve.u_prime.is_finite()
                && (nodes - nodes.round()).abs() < 1e-9
                && evolve.u_prime.abs() < evolve.velocity_range
                && within_reach(launch, evolve.u_prime),
            "evolve.u_prime",
            format!(
                "{} must be a multiple of evolve.grid_step ({}) inside the grid and within reach of the launch proposal",
                evolve.u_prime, evolve.grid_step
            ),
        )?;
        let ratio = evolve.early_bin_width / context.kernel.bin_width;
        check(
            (ratio - ratio.round()).abs() < 1e-6 && ratio.round() as u64 % 2 == 1,
            "evolve.early_bin_width",
            format!(
                "{} must be an odd multiple of kernel.bin_width ({})",
                evolve.early_bin_width, context.kernel.bin_width
            ),
        )?;
        for (name, times) in [
            ("times", &evolve.times),
            ("early_times", &evolve.early_times),
            ("times_ns", &evolve.times_ns),
        ] {
            check_length(times, &format!("evolve.{name}"))?;
            let in_gamma = name != "times_ns";
            for (k, &t) in times.iter().enumerate() {
                check(
                    positive(t) && (t <= MAX_EVOLVE_TIME || !in_gamma),
                    format!("evolve.{name}[{k}]"),
                    format!(
                        "{t} must lie in (0, {MAX_EVOLVE_TIME}] (1/Gamma: relaxed long before)"
                    ),
                )?;
            }
        }
        check(
            !evolve.times.is_empty() || !evolve.times_ns.is_empty(),
            "evolve.times",
            "lists no time (give times or gas with times_ns)",
        )
    }
}

/// Checks a master-equation grid `[-range, range]` of spacing `step` given
/// as `{section}.velocity_range` and `{section}.grid_step`: both positive, at
/// least two steps, at most [`MAX_EVOLVE_HALF_NODES`] per side, and within
/// reach of the wide launch proposal `wide` (whose scenes fill it).
pub(super) fn check_grid(
    section: &str,
    range: f64,
    step: f64,
    wide: &LaunchProposal,
) -> Result<(), Invalid> {
    for (name, value) in [("grid_step", step), ("velocity_range", range)] {
        check(
            positive(value),
            format!("{section}.{name}"),
            format!("{value} must be > 0"),
        )?;
    }
    check(
        range >= 2.0 * step,
        format!("{section}.velocity_range"),
        "must span at least two grid steps",
    )?;
    check(
        range / step <= MAX_EVOLVE_HALF_NODES,
        format!("{section}.grid_step"),
        format!(
            "more than {} grid nodes (dense generators of n^2 entries, exponentials in n^3): widen the step",
            2.0 * MAX_EVOLVE_HALF_NODES + 1.0
        ),
    )?;
    check(
        within_reach(wide, range) && within_reach(wide, -range),
        format!("{section}.velocity_range"),
        format!(
            "+-{range} is beyond the reach of the wide launch proposal (collisions.launch_shift {} +- (sweep.launch_spread {} + {REWEIGHTING_REACH})): widen sweep.launch_spread",
            wide.shift, wide.spread
        ),
    )
}
