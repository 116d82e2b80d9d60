//! `[md]` and `[[md.system]]`: molecular dynamics of rings (physics.md §7).

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, check_name, positive};
use super::scan::MAX_LAUNCH_SPEED;
use super::{GasConfig, GasParams};
use crate::physics::potential::Potential;
use crate::physics::units::PhysicalGas;

/// `[md]`: molecular dynamics of rings (physics.md §7).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MdConfig {
    /// Run the md stage.
    pub enabled: bool,
    /// Independent runs per system.
    pub runs: u32,
    /// Seed of the runs' streams.
    pub seed: u64,
    /// Interacting neighbours on each side.
    pub neighbours: u32,
    /// Integrator tolerance.
    pub tolerance: f64,
    /// Estimator window around `u'`.
    pub window: f64,
    /// Estimator bin width.
    pub bin_width: f64,
    /// Sample times per run, spread evenly over `t_f (1 +- sample_spread)`.
    pub samples: u32,
    /// Half-width of the sampling window as a fraction of `t_f`.
    pub sample_spread: f64,
    /// Lineages starting within this distance of `u'` enter the tagged estimator.
    pub start_band: f64,
    /// The rings.
    pub system: Vec<MdSystemConfig>,
}

impl Default for MdConfig {
    fn default() -> Self {
        MdConfig {
            enabled: false,
            runs: 16,
            seed: 1,
            neighbours: 3,
            tolerance: 1e-10,
            window: 0.2,
            bin_width: 0.01,
            samples: 5,
            sample_spread: 0.02,
            start_band: 0.1,
            system: Vec::new(),
        }
    }
}

/// `[[md.system]]`: one ring.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MdSystemConfig {
    /// Label.
    pub name: String,
    /// A `[[gas]]` given as a ring (`ring_particles`, `ring_radius_um`).
    pub gas: String,
    /// Velocity `u'` of the special particle.
    #[serde(default)]
    pub u_prime: f64,
    /// Final time `t_f`, ns.
    pub final_time_ns: f64,
    /// Runs of this ring (default `md.runs`): cheap small rings can buy the
    /// precision a finite-size study needs.
    pub runs: Option<u32>,
}

/// Resolved parameters of one `md` instance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MdParams {
    /// Label.
    pub name: String,
    /// The potential (an inverse power law or Lennard-Jones).
    pub potential: Potential,
    /// The gas.
    pub gas: PhysicalGas,
    /// Particles `N`.
    pub particles: u32,
    /// Ring radius, um.
    pub radius_um: f64,
    /// Circumference in `l`.
    pub circumference: f64,
    /// `u'`.
    pub u_prime: f64,
    /// `t_f`, ns.
    pub final_time_ns: f64,
    /// Sample times, ns.
    pub sample_times_ns: Vec<f64>,
    /// Sample times, `l / v_th`.
    pub sample_times: Vec<f64>,
    /// Runs.
    pub runs: u32,
    /// Seed.
    pub seed: u64,
    /// Neighbours per side.
    pub neighbours: u32,
    /// Tolerance.
    pub tolerance: f64,
    /// Window.
    pub window: f64,
    /// Bin width.
    pub bin_width: f64,
    /// Tagged-estimator start band.
    pub start_band: f64,
}

/// Largest MD runs per ring.
pub const MAX_MD_RUNS: u32 = 1 << 16;

/// Largest interacting neighbours per side.
pub const MAX_NEIGHBOURS: u32 = 64;

impl MdParams {
    /// `rho l` of the ring's gas (as the `gases` stage computes it).
    pub fn scaled_density(&self) -> f64 {
        self.gas
            .scaled_density(self.potential.family().length_exponent())
    }

    /// The final time `t_f` in units of the ring's own `1 / (rho^2 l v_th)`:
    /// rings at equal values are the same dilute physics (the scaling collapse).
    pub fn scaled_final_time(&self) -> f64 {
        let exponent = self.potential.family().length_exponent();
        self.final_time_ns * self.gas.rate_per_ns(1.0, exponent)
    }
}

/// Most velocity bins of a ring's estimator window (`md.window / md.bin_width`).
pub const MAX_MD_BINS: f64 = 1e5;

/// Largest sample times per ring.
pub const MAX_MD_SAMPLES: u32 = 1000;

/// Largest neighbour encounters per MD run, `N rho v_th t_f` (the published
/// ring N = 161, R = 51200 um, 12800 ns has 1.4e5).
pub const MAX_RING_ENCOUNTERS: f64 = 1e9;

impl MdConfig {
    /// Checks the settings and every ring, and resolves one `md` instance per
    /// ring (none when disabled). `configs` are the `[[gas]]` entries and
    /// `gases` the same resolved.
    pub(super) fn resolve(
        &self,
        configs: &[GasConfig],
        gases: &[GasParams],
    ) -> Result<Vec<MdParams>, Invalid> {
        if !self.enabled {
            return Ok(Vec::new());
        }
        self.validate()?;
        self.system
            .iter()
            .enumerate()
            .map(|(k, system)| self.ring(k, system, configs, gases))
            .collect()
    }

