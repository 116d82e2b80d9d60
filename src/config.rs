//! The study definition, `pipeline.toml`: parsed strictly, validated, and
//! resolved into per-stage parameters.
//!
//! Unknown keys, wrong types and out-of-range values are rejected with a
//! [`ConfigError`] naming the key path and, where the document shows it, the
//! line. Every key is documented in README.md.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::physics::potential::Potential;
use crate::physics::sampling::{LaunchProposal, OffsetProposal, SamplingPlan};
use crate::physics::scene::{EngineSettings, Method};
use crate::physics::units::{Mass, PhysicalGas, ring_density_per_um};

/// A rejected configuration: file, key path, line (when known) and reason.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfigError {
    /// The configuration file.
    pub file: PathBuf,
    /// Dotted key path, e.g. `engine.tolerance` or `scan.launch[1].u2`.
    pub key: String,
    /// 1-based line of the offending value, when it could be located.
    pub line: Option<usize>,
    /// What is wrong and how to fix it.
    pub message: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if self.key.is_empty() {
            write!(f, ": {}", self.message)
        } else {
            write!(f, ": `{}`: {}", self.key, self.message)
        }
    }
}

impl std::error::Error for ConfigError {}

/// The whole study, as written in `pipeline.toml`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// Where artifacts live.
    #[serde(default)]
    pub store: StoreConfig,
    /// Which potentials the study covers.
    pub potentials: PotentialsConfig,
    /// How three-body scenes are integrated.
    #[serde(default)]
    pub engine: EngineConfig,
    /// Mono-energetic kick curves.
    pub scan: ScanConfig,
    /// Monte Carlo scenes for the collision kernel.
    #[serde(default)]
    pub collisions: CollisionsConfig,
    /// Kernel, moments and table settings.
    #[serde(default)]
    pub kernel: KernelConfig,
    /// The `u'` sweep: rates, Fokker-Planck consistency, detailed balance.
    #[serde(default)]
    pub sweep: SweepConfig,
    /// The convergence study of `a_n` under numerical settings.
    #[serde(default)]
    pub convergence: ConvergenceConfig,
    /// Evolution of `h(u, t)` by the master and Fokker-Planck equations.
    #[serde(default)]
    pub evolve: EvolveConfig,
    /// Molecular dynamics of rings.
    #[serde(default)]
    pub md: MdConfig,
    /// Gases in physical units whose thermalization rates are tabulated.
    #[serde(default)]
    pub gas: Vec<GasConfig>,
}

/// `[[gas]]`: a gas in physical units.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GasConfig {
    /// Label used in tables.
    pub name: String,
    /// Id of a configured potential (`ipp-6`, `lj-1`).
    pub potential: String,
    /// Potential length `l0`, um.
    pub l0_um: f64,
    /// Potential energy `eps`, eV.
    pub eps_ev: f64,
    /// Temperature `kT`, eV.
    pub kt_ev: f64,
    /// Mass in electron masses (give this or `mass_amu`).
    pub mass_electron: Option<f64>,
    /// Mass in atomic mass units.
    pub mass_amu: Option<f64>,
    /// Linear density, 1/um (give this or the ring).
    pub density_per_um: Option<f64>,
    /// Particles on a ring (with `ring_radius_um`): density `(N - 1) / (2 pi R)`.
    pub ring_particles: Option<u32>,
    /// Ring radius, um.
    pub ring_radius_um: Option<f64>,
}

/// Resolved parameters of one gas.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GasParams {
    /// Label.
    pub name: String,
    /// The potential.
    pub potential: Potential,
    /// The gas.
    pub gas: PhysicalGas,
}

impl GasParams {
    /// The kernel parameters of this gas's density (`u' = 0`).
    pub fn scaled_density(&self) -> f64 {
        self.gas.scaled_density(self.potential.length_exponent())
    }
}

/// `[convergence]`.
#[derive(Clone, Debug, Deserialize)]
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

/// `[evolve]`: evolution of `h(u, t)` from `delta(u - u')` (physics.md §4).
#[derive(Clone, Debug, Deserialize)]
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
    /// Collisions instance of the early (translation-invariant) kernel.
    pub collisions: String,
    /// Collisions instance of the grid kernel (a launch mixture reaching the whole grid).
    pub wide_collisions: String,
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

/// `[md]`: molecular dynamics of rings (physics.md §7).
#[derive(Clone, Debug, Deserialize)]
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
#[derive(Clone, Debug, Deserialize)]
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

/// `[sweep]`.
#[derive(Clone, Debug, Deserialize)]
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
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            enabled: true,
            u_prime_min: -3.0,
            u_prime_max: 3.0,
            points: 25,
            balance_separations: vec![0.01, 0.02, 0.05],
            balance_bin_width: 0.005,
            launch_spread: 2.0,
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
    /// Collisions instance the sweep reads (its own set when it has a launch spread).
    pub collisions: String,
}

/// `[collisions]`: how kernel scenes are sampled (numerics.md "Sampling scenes").
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CollisionsConfig {
    /// Seed of every randomization.
    pub seed: u64,
    /// Independent randomizations (replicates); standard errors come from their spread.
    pub randomizations: u32,
    /// Scenes per randomization (both strata together); each stratum's share is
    /// rounded to the nearest power of two.
    pub points: u32,
    /// Fraction of the scenes drawn in the same-side stratum when no pilot runs.
    pub same_side_fraction: f64,
    /// Pilot scenes per stratum that set the strata allocation (Neyman); 0 disables.
    pub pilot_points: u32,
    /// Scrambled Sobol' points (default) or plain Monte Carlo points.
    pub quasi_random: bool,
    /// `u'` the launch-speed proposal is tuned for.
    pub launch_shift: f64,
    /// Side components of the launch proposal at `launch_shift +- launch_spread` (0: none).
    pub launch_spread: f64,
    /// Mixture proposal of the arrival offset (`[collisions.proposal]`).
    pub proposal: OffsetProposal,
    /// Per-potential replacements of `points`, keyed by potential id
    /// (`[collisions.points_per_potential]`, e.g. `"lj-0.1" = 8192`).
    pub points_per_potential: BTreeMap<String, u32>,
}

impl Default for CollisionsConfig {
    fn default() -> Self {
        CollisionsConfig {
            seed: 1,
            randomizations: 16,
            points: 4096,
            same_side_fraction: 0.15,
            pilot_points: 1024,
            quasi_random: true,
            launch_shift: 0.0,
            launch_spread: 0.0,
            proposal: OffsetProposal::default(),
            points_per_potential: BTreeMap::new(),
        }
    }
}

/// `[kernel]`.
#[derive(Clone, Debug, Deserialize)]
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
    /// Range of `|u - u'|` of the shape fit, `[min, max]`.
    pub fit_range: [f64; 2],
}

pub use crate::kernel::DEFAULT_KICK_FLOOR;

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
        }
    }
}

