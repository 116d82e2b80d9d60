//! The study definition, `pipeline.toml`: parsed strictly, validated and
//! resolved into per-stage parameters in one pass.
//!
//! One module per section (`[store]`, `[potentials]`, `[engine]`, `[scan]`,
//! `[collisions]`, `[kernel]`, `[sweep]`, `[dissociation]`, `[convergence]`, `[evolve]`, `[spectrum]`,
//! `[md]`, `[[gas]]`, `[figures]`, `[publication]`, `[limits]`, `[slurm]`), each owning its schema with defaults, the check of
//! every documented range, and the parameters of the stages it configures.
//! Unknown keys, wrong types and out-of-range values are rejected with a
//! [`ConfigError`] naming the key path and, where the document shows it, the
//! line. Every key is documented in docs/configuration.md (a test checks the table
//! against the defaults here).
//!
//! **Adding a key.** A stage's parameters are hashed into its artifact keys.
//! A new parameter field must be skipped from serialization at its default
//! (`#[serde(skip_serializing_if = "...")]`), so that adding it recomputes
//! nothing; only a value other than the default changes keys.

mod check;
mod collisions;
mod convergence;
mod dissociation;
mod engine;
mod evolve;
mod figures;
mod gas;
mod kernel;
mod limits;
mod md;
mod potentials;
mod publication;
mod rings;
mod scan;
mod slurm;
mod spectrum;
mod store;
mod sweep;

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::physics::potential::Potential;
use crate::physics::scene::EngineSettings;

pub use check::{MAX_LIST, compact};
pub use collisions::{
    CollisionsConfig, CollisionsParams, LaunchesParams, MAX_PILOT_POINTS, MAX_RANDOMIZATIONS,
    MAX_SCENES, OffsetMethod, StrataPoints,
};
pub use convergence::{ConvergenceConfig, ConvergenceParams};
pub use dissociation::{DissociationConfig, DissociationParams, MAX_DISSOCIATION_POINTS};
pub use engine::EngineConfig;
pub use evolve::{EvolveConfig, EvolveParams, MAX_EVOLVE_HALF_NODES, PhysicalTimes};
pub use figures::FiguresConfig;
pub use gas::{GasConfig, GasParams, MAX_GAS_DENSITY, MAX_RING_PARTICLES};
pub use kernel::{
    DEFAULT_KICK_FLOOR, FitParams, KernelConfig, KernelParams, MAX_BINS, PAPER_TRUNCATION,
};
pub use limits::LimitsConfig;
pub use md::{
    MAX_MD_RUNS, MAX_MD_SAMPLES, MAX_NEIGHBOURS, MAX_RING_ENCOUNTERS, MdConfig, MdParams,
    MdSystemConfig,
};
pub use potentials::PotentialsConfig;
pub use publication::{AuthorConfig, LICENSES, PublicationConfig, license_url};
pub use scan::{
    MAX_SCAN_LAUNCHES, MAX_SCAN_POINTS, MAX_SCAN_SCENES, NamedLaunch, ScanConfig, ScanGrid,
    ScanGridOverride, ScanParams,
};
pub use slurm::SlurmConfig;
pub use spectrum::{MAX_SPECTRUM_MODES, SpectrumConfig, SpectrumEstimator, SpectrumParams};
pub use store::StoreConfig;
pub use sweep::{MAX_SWEEP_POINTS, SweepConfig, SweepParams};

use check::Invalid;

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
#[derive(Clone, Debug, Deserialize, Serialize)]
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
    /// Collision-induced dissociation of bound pairs (potentials with a well).
    #[serde(default)]
    pub dissociation: DissociationConfig,
    /// The convergence study of `a_n` under numerical settings.
    #[serde(default)]
    pub convergence: ConvergenceConfig,
    /// Evolution of `h(u, t)` by the master and Fokker-Planck equations.
    #[serde(default)]
    pub evolve: EvolveConfig,
    /// The relaxation spectrum of the collision generators.
    #[serde(default)]
    pub spectrum: SpectrumConfig,
    /// Molecular dynamics of rings.
    #[serde(default)]
    pub md: MdConfig,
    /// Gases in physical units whose thermalization rates are tabulated.
    #[serde(default)]
    pub gas: Vec<GasConfig>,
    /// The figures.
    #[serde(default)]
    pub figures: FiguresConfig,
    /// How an exported dataset describes and credits itself.
    #[serde(default)]
    pub publication: PublicationConfig,
    /// The largest study started without `--i-know`.
    #[serde(default)]
    pub limits: LimitsConfig,
    /// What `slurm submit` asks of the scheduler.
    #[serde(default)]
    pub slurm: SlurmConfig,
}