    /// Checks the settings shared by the rings.
    fn validate(&self) -> Result<(), Invalid> {
        check(
            (2..=MAX_MD_RUNS).contains(&self.runs),
            "md.runs",
            format!(
                "{} is outside [2, {MAX_MD_RUNS}] (errors come from the runs' spread)",
                self.runs
            ),
        )?;
        check(
            (1..=MAX_NEIGHBOURS).contains(&self.neighbours),
            "md.neighbours",
            format!("{} is outside [1, {MAX_NEIGHBOURS}]", self.neighbours),
        )?;
        check(
            self.tolerance > 0.0 && self.tolerance <= 1e-6,
            "md.tolerance",
            format!("{} is outside (0, 1e-6]", self.tolerance),
        )?;
        check(
            self.window > 0.0 && self.window <= 2.0 * MAX_LAUNCH_SPEED,
            "md.window",
            format!(
                "{} is outside (0, {}] v_th",
                self.window,
                2.0 * MAX_LAUNCH_SPEED
            ),
        )?;
        check(
            self.bin_width > 0.0
                && self.bin_width <= self.window
                && self.window / self.bin_width <= MAX_MD_BINS,
            "md.bin_width",
            format!(
                "{} must be in [md.window / {MAX_MD_BINS}, md.window] (md.window = {})",
                self.bin_width, self.window
            ),
        )?;
        check(
            (1..=MAX_MD_SAMPLES).contains(&self.samples),
            "md.samples",
            format!("{} is outside [1, {MAX_MD_SAMPLES}]", self.samples),
        )?;
        check(
            (0.0..0.5).contains(&self.sample_spread),
            "md.sample_spread",
            format!("{} is outside [0, 0.5)", self.sample_spread),
        )?;
        check(self.start_band > 0.0, "md.start_band", "must be > 0")?;
        check(!self.system.is_empty(), "md.system", "lists no ring")
    }

    /// Checks ring `k` and resolves its parameters.
    fn ring(
        &self,
        k: usize,
        system: &MdSystemConfig,
        configs: &[GasConfig],
        gases: &[GasParams],
    ) -> Result<MdParams, Invalid> {
        let key = |name: &str| format!("md.system[{k}].{name}");
        check_name(&system.name, key("name"))?;
        check(
            self.system.iter().filter(|s| s.name == system.name).count() == 1,
            key("name"),
            format!("`{}` is used twice", system.name),
        )?;
        let ring = configs
            .iter()
            .zip(gases)
            .find(|(config, _)| config.name == system.gas)
            .and_then(|(config, gas)| Some((config.ring_particles?, config.ring_radius_um?, gas)));
        let Some((particles, radius_um, resolved)) = ring else {
            return Err((
                key("gas"),
                format!(
                    "`{}` is no gas.name of a [[gas]] given as a ring (ring_particles, ring_radius_um)",
                    system.gas
                ),
            ));
        };
        let potential = resolved.potential;
        if let Some(obstacle) = potential.family().ring_obstacle() {
            return Err((
                key("gas"),
                format!("{obstacle}: `{}` cannot run", potential.id()),
            ));
        }
        check(
            positive(system.final_time_ns),
            key("final_time_ns"),
            format!("{} must be > 0", system.final_time_ns),
        )?;
        check(
            system.u_prime.is_finite() && system.u_prime.abs() <= MAX_LAUNCH_SPEED,
            key("u_prime"),
            format!(
                "{} is outside +-{MAX_LAUNCH_SPEED} v_th (the scans' fastest launch)",
                system.u_prime
            ),
        )?;
        let gas = resolved.gas;
        // The special particle at `u'` meets `|u'|` thermal particles' worth.
        let encounters = (f64::from(particles) + system.u_prime.abs())
            * gas.density_per_um
            * gas.thermal_speed_um_per_ns()
            * system.final_time_ns;
        check(
            encounters <= MAX_RING_ENCOUNTERS,
            key("final_time_ns"),
            format!(
                "{} ns gives ~{encounters:.1e} neighbour encounters per run ((N + |u'|) rho v_th t_f), more than {MAX_RING_ENCOUNTERS:.0e}",
                system.final_time_ns
            ),
        )?;
        check(
            system
                .runs
                .is_none_or(|runs| (2..=MAX_MD_RUNS).contains(&runs)),
            key("runs"),
            format!("must lie in [2, {MAX_MD_RUNS}] (errors come from the runs' spread)"),
        )?;
        let exponent = potential.family().length_exponent();
        let length = gas.length_unit_um(exponent);
        let time_unit = gas.time_unit_ns(exponent);
        let samples = self.samples.max(1);
        let sample_times_ns: Vec<f64> = (0..samples)
            .map(|k| {
                let offset = if samples == 1 {
                    0.0
                } else {
                    2.0 * f64::from(k) / f64::from(samples - 1) - 1.0
                };
                system.final_time_ns * (1.0 + self.sample_spread * offset)
            })
            .collect();
        Ok(MdParams {
            name: system.name.clone(),
            potential,
            gas,
            particles,
            radius_um,
            circumference: 2.0 * std::f64::consts::PI * radius_um / length,
            u_prime: system.u_prime,
            final_time_ns: system.final_time_ns,
            sample_times: sample_times_ns.iter().map(|t| t / time_unit).collect(),
            sample_times_ns,
            runs: system.runs.unwrap_or(self.runs),
            seed: self.seed,
            neighbours: self.neighbours,
            tolerance: self.tolerance,
            window: self.window,
            bin_width: self.bin_width,
            start_band: self.start_band,
        })
    }
}