/// Resolved parameters of a `collisions` instance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CollisionsParams {
    /// The potential.
    pub potential: Potential,
    /// Engine settings.
    pub engine: EngineSettings,
    /// What to draw (strata split by `same_side_fraction` unless a pilot decides).
    pub sampling: SamplingPlan,
    /// Scenes per randomization, both strata.
    pub points: u32,
    /// Pilot scenes per stratum for the Neyman allocation (0: keep the fraction).
    pub pilot_points: u32,
    /// Engine of the pilot: the study's, also for re-integrations at other
    /// tolerances, so that they get the same split and the same points.
    pub pilot_engine: EngineSettings,
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

/// `[store]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoreConfig {
    /// Artifact store directory, relative to the configuration file.
    pub path: PathBuf,
}

impl Default for StoreConfig {
    fn default() -> Self {
        StoreConfig {
            path: PathBuf::from("data"),
        }
    }
}

/// `[potentials]`: one potential per listed value.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PotentialsConfig {
    /// Exponents `n > 1` of inverse power laws `U = eps (l0/d)^n`.
    #[serde(default)]
    pub inverse_power: Vec<f64>,
    /// `theta = kT/eps > 0` of Lennard-Jones potentials.
    #[serde(default)]
    pub lennard_jones: Vec<f64>,
}

impl PotentialsConfig {
    /// One potential per listed value, inverse power laws first, in file order.
    pub fn list(&self) -> Vec<Potential> {
        let inverse = self
            .inverse_power
            .iter()
            .map(|&n| Potential::InversePower { n });
        let lj = self
            .lennard_jones
            .iter()
            .map(|&theta| Potential::LennardJones { theta });
        inverse.chain(lj).collect()
    }
}

/// `[engine]`.
#[derive(Clone, Copy, Debug, Deserialize)]
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

/// `[scan]`: settings shared by all potentials, with per-potential overrides.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanConfig {
    /// Observation region length `L` (scaled), only used to report launch delays.
    #[serde(default = "default_launch_length")]
    pub launch_length: f64,
    /// Smallest arrival offset of particle 3 after particle 2 (scaled time).
    pub offset_min: f64,
    /// Largest arrival offset.
    pub offset_max: f64,
    /// Number of equally spaced offsets, >= 3.
    pub points: u32,
    /// Launch velocity pairs to scan.
    pub launch: Vec<NamedLaunch>,
    /// Per-potential replacements of grid settings, keyed by potential id (`ipp-6`, `lj-0.05`).
    #[serde(default)]
    pub overrides: BTreeMap<String, ScanGridOverride>,
}

fn default_launch_length() -> f64 {
    90.0
}

impl ScanConfig {
    /// The shared offset grid, with the overrides of `potential_id` applied.
    pub fn grid(&self, potential_id: &str) -> ScanGrid {
        let change = self
            .overrides
            .get(potential_id)
            .copied()
            .unwrap_or_default();
        ScanGrid {
            offset_min: change.offset_min.unwrap_or(self.offset_min),
            offset_max: change.offset_max.unwrap_or(self.offset_max),
            points: change.points.unwrap_or(self.points),
        }
    }
}

/// The offset grid of a scan.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScanGrid {
    /// Smallest arrival offset of particle 3 after particle 2 (scaled time).
    pub offset_min: f64,
    /// Largest arrival offset.
    pub offset_max: f64,
    /// Number of equally spaced offsets, >= 3.
    pub points: u32,
}

/// `[scan.overrides.<potential id>]`: any subset of [`ScanGrid`].
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanGridOverride {
    /// Replaces `scan.offset_min`.
    pub offset_min: Option<f64>,
    /// Replaces `scan.offset_max`.
    pub offset_max: Option<f64>,
    /// Replaces `scan.points`.
    pub points: Option<u32>,
}

/// A named pair of launch velocities (units of `v_th`, special particle at rest).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NamedLaunch {
    /// Label used in tables.
    pub name: String,
    /// Velocity of the first arrival.
    pub u2: f64,
    /// Velocity of the second arrival.
    pub u3: f64,
}

/// Fully resolved parameters of one `scan` stage instance: everything its
/// output depends on, and nothing else.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScanParams {
    /// The potential.
    pub potential: Potential,
    /// Engine settings.
    pub engine: EngineSettings,
    /// `L`, for the reported launch delays.
    pub launch_length: f64,
    /// Offset grid.
    pub grid: ScanGrid,
    /// Launch pairs.
    pub launches: Vec<NamedLaunch>,
}

/// A loaded and validated study.
#[derive(Clone, Debug)]
pub struct Study {
    /// The configuration file.
    pub file: PathBuf,
    /// Parsed content.
    pub config: Config,
}