/// A loaded and validated study, with the parameters that needed lookups
/// across sections resolved once.
#[derive(Clone, Debug)]
pub struct Study {
    /// The configuration file.
    pub file: PathBuf,
    /// Parsed content.
    pub config: Config,
    /// The potentials, inverse power laws first, in file order.
    potentials: Vec<Potential>,
    /// The gases with their potentials.
    gases: Vec<GasParams>,
    /// The rings of `[md]` (empty when disabled).
    md: Vec<MdParams>,
    /// The evolve stage, when enabled.
    evolve: Option<EvolveParams>,
    /// The convergence study and its collisions at other tolerances, when enabled.
    convergence: Option<(ConvergenceParams, Vec<CollisionsParams>)>,
}

/// Most kernels of one study (potentials times `(u', density)` targets):
/// each is an instance of `kernel`, `moments`, `fit` and a figure, so the
/// plan's size is bounded at load, before anything is planned.
pub const MAX_KERNELS: usize = 4096;

/// Largest configuration file read: a study of every key with hundreds of
/// rings and gases is ~100 kB (a `/dev/zero` or a data file given by mistake
/// must not be read without end).
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// The bytes of `file` if it holds at most `limit` of them, `None` if more.
fn read_bounded(file: &Path, limit: u64) -> std::io::Result<Option<Vec<u8>>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(file)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= limit).then_some(bytes))
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
        let bytes = read_bounded(file, MAX_CONFIG_BYTES)
            .map_err(|e| error(None, format!("cannot read the file: {e}")))?
            .ok_or_else(|| {
                error(
                    None,
                    format!("the file is larger than {MAX_CONFIG_BYTES} bytes: not a study configuration"),
                )
            })?;
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

    /// Parses, validates and resolves configuration text (`file` is used in messages).
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
            let mut message = e.inner().message().to_string();
            // A date-time deserializes as a map inside the TOML reader.
            if let Some(date) = date_at_key(text, &key) {
                message = message.replace(
                    "invalid type: map",
                    &format!("invalid type: date-time `{date}`"),
                );
            }
            error(key, line, check::shortened(&message))
        })?;
        Study::resolve(file, config).map_err(|(key, message)| {
            let line = line_of_key(text, &key);
            error(
                key,
                line,
                check::shortened(&check::compact_numbers(&message)),
            )
        })
    }

    /// Checks every section in dependency order and resolves what needs
    /// lookups across sections, in one pass.
    fn resolve(file: &Path, config: Config) -> Result<Study, Invalid> {
        config.store.validate()?;
        let potentials = config.potentials.resolve()?;
        config.engine.validate(&potentials)?;
        config.scan.validate(&potentials)?;
        config.collisions.validate(&potentials)?;
        let launch = config.collisions.launch();
        config.kernel.validate(&launch)?;
        let kernels = potentials.len() * config.kernel.targets().len();
        check::check(
            kernels <= MAX_KERNELS,
            "kernel",
            format!(
                "{} potentials x {} (u', density) targets are {kernels} kernels, more than {MAX_KERNELS}: every kernel is an instance of four stages; split the study",
                potentials.len(),
                config.kernel.targets().len()
            ),
        )?;
        let wide = config.sweep.wide_launch(&launch);
        config.sweep.validate(&wide)?;
        config.dissociation.validate()?;
        let gases = gas::resolve(&config.gas, &potentials)?;
        let convergence = config.convergence.resolve(&convergence::Context {
            potentials: &potentials,
            collisions: &config.collisions,
            kernel: &config.kernel,
            engine: &config.engine,
        })?;
        let evolve = config.evolve.resolve(&evolve::Context {
            potentials: &potentials,
            gases: &gases,
            kernel: &config.kernel,
            launch: &launch,
            wide: &wide,
        })?;
        config.spectrum.validate(&wide)?;
        let md = config.md.resolve(&config.gas, &gases)?;
        config.publication.validate()?;
        config.limits.validate()?;
        config.slurm.validate()?;
        Ok(Study {
            file: file.to_path_buf(),
            potentials,
            gases,
            md,
            evolve,
            convergence,
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
        self.potentials.clone()
    }

    /// Engine settings of the scenes of `potential` as the physics sees them.
    pub fn engine(&self, potential: Potential) -> EngineSettings {
        self.config.engine.settings(&potential)
    }

    /// Resolved parameters of the collision scenes of `potential`.
    pub fn collisions_params(&self, potential: Potential) -> CollisionsParams {
        self.config
            .collisions
            .params(potential, self.engine(potential))
    }

    /// Every `(u', density)` the kernel is evaluated at, with `(0, 0)` (which
    /// defines `a_n`) always first.
    pub fn kernel_targets(&self) -> Vec<(f64, f64)> {
        self.config.kernel.targets()
    }

    /// Resolved kernel parameters of `potential` at `(u', density)`.
    pub fn kernel_params(&self, potential: Potential, u_prime: f64, density: f64) -> KernelParams {
        self.config.kernel.params(potential, u_prime, density)
    }

    /// Resolved parameters of the shape fit of a kernel.
    pub fn fit_params(&self, kernel: KernelParams) -> FitParams {
        self.config.kernel.fit(kernel)
    }

    /// Resolved parameters of the sweep of `potential`, if enabled.
    pub fn sweep_params(&self, potential: Potential) -> Option<SweepParams> {
        let kernel = self.kernel_params(potential, 0.0, 0.0);
        self.config.sweep.params(kernel)
    }

    /// Resolved parameters of the dissociation of `potential`, if enabled
    /// and its family has a well.
    pub fn dissociation_params(&self, potential: Potential) -> Option<DissociationParams> {
        self.config
            .dissociation
            .params(potential, self.engine(potential))
    }

    /// Resolved parameters of the spectrum of `potential`, if enabled.
    pub fn spectrum_params(&self, potential: Potential) -> Option<SpectrumParams> {
        self.config.spectrum.params(&self.config.kernel, potential)
    }

    /// Resolved parameters of every md system (empty unless enabled).
    pub fn md_params(&self) -> Vec<MdParams> {
        self.md.clone()
    }

    /// Resolved parameters of the evolve stage, if enabled.
    pub fn evolve_params(&self) -> Option<EvolveParams> {
        self.evolve.clone()
    }

    /// Resolved convergence parameters and the collisions at each varied
    /// tolerance, if the study is enabled.
    pub fn convergence(&self) -> Option<(ConvergenceParams, Vec<CollisionsParams>)> {
        self.convergence.clone()
    }

    /// The configured gases with their potentials.
    pub fn gases(&self) -> Vec<GasParams> {
        self.gases.clone()
    }

    /// Resolved parameters of the scan of `potential`.
    pub fn scan_params(&self, potential: Potential) -> ScanParams {
        self.config.scan.params(potential, self.engine(potential))
    }
}

/// 1-based line of a byte offset.
fn line_of_span(text: &str, span: Option<std::ops::Range<usize>>) -> Option<usize> {
    let start = span?.start.min(text.len());
    Some(text[..start].matches('\n').count() + 1)
}

/// Line of the value at a dotted key path such as `scan.launch[1].u2`.
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    line_of_span(text, Some(value_at_key(text, key)?.span()))
}

/// The date-time written at `key`, if the value there is one.
fn date_at_key(text: &str, key: &str) -> Option<String> {
    match value_at_key(text, key)?.into_inner() {
        toml::de::DeValue::Datetime(date) => Some(date.to_string()),
        _ => None,
    }
}

/// The spanned value at a dotted key path such as `scan.launch[1].u2`, found
/// in the spanned document tree. A segment may itself hold dots (a quoted
/// key such as `points_per_potential."lj-0.1"`): at each level the longest
/// key of the table that the path continues with is taken.
fn value_at_key<'t>(text: &'t str, key: &str) -> Option<toml::Spanned<toml::de::DeValue<'t>>> {
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
    Some(current)
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
            Potential::inverse_power(1.0 + f64::EPSILON),
            Potential::inverse_power(99.999_999_999_999_99),
            Potential::lennard_jones(0.001_234_567_890_123_456_7),
            Potential::lennard_jones(999.999_999_999_999_9),
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
            Potential::lennard_jones(0.1)
        );
    }
}