impl Study {
    /// Reads, parses and validates a configuration file.
    pub fn load(file: &Path) -> Result<Study, ConfigError> {
        let error = |line: Option<usize>, message: String| ConfigError {
            file: file.to_path_buf(),
            key: String::new(),
            line,
            message,
        };
        let bytes =
            std::fs::read(file).map_err(|e| error(None, format!("cannot read the file: {e}")))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let valid = e.utf8_error().valid_up_to();
            let bytes = e.as_bytes();
            let line = bytes[..valid].iter().filter(|&&b| b == b'\n').count() + 1;
            error(
                Some(line),
                format!(
                    "the file is not UTF-8 text (byte 0x{:02x}): TOML files are UTF-8",
                    bytes[valid]
                ),
            )
        })?;
        Study::parse(file, &text)
    }

    /// Parses and validates configuration text (`file` is used in messages).
    pub fn parse(file: &Path, text: &str) -> Result<Study, ConfigError> {
        let error = |key: String, line: Option<usize>, message: String| ConfigError {
            file: file.to_path_buf(),
            key,
            line,
            message,
        };
        let deserializer = toml::Deserializer::parse(text).map_err(|e| {
            error(
                String::new(),
                line_of_span(text, e.span()),
                format!("TOML syntax: {}", e.message().trim_end()),
            )
        })?;
        let config: Config = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let key = e.path().to_string();
            let line = line_of_span(text, e.inner().span()).or_else(|| line_of_key(text, &key));
            error(key, line, e.inner().message().to_string())
        })?;
        validate(&config).map_err(|(key, message)| {
            let line = line_of_key(text, &key);
            error(key, line, message)
        })?;
        Ok(Study {
            file: file.to_path_buf(),
            config,
        })
    }

    /// The artifact store directory.
    pub fn store_path(&self) -> PathBuf {
        let base = self.file.parent().unwrap_or(Path::new("."));
        base.join(&self.config.store.path)
    }

    /// The configured potentials, inverse power laws first, in file order.
    pub fn potentials(&self) -> Vec<Potential> {
        self.config.potentials.list()
    }

    /// Engine settings as the physics sees them.
    pub fn engine(&self) -> EngineSettings {
        let engine = self.config.engine;
        EngineSettings {
            method: engine.method,
            tolerance: engine.tolerance,
            max_steps: engine.max_steps,
            free_flight: engine.free_flight,
        }
    }

    /// Resolved parameters of the collision scenes of `potential`.
    pub fn collisions_params(&self, potential: Potential) -> CollisionsParams {
        let sampling = &self.config.collisions;
        let mut plan = SamplingPlan {
            seed: sampling.seed,
            randomizations: sampling.randomizations,
            opposite_points: 0,
            same_side_points: 0,
            proposal: sampling.proposal,
            quasi_random: sampling.quasi_random,
            launch: LaunchProposal {
                shift: sampling.launch_shift,
                spread: sampling.launch_spread,
            },
        };
        let points = sampling
            .points_per_potential
            .get(&potential.id())
            .copied()
            .unwrap_or(sampling.points);
        plan.allocate(points, sampling.same_side_fraction);
        CollisionsParams {
            potential,
            engine: self.engine(),
            sampling: plan,
            points,
            pilot_points: sampling.pilot_points,
            pilot_engine: self.engine(),
        }
    }

    /// Every `(u', density)` the kernel is evaluated at, with `(0, 0)` (which
    /// defines `a_n`) always first.
    pub fn kernel_targets(&self) -> Vec<(f64, f64)> {
        let kernel = &self.config.kernel;
        let mut targets = vec![(0.0, 0.0)];
        for &u in &kernel.u_prime {
            for &density in &kernel.density {
                if !targets.contains(&(u, density)) {
                    targets.push((u, density));
                }
            }
        }
        targets
    }

    /// Resolved kernel parameters of `potential` at `(u', density)`.
    pub fn kernel_params(&self, potential: Potential, u_prime: f64, density: f64) -> KernelParams {
        let kernel = &self.config.kernel;
        KernelParams {
            potential,
            u_prime,
            density,
            window: kernel.window,
            bin_width: kernel.bin_width,
            launch_length: kernel.launch_length,
            kick_floor: kernel.kick_floor,
        }
    }

    /// Resolved parameters of the shape fit of a kernel.
    pub fn fit_params(&self, kernel: KernelParams) -> FitParams {
        let [range_min, range_max] = self.config.kernel.fit_range;
        FitParams {
            kernel,
            range_min,
            range_max,
        }
    }

    /// The collisions instance that reaches every `u'` of the sweep and of the
    /// evolution grid: its name and, when it is not the main set, its
    /// parameters (the main set with the sweep's launch spread).
    pub fn wide_collisions(&self, potential: Potential) -> (String, Option<CollisionsParams>) {
        let spread = self.config.sweep.launch_spread;
        if spread > 0.0 {
            let mut params = self.collisions_params(potential);
            params.sampling.launch.spread = spread;
            (format!("{}_sweep", potential.id()), Some(params))
        } else {
            (potential.id(), None)
        }
    }

    /// Resolved parameters of the sweep of `potential`, if enabled.
    pub fn sweep_params(&self, potential: Potential) -> Option<SweepParams> {
        let sweep = &self.config.sweep;
        if !sweep.enabled {
            return None;
        }
        let (collisions, _) = self.wide_collisions(potential);
        let params = SweepParams {
            kernel: self.kernel_params(potential, 0.0, 0.0),
            u_prime_min: sweep.u_prime_min,
            u_prime_max: sweep.u_prime_max,
            points: sweep.points,
            balance_separations: sweep.balance_separations.clone(),
            balance_bin_width: sweep.balance_bin_width,
            collisions,
        };
        Some(params)
    }

    /// Resolved parameters of every md system, if enabled.
    pub fn md_params(&self) -> Vec<MdParams> {
        let md = &self.config.md;
        if !md.enabled {
            return Vec::new();
        }
        md.system
            .iter()
            .filter_map(|system| {
                let gas = self.config.gas.iter().find(|g| g.name == system.gas)?;
                let resolved = self.gases().into_iter().find(|g| g.name == system.gas)?;
                let (particles, radius_um) = (gas.ring_particles?, gas.ring_radius_um?);
                let exponent = resolved.potential.length_exponent();
                let length = resolved.gas.length_unit_um(exponent);
                let time_unit = resolved.gas.time_unit_ns(exponent);
                let samples = md.samples.max(1);
                let sample_times_ns: Vec<f64> = (0..samples)
                    .map(|k| {
                        let offset = if samples == 1 {
                            0.0
                        } else {
                            2.0 * f64::from(k) / f64::from(samples - 1) - 1.0
                        };
                        system.final_time_ns * (1.0 + md.sample_spread * offset)
                    })
                    .collect();
                Some(MdParams {
                    name: system.name.clone(),
                    potential: resolved.potential,
                    gas: resolved.gas,
                    particles,
                    radius_um,
                    circumference: 2.0 * std::f64::consts::PI * radius_um / length,
                    u_prime: system.u_prime,
                    final_time_ns: system.final_time_ns,
                    sample_times: sample_times_ns.iter().map(|t| t / time_unit).collect(),
                    sample_times_ns,
                    runs: system.runs.unwrap_or(md.runs),
                    seed: md.seed,
                    neighbours: md.neighbours,
                    tolerance: md.tolerance,
                    window: md.window,
                    bin_width: md.bin_width,
                    start_band: md.start_band,
                })
            })
            .collect()
    }

    /// Resolved parameters of the evolve stage, if enabled.
    pub fn evolve_params(&self) -> Option<EvolveParams> {
        let evolve = &self.config.evolve;
        if !evolve.enabled {
            return None;
        }
        let potential = *self
            .potentials()
            .iter()
            .find(|p| p.id() == evolve.potential)?;
        let kernel = self.kernel_params(potential, evolve.u_prime, 0.0);
        let sorted = |times: &[f64]| {
            let mut sorted = times.to_vec();
            sorted.sort_by(f64::total_cmp);
            sorted.dedup();
            sorted
        };
        let physical = evolve.gas.as_ref().and_then(|name| {
            let gas = self.gases().into_iter().find(|g| &g.name == name)?;
            let times_ns = sorted(&evolve.times_ns);
            let unit = gas.gas.rate_per_ns(1.0, potential.length_exponent());
            Some(PhysicalTimes {
                gas: gas.name,
                times_scaled: times_ns.iter().map(|t| t * unit).collect(),
                times_ns,
            })
        });
        Some(EvolveParams {
            kernel,
            collisions: potential.id(),
            wide_collisions: self.wide_collisions(potential).0,
            times: sorted(&evolve.times),
            early_times: sorted(&evolve.early_times),
            early_rebin: (evolve.early_bin_width / kernel.bin_width).round() as u32,
            early_range: evolve.early_range,
            velocity_range: evolve.velocity_range,
            grid_step: evolve.grid_step,
            physical,
        })
    }

    /// Resolved convergence parameters and the collisions at each varied
    /// tolerance, if the study is enabled.
    pub fn convergence(&self) -> Option<(ConvergenceParams, Vec<CollisionsParams>)> {
        let study = &self.config.convergence;
        if !study.enabled {
            return None;
        }
        let potential = Potential::InversePower {
            n: study.inverse_power,
        };
        let variants = study
            .tolerances
            .iter()
            .map(|&tolerance| {
                let mut params = self.collisions_params(potential);
                params.engine.tolerance = tolerance;
                params
            })
            .collect();
        let params = ConvergenceParams {
            kernel: self.kernel_params(potential, 0.0, 0.0),
            densities: study.densities.clone(),
            offset_bounds: study.offset_bounds.clone(),
            tolerances: study.tolerances.clone(),
            bin_widths: study.bin_widths.clone(),
        };
        Some((params, variants))
    }

    /// The configured gases with their potentials.
    pub fn gases(&self) -> Vec<GasParams> {
        let potentials = self.potentials();
        self.config
            .gas
            .iter()
            .filter_map(|gas| {
                let potential = *potentials.iter().find(|p| p.id() == gas.potential)?;
                Some(GasParams {
                    name: gas.name.clone(),
                    potential,
                    gas: physical_gas(gas)?,
                })
            })
            .collect()
    }

    /// Resolved parameters of the scan of `potential`.
    pub fn scan_params(&self, potential: Potential) -> ScanParams {
        let scan = &self.config.scan;
        ScanParams {
            potential,
            engine: self.engine(),
            launch_length: scan.launch_length,
            grid: scan.grid(&potential.id()),
            launches: scan.launch.clone(),
        }
    }
}

/// The physical gas of a `[[gas]]` entry (`None` when its mass or density is
/// incompletely given, which validation rejects).
fn physical_gas(gas: &GasConfig) -> Option<PhysicalGas> {
    let mass = match (gas.mass_electron, gas.mass_amu) {
        (Some(m), _) => Mass::ElectronMasses(m),
        (None, Some(m)) => Mass::AtomicMassUnits(m),
        (None, None) => return None,
    };
    let density_per_um = match (gas.density_per_um, gas.ring_particles, gas.ring_radius_um) {
        (Some(density), _, _) => density,
        (None, Some(particles), Some(radius)) => ring_density_per_um(particles, radius),
        _ => return None,
    };
    Some(PhysicalGas {
        l0_um: gas.l0_um,
        eps_ev: gas.eps_ev,
        kt_ev: gas.kt_ev,
        mass,
        density_per_um,
    })
}

/// A validation failure: key path and message.
type Invalid = (String, String);

fn check(ok: bool, key: impl Into<String>, message: impl Into<String>) -> Result<(), Invalid> {
    if ok {
        Ok(())
    } else {
        Err((key.into(), message.into()))
    }
}

fn validate(config: &Config) -> Result<(), Invalid> {
    validate_potentials(&config.potentials)?;
    let engine = &config.engine;
    check(
        engine.tolerance > 0.0 && engine.tolerance <= 1e-3,
        "engine.tolerance",
        format!(
            "{} is outside (0, 1e-3]; 1e-12 is a good default",
            engine.tolerance
        ),
    )?;
    check(
        engine.max_steps >= 1,
        "engine.max_steps",
        "must be at least 1",
    )?;
    validate_scan(config)?;
    validate_collisions(&config.collisions)?;
    let ids: Vec<String> = config.potentials.list().iter().map(Potential::id).collect();
    for (id, &points) in &config.collisions.points_per_potential {
        let key = format!("collisions.points_per_potential.{id}");
        check(
            ids.contains(id),
            key.clone(),
            format!(
                "`{id}` names no configured potential; known ids: {}",
                ids.join(", ")
            ),
        )?;
        check_scenes(&config.collisions, points, &key)?;
    }
    let launch = LaunchProposal {
        shift: config.collisions.launch_shift,
        spread: config.collisions.launch_spread,
    };
    validate_kernel(&config.kernel, &launch)?;
    let sweep_launch = LaunchProposal {
        spread: config.sweep.launch_spread.max(launch.spread),
        ..launch
    };
    validate_sweep(&config.sweep, &sweep_launch)?;
    validate_convergence(config)?;
    validate_gases(config)?;
    validate_evolve(config, &launch, &sweep_launch)?;
    validate_md(config)
}

fn validate_md(config: &Config) -> Result<(), Invalid> {
    let md = &config.md;
    if !md.enabled {
        return Ok(());
    }
    check(
        (2..=MAX_MD_RUNS).contains(&md.runs),
        "md.runs",
        format!(
            "{} is outside [2, {MAX_MD_RUNS}] (errors come from the runs' spread)",
            md.runs
        ),
    )?;
    check(
        (1..=MAX_NEIGHBOURS).contains(&md.neighbours),
        "md.neighbours",
        format!("{} is outside [1, {MAX_NEIGHBOURS}]", md.neighbours),
    )?;
    check(
        md.tolerance > 0.0 && md.tolerance <= 1e-6,
        "md.tolerance",
        format!("{} is outside (0, 1e-6]", md.tolerance),
    )?;
    check(
        md.window > 0.0 && md.bin_width > 0.0 && md.bin_width <= md.window,
        "md.bin_width",
        format!("{} must be in (0, md.window = {}]", md.bin_width, md.window),
    )?;
    check(
        (1..=MAX_MD_SAMPLES).contains(&md.samples),
        "md.samples",
        format!("{} is outside [1, {MAX_MD_SAMPLES}]", md.samples),
    )?;
    check(
        (0.0..0.5).contains(&md.sample_spread),
        "md.sample_spread",
        format!("{} is outside [0, 0.5)", md.sample_spread),
    )?;
    check(md.start_band > 0.0, "md.start_band", "must be > 0")?;
    check(!md.system.is_empty(), "md.system", "lists no ring")?;
    for (k, system) in md.system.iter().enumerate() {
        let key = |name: &str| format!("md.system[{k}].{name}");
        check(
            md.system.iter().filter(|s| s.name == system.name).count() == 1,
            key("name"),
            format!("`{}` is used twice", system.name),
        )?;
        let gas = config.gas.iter().find(|g| g.name == system.gas);
        check(
            gas.is_some_and(|g| g.ring_particles.is_some()),
            key("gas"),
            format!(
                "`{}` names no [[gas]] given as a ring (ring_particles, ring_radius_um)",
                system.gas
            ),
        )?;
        let id = gas.map(|g| g.potential.as_str()).unwrap_or_default();
        let potential = config.potentials.list().into_iter().find(|p| p.id() == id);
        check(
            matches!(
                potential,
                Some(Potential::InversePower { n }) if n >= 2.0
            ) || matches!(potential, Some(Potential::LennardJones { .. })),
            key("gas"),
            format!(
                "the md stage runs inverse power laws with n >= 2 (n = 2 as a whole ring, larger n by cluster stepping) and Lennard-Jones; `{id}` is neither"
            ),
        )?;
        check(
            system.final_time_ns.is_finite() && system.final_time_ns > 0.0,
            key("final_time_ns"),
            format!("{} must be > 0", system.final_time_ns),
        )?;
        if let Some(physical) = gas.and_then(physical_gas) {
            let particles = f64::from(gas.and_then(|g| g.ring_particles).unwrap_or(0));
            let encounters = particles
                * physical.density_per_um
                * physical.thermal_speed_um_per_ns()
                * system.final_time_ns;
            check(
                encounters <= MAX_RING_ENCOUNTERS,
                key("final_time_ns"),
                format!(
                    "{} ns gives ~{encounters:.1e} neighbour encounters per run (N rho v_th t_f), more than {MAX_RING_ENCOUNTERS:.0e}",
                    system.final_time_ns
                ),
            )?;
        }
        check(system.u_prime.is_finite(), key("u_prime"), "must be finite")?;
        check(
            system
                .runs
                .is_none_or(|runs| (2..=MAX_MD_RUNS).contains(&runs)),
            key("runs"),
            format!("must lie in [2, {MAX_MD_RUNS}] (errors come from the runs' spread)"),
        )?;
    }
    Ok(())
}

/// Largest MD runs per ring.
pub const MAX_MD_RUNS: u32 = 1 << 16;

/// Largest interacting neighbours per side.
pub const MAX_NEIGHBOURS: u32 = 64;

/// Largest sample times per ring.
pub const MAX_MD_SAMPLES: u32 = 1000;

/// Largest neighbour encounters per MD run, `N rho v_th t_f` (the published
/// ring N = 161, R = 51200 um, 12800 ns has 1.4e5).
pub const MAX_RING_ENCOUNTERS: f64 = 1e9;

fn validate_evolve(
    config: &Config,
    launch: &LaunchProposal,
    wide: &LaunchProposal,
) -> Result<(), Invalid> {
    let evolve = &config.evolve;
    if !evolve.enabled {
        return Ok(());
    }
    let ids: Vec<String> = config.potentials.list().iter().map(Potential::id).collect();
    check(
        ids.contains(&evolve.potential),
        "evolve.potential",
        format!(
            "`{}` names no configured potential; known ids: {}",
            evolve.potential,
            ids.join(", ")
        ),
    )?;
    let positive = |value: f64| value.is_finite() && value > 0.0;
    for (name, value) in [
        ("grid_step", evolve.grid_step),
        ("velocity_range", evolve.velocity_range),
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
        evolve.velocity_range >= 2.0 * evolve.grid_step,
        "evolve.velocity_range",
        "must span at least two grid steps",
    )?;
    check(
        evolve.velocity_range / evolve.grid_step <= MAX_EVOLVE_HALF_NODES,
        "evolve.grid_step",
        format!(
            "more than {} grid nodes (dense generators of n^2 entries, exponentials in n^3): widen the step",
            2.0 * MAX_EVOLVE_HALF_NODES + 1.0
        ),
    )?;
    check(
        evolve.early_range / evolve.early_bin_width <= MAX_BINS,
        "evolve.early_bin_width",
        "more than a million early bins: widen the bins or narrow evolve.early_range",
    )?;
    check(
        within_reach(wide, evolve.velocity_range) && within_reach(wide, -evolve.velocity_range),
        "evolve.velocity_range",
        format!(
            "{} is beyond the reach of the wide launch proposal (+- (sweep.launch_spread {} + {REWEIGHTING_REACH})): widen sweep.launch_spread",
            evolve.velocity_range, wide.spread
        ),
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
    let ratio = evolve.early_bin_width / config.kernel.bin_width;
    check(
        (ratio - ratio.round()).abs() < 1e-6 && ratio.round() as u64 % 2 == 1,
        "evolve.early_bin_width",
        format!(
            "{} must be an odd multiple of kernel.bin_width ({})",
            evolve.early_bin_width, config.kernel.bin_width
        ),
    )?;
    for (name, times) in [
        ("times", &evolve.times),
        ("early_times", &evolve.early_times),
        ("times_ns", &evolve.times_ns),
    ] {
        check(
            times.len() <= MAX_LIST,
            format!("evolve.{name}"),
            format!("lists {} times, more than {MAX_LIST}", times.len()),
        )?;
        for (k, &t) in times.iter().enumerate() {
            check(
                positive(t),
                format!("evolve.{name}[{k}]"),
                format!("{t} must be > 0"),
            )?;
        }
    }
    check(
        !evolve.times.is_empty() || !evolve.times_ns.is_empty(),
        "evolve.times",
        "lists no time (give times or gas with times_ns)",
    )?;
    match &evolve.gas {
        Some(name) => {
            let gas = config.gas.iter().find(|g| &g.name == name);
            check(
                gas.is_some_and(|g| g.potential == evolve.potential),
                "evolve.gas",
                format!(
                    "`{name}` names no [[gas]] with potential {}",
                    evolve.potential
                ),
            )
        }
        None => check(
            evolve.times_ns.is_empty(),
            "evolve.times_ns",
            "needs evolve.gas (the gas whose units convert them)",
        ),
    }
}

/// Largest `evolve.velocity_range / evolve.grid_step` (801 nodes).
pub const MAX_EVOLVE_HALF_NODES: f64 = 400.0;

/// Largest histogram bins of a kernel or an early evolution.
pub const MAX_BINS: f64 = 1e6;

/// Longest list of values (velocities, densities, times, settings).
pub const MAX_LIST: usize = 256;

fn validate_gases(config: &Config) -> Result<(), Invalid> {
    let ids: Vec<String> = config.potentials.list().iter().map(Potential::id).collect();
    for (k, gas) in config.gas.iter().enumerate() {
        let key = |name: &str| format!("gas[{k}].{name}");
        check(!gas.name.is_empty(), key("name"), "is empty")?;
        check(
            ids.contains(&gas.potential),
            key("potential"),
            format!(
                "`{}` names no configured potential; known ids: {}",
                gas.potential,
                ids.join(", ")
            ),
        )?;
        for (name, value) in [
            ("l0_um", gas.l0_um),
            ("eps_ev", gas.eps_ev),
            ("kt_ev", gas.kt_ev),
        ] {
            check(
                value.is_finite() && value > 0.0,
                key(name),
                format!("{value} must be > 0"),
            )?;
        }
        let potential = config
            .potentials
            .list()
            .into_iter()
            .find(|p| p.id() == gas.potential);
        if let Some(Potential::LennardJones { theta }) = potential {
            let ratio = gas.kt_ev / gas.eps_ev;
            check(
                (ratio / theta - 1.0).abs() <= 1e-9,
                key("kt_ev"),
                format!(
                    "kt_ev / eps_ev = {ratio} differs from theta = kT/eps = {theta} of `{}`",
                    gas.potential
                ),
            )?;
        }
        let masses = [gas.mass_electron, gas.mass_amu];
        check(
            masses.iter().flatten().count() == 1
                && masses.iter().flatten().all(|m| m.is_finite() && *m > 0.0),
            key("mass_electron"),
            "give exactly one positive mass: mass_electron or mass_amu",
        )?;
        let ring = gas.ring_particles.is_some() || gas.ring_radius_um.is_some();
        check(
            gas.density_per_um.is_some() != ring,
            key("density_per_um"),
            "give either density_per_um or ring_particles with ring_radius_um",
        )?;
        if let Some(density) = gas.density_per_um {
            check(
                density.is_finite() && density > 0.0,
                key("density_per_um"),
                format!("{density} must be > 0"),
            )?;
        } else {
            check(
                gas.ring_particles
                    .is_some_and(|n| (3..=MAX_RING_PARTICLES).contains(&n)),
                key("ring_particles"),
                format!("needs 3 to {MAX_RING_PARTICLES} particles"),
            )?;
            check(
                gas.ring_radius_um.is_some_and(|r| r.is_finite() && r > 0.0),
                key("ring_radius_um"),
                "needs a ring radius > 0",
            )?;
        }
    }
    for (k, gas) in config.gas.iter().enumerate() {
        let potential = config
            .potentials
            .list()
            .into_iter()
            .find(|p| p.id() == gas.potential);
        if let (Some(potential), Some(physical)) = (potential, physical_gas(gas)) {
            let density = physical.scaled_density(potential.length_exponent());
            let key = if gas.density_per_um.is_some() {
                "density_per_um"
            } else {
                "ring_radius_um"
            };
            check(
                density <= MAX_GAS_DENSITY,
                format!("gas[{k}].{key}"),
                format!(
                    "gives rho*l = {density:.4e}, above {MAX_GAS_DENSITY}: the three-body kernel describes dilute gases (rho*l << 1)"
                ),
            )?;
        }
    }
    check_unique(
        &config
            .gas
            .iter()
            .map(|g| g.name.as_str())
            .collect::<Vec<_>>(),
        "gas",
    )
}

/// Largest particles of a ring.
pub const MAX_RING_PARTICLES: u32 = 100_000;

/// Largest `rho * l` of a gas, as for `kernel.density`.
pub const MAX_GAS_DENSITY: f64 = 0.1;

fn validate_convergence(config: &Config) -> Result<(), Invalid> {
    let study = &config.convergence;
    if !study.enabled {
        return Ok(());
    }
    check(
        config
            .potentials
            .inverse_power
            .contains(&study.inverse_power),
        "convergence.inverse_power",
        format!(
            "n = {} is not among potentials.inverse_power",
            study.inverse_power
        ),
    )?;
    let lists: [(&str, &Vec<f64>, f64, f64); 4] = [
        ("densities", &study.densities, 0.0, 0.1),
        ("offset_bounds", &study.offset_bounds, 1e-3, 1e6),
        ("tolerances", &study.tolerances, 1e-16, 1e-3),
        (
            "bin_widths",
            &study.bin_widths,
            1e-7,
            0.5 * config.kernel.window,
        ),
    ];
    for (name, values, low, high) in lists {
        check(
            values.len() <= MAX_LIST,
            format!("convergence.{name}"),
            format!("lists {} values, more than {MAX_LIST}", values.len()),
        )?;
        for (k, &value) in values.iter().enumerate() {
            check(
                value.is_finite() && value > low && value <= high,
                format!("convergence.{name}[{k}]"),
                format!("{value} is outside ({low}, {high}]"),
            )?;
        }
    }
    check_unique(&study.tolerances, "convergence.tolerances")
}

fn validate_sweep(sweep: &SweepConfig, launch: &LaunchProposal) -> Result<(), Invalid> {
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

/// Largest `u'` points of the sweep.
pub const MAX_SWEEP_POINTS: u32 = 1001;

fn validate_collisions(sampling: &CollisionsConfig) -> Result<(), Invalid> {
    check(
        (2..=MAX_RANDOMIZATIONS).contains(&sampling.randomizations),
        "collisions.randomizations",
        format!(
            "{} is outside [2, {MAX_RANDOMIZATIONS}]: at least 2 are needed for a standard error",
            sampling.randomizations
        ),
    )?;
    check_scenes(sampling, sampling.points, "collisions.points")?;
    check(
        sampling.pilot_points == 0 || (16..=MAX_PILOT_POINTS).contains(&sampling.pilot_points),
        "collisions.pilot_points",
        format!(
            "{} must be 0 (no pilot) or in [16, {MAX_PILOT_POINTS}]: fewer pilot scenes cannot estimate a stratum's spread",
            sampling.pilot_points
        ),
    )?;
    check(
        sampling.same_side_fraction > 0.0 && sampling.same_side_fraction < 1.0,
        "collisions.same_side_fraction",
        format!(
            "{} must lie in (0, 1): both strata need scenes",
            sampling.same_side_fraction
        ),
    )?;
    check(
        sampling.launch_shift.is_finite() && sampling.launch_shift.abs() <= 3.0,
        "collisions.launch_shift",
        format!("{} is outside [-3, 3]", sampling.launch_shift),
    )?;
    check(
        sampling.launch_spread.is_finite() && (0.0..=3.0).contains(&sampling.launch_spread),
        "collisions.launch_spread",
        format!("{} is outside [0, 3]", sampling.launch_spread),
    )?;
    let proposal = &sampling.proposal;
    for (key, value) in [
        ("core_weight", proposal.core_weight),
        ("tail_weight", proposal.tail_weight),
        ("uniform_weight", proposal.uniform_weight),
    ] {
        check(
            value.is_finite() && value >= 0.0,
            format!("collisions.proposal.{key}"),
            format!("{value} must be a finite weight >= 0"),
        )?;
    }
    check(
        proposal.tail_weight > 0.0,
        "collisions.proposal.tail_weight",
        "must be > 0: only the Cauchy tail covers every offset, so no scene is left out",
    )?;
    for (key, value) in [
        ("core_width", proposal.core_width),
        ("tail_width", proposal.tail_width),
        ("uniform_range", proposal.uniform_range),
    ] {
        check(
            value.is_finite() && value > 0.0,
            format!("collisions.proposal.{key}"),
            format!("{value} must be a finite width > 0 (in collision times)"),
        )?;
    }
    Ok(())
}

/// Largest number of randomizations (replicates) of a collisions instance.
pub const MAX_RANDOMIZATIONS: u32 = 1024;

/// Largest pilot scenes per stratum.
pub const MAX_PILOT_POINTS: u32 = 1 << 20;

/// Largest scenes of one collisions instance (randomizations x points): each
/// event takes ~120 bytes in memory before it is encoded, so 2^25 events take
/// ~4 GB (the publication study draws 2^19).
pub const MAX_SCENES: u64 = 1 << 25;

/// Checks the scenes per randomization `points` (under `key`) and the
/// instance's total against [`MAX_SCENES`].
fn check_scenes(sampling: &CollisionsConfig, points: u32, key: &str) -> Result<(), Invalid> {
    check(points >= 2, key, "must be at least 2")?;
    let total = u64::from(sampling.randomizations) * u64::from(points);
    check(
        total <= MAX_SCENES,
        key,
        format!(
            "{points} scenes x {} randomizations = {total} exceeds {MAX_SCENES} (~4 GB of events in memory): use fewer points",
            sampling.randomizations
        ),
    )
}

/// Largest `|u' - launch_shift|` that reweighting covers: beyond it the launch
/// speeds that matter lie past the largest speed the point set can draw (6.8
/// v_th), biasing the kernel by > 0.5%, and the weights' variance explodes.
const REWEIGHTING_REACH: f64 = 3.0;

/// `true` when `u'` lies within reach of a component of the launch proposal.
fn within_reach(launch: &LaunchProposal, u_prime: f64) -> bool {
    (u_prime - launch.shift).abs() <= REWEIGHTING_REACH + launch.spread
}

fn validate_kernel(kernel: &KernelConfig, launch: &LaunchProposal) -> Result<(), Invalid> {
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
        kernel.window.is_finite() && kernel.window >= 3.0 * kernel.bin_width,
        "kernel.window",
        format!(
            "{} must hold at least 3 bins of kernel.bin_width",
            kernel.window
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
        kernel.kick_floor >= 0.0 && kernel.kick_floor < 0.5 * kernel.bin_width,
        "kernel.kick_floor",
        format!("{} must lie in [0, bin_width/2)", kernel.kick_floor),
    )?;
    let [low, high] = kernel.fit_range;
    check(
        low > 0.0 && low < high && high <= 0.5 * kernel.window,
        "kernel.fit_range",
        format!("[{low}, {high}] must satisfy 0 < min < max <= window/2"),
    )
}

fn validate_potentials(potentials: &PotentialsConfig) -> Result<(), Invalid> {
    check(
        !potentials.inverse_power.is_empty() || !potentials.lennard_jones.is_empty(),
        "potentials",
        "lists no potential: give `inverse_power = [6]` or `lennard_jones = [1.0]`",
    )?;
    for (k, &n) in potentials.inverse_power.iter().enumerate() {
        check(
            n > 1.0 && n <= MAX_EXPONENT,
            format!("potentials.inverse_power[{k}]"),
            format!(
                "n = {} is outside (1, {MAX_EXPONENT}] (the potential tail must be integrable; steeper walls are hard spheres)",
                compact(n)
            ),
        )?;
    }
    for (k, &theta) in potentials.lennard_jones.iter().enumerate() {
        check(
            (THETA_RANGE[0]..=THETA_RANGE[1]).contains(&theta),
            format!("potentials.lennard_jones[{k}]"),
            format!(
                "theta = kT/eps = {} is outside [{}, {}]",
                compact(theta),
                THETA_RANGE[0],
                THETA_RANGE[1]
            ),
        )?;
    }
    check_unique(&potentials.inverse_power, "potentials.inverse_power")?;
    check_unique(&potentials.lennard_jones, "potentials.lennard_jones")
}

/// A number for a message: plain when of moderate size, else in exponent form
/// (`1e300`, not three hundred digits).
fn compact(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) || !x.is_finite() {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

/// Largest inverse-power exponent `n`.
pub const MAX_EXPONENT: f64 = 100.0;

/// Range of Lennard-Jones `theta = kT/eps`: below it nearly every pair is
/// bound, above it the well does not matter. With `n` in `(1, MAX_EXPONENT]`
/// this bounds every potential id (which names files) to 24 characters.
pub const THETA_RANGE: [f64; 2] = [1e-3, 1e3];

fn check_unique<T: PartialEq + fmt::Display>(values: &[T], key: &str) -> Result<(), Invalid> {
    for (k, value) in values.iter().enumerate() {
        check(
            !values[..k].contains(value),
            format!("{key}[{k}]"),
            format!("{value} is listed twice"),
        )?;
    }
    Ok(())
}

/// Largest offsets per launch pair of a scan.
pub const MAX_SCAN_POINTS: u32 = 1 << 20;

/// Largest scenes of one scan (offsets x launch pairs).
pub const MAX_SCAN_SCENES: u64 = 1 << 22;

/// Largest number of scan launch pairs.
pub const MAX_SCAN_LAUNCHES: usize = 64;

fn validate_grid(grid: &ScanGrid, prefix: &str) -> Result<(), Invalid> {
    for (name, value) in [
        ("offset_min", grid.offset_min),
        ("offset_max", grid.offset_max),
    ] {
        check(
            value.is_finite(),
            format!("{prefix}{name}"),
            format!("{value} must be a finite offset"),
        )?;
    }
    check(
        grid.offset_min < grid.offset_max,
        format!("{prefix}offset_max"),
        format!(
            "must exceed offset_min ({} >= {})",
            grid.offset_min, grid.offset_max
        ),
    )?;
    check(
        grid.points >= 3,
        format!("{prefix}points"),
        format!(
            "{} points cannot bracket a peak: use at least 3",
            grid.points
        ),
    )?;
    check(
        grid.points <= MAX_SCAN_POINTS,
        format!("{prefix}points"),
        format!(
            "{} is more than {MAX_SCAN_POINTS} offsets per launch pair",
            grid.points
        ),
    )
}

fn validate_scan(config: &Config) -> Result<(), Invalid> {
    let scan = &config.scan;
    check(
        scan.launch_length.is_finite() && scan.launch_length > 0.0,
        "scan.launch_length",
        format!("L = {} must be a finite length > 0", scan.launch_length),
    )?;
    validate_grid(&scan.grid(""), "scan.")?;
    check(
        !scan.launch.is_empty() && scan.launch.len() <= MAX_SCAN_LAUNCHES,
        "scan.launch",
        format!(
            "lists {} launch pairs: give 1 to {MAX_SCAN_LAUNCHES}",
            scan.launch.len()
        ),
    )?;
    for (k, launch) in scan.launch.iter().enumerate() {
        for (name, u) in [("u2", launch.u2), ("u3", launch.u3)] {
            check(
                u.is_finite() && u != 0.0,
                format!("scan.launch[{k}].{name}"),
                format!("{u} must be finite and non-zero (a particle at rest never arrives)"),
            )?;
        }
        check(
            launch.u2 != launch.u3,
            format!("scan.launch[{k}].u3"),
            "equal velocities never collide",
        )?;
        check(
            !launch.name.is_empty(),
            format!("scan.launch[{k}].name"),
            "is empty",
        )?;
    }
    let names: Vec<&str> = scan.launch.iter().map(|l| l.name.as_str()).collect();
    check_unique(&names, "scan.launch")?;
    let largest = scan
        .overrides
        .keys()
        .map(|id| scan.grid(id).points)
        .fold(scan.points, u32::max);
    let scenes = u64::from(largest) * scan.launch.len() as u64;
    check(
        scenes <= MAX_SCAN_SCENES,
        "scan.points",
        format!(
            "{largest} offsets x {} launch pairs = {scenes} scenes exceeds {MAX_SCAN_SCENES} (~1 GB of curve rows in memory)",
            scan.launch.len()
        ),
    )?;
    let ids: Vec<String> = config.potentials.list().iter().map(Potential::id).collect();
    for id in scan.overrides.keys() {
        check(
            ids.contains(id),
            format!("scan.overrides.{id}"),
            format!(
                "names no configured potential; known ids: {}",
                ids.join(", ")
            ),
        )?;
        validate_grid(&scan.grid(id), &format!("scan.overrides.{id}."))?;
    }
    Ok(())
}

/// 1-based line of a byte offset.
fn line_of_span(text: &str, span: Option<std::ops::Range<usize>>) -> Option<usize> {
    let start = span?.start.min(text.len());
    Some(text[..start].matches('\n').count() + 1)
}

/// Line of the value at a dotted key path such as `scan.launch[1].u2`, found in
/// the spanned document tree. A segment may itself hold dots (a quoted key
/// such as `points_per_potential."lj-0.1"`): at each level the longest key of
/// the table that the path continues with is taken.
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    let root = DeTable::parse(text).ok()?;
    let mut current: toml::Spanned<DeValue> =
        toml::Spanned::new(root.span(), DeValue::Table(root.into_inner()));
    let mut rest = key;
    while !rest.is_empty() {
        let DeValue::Table(table) = current.into_inner() else {
            return None;
        };
        let (name, value) = table
            .into_iter()
            .filter(|(k, _)| {
                let name: &str = k.get_ref().as_ref();
                rest.strip_prefix(name)
                    .is_some_and(|after| after.is_empty() || after.starts_with(['.', '[']))
            })
            .max_by_key(|(k, _)| k.get_ref().len())?;
        current = value;
        rest = &rest[name.get_ref().len()..];
        while let Some(indexed) = rest.strip_prefix('[') {
            let (index, after) = indexed.split_once(']')?;
            let DeValue::Array(array) = current.into_inner() else {
                return None;
            };
            current = array.into_iter().nth(index.parse().ok()?)?;
            rest = after;
        }
        rest = rest.strip_prefix('.').unwrap_or(rest);
    }
    line_of_span(text, Some(current.span()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = r#"
[potentials]
inverse_power = [2, 6]

[engine]
tolerance = 1e-12

[scan]
offset_min = -5.0
offset_max = 5.0
points = 11

[[scan.launch]]
name = "symmetric"
u2 = 1.0
u3 = -1.0

[scan.overrides.ipp-6]
points = 21
"#;

    fn parse(text: &str) -> Result<Study, ConfigError> {
        Study::parse(Path::new("pipeline.toml"), text)
    }

    /// Potential ids name files: the range bounds keep the longest ones
    /// (17 significant digits, the most a shortest f64 form has) short.
    #[test]
    fn potential_ids_within_the_ranges_are_short() {
        let extremes = [
            Potential::InversePower {
                n: 1.0 + f64::EPSILON,
            },
            Potential::InversePower {
                n: 99.999_999_999_999_99,
            },
            Potential::LennardJones {
                theta: 0.001_234_567_890_123_456_7,
            },
            Potential::LennardJones {
                theta: 999.999_999_999_999_9,
            },
        ];
        for potential in extremes {
            assert!(potential.id().len() <= 24, "{}", potential.id());
        }
    }

    #[test]
    fn valid_config_resolves_overrides_per_potential() {
        let study = parse(VALID).unwrap();
        let potentials = study.potentials();
        assert_eq!(potentials.len(), 2);
        assert_eq!(study.scan_params(potentials[0]).grid.points, 11);
        assert_eq!(study.scan_params(potentials[1]).grid.points, 21);
    }

    #[test]
    fn out_of_range_tolerance_names_key_and_line() {
        let error = parse(&VALID.replace("tolerance = 1e-12", "tolerance = 0.5")).unwrap_err();
        assert_eq!(error.key, "engine.tolerance");
        assert_eq!(error.line, Some(6));
    }

    #[test]
    fn unknown_key_is_rejected_with_its_path() {
        let error = parse(&VALID.replace("points = 11", "points = 11\npionts = 3")).unwrap_err();
        assert!(error.message.contains("pionts"), "{error}");
        assert!(error.key.starts_with("scan"), "{error}");
        assert_eq!(error.line, Some(12));
    }

    #[test]
    fn wrong_type_names_key() {
        let error = parse(&VALID.replace("points = 11", "points = \"many\"")).unwrap_err();
        assert_eq!(error.key, "scan.points");
        assert_eq!(error.line, Some(11));
    }

    #[test]
    fn invalid_values_name_their_keys() {
        let cases = [
            (
                "inverse_power = [2, 6]",
                "inverse_power = [2, 0]",
                "potentials.inverse_power[1]",
            ),
            ("inverse_power = [2, 6]", "inverse_power = []", "potentials"),
            ("u2 = 1.0", "u2 = 0.0", "scan.launch[0].u2"),
            ("offset_max = 5.0", "offset_max = -6.0", "scan.offset_max"),
            (
                "[scan.overrides.ipp-6]",
                "[scan.overrides.ipp-7]",
                "scan.overrides.ipp-7",
            ),
        ];
        for (from, to, key) in cases {
            let error = parse(&VALID.replace(from, to)).unwrap_err();
            assert_eq!(error.key, key, "{error}");
        }
    }

    /// A Lennard-Jones gas fixes `theta = kT/eps`: a temperature that
    /// disagrees with its potential is named; a matching one runs as a ring.
    #[test]
    fn lennard_jones_gas_must_match_its_theta() {
        let ring = |kt: f64| {
            format!(
                "{VALID}\n[[gas]]\nname = \"lj\"\npotential = \"lj-0.1\"\nl0_um = 1.0\neps_ev = 1.0\nkt_ev = {kt}\nmass_amu = 4.0\nring_particles = 41\nring_radius_um = 6400.0\n\n[md]\nenabled = true\n\n[[md.system]]\nname = \"lj\"\ngas = \"lj\"\nfinal_time_ns = 10.0\n"
            )
            .replace("inverse_power = [2, 6]", "inverse_power = [2, 6]\nlennard_jones = [0.1]")
        };
        let error = parse(&ring(0.2)).unwrap_err();
        assert_eq!(error.key, "gas[0].kt_ev", "{error}");
        let study = parse(&ring(0.1)).unwrap();
        assert_eq!(
            study.md_params()[0].potential,
            Potential::LennardJones { theta: 0.1 }
        );
    }
}
