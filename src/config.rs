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
use crate::physics::scene::{EngineSettings, Method};

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
        write!(f, ": `{}`: {}", self.key, self.message)
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
}

impl Default for EngineConfig {
    fn default() -> Self {
        EngineConfig {
            method: Method::Dprkn12,
            tolerance: 1e-12,
            max_steps: 100_000,
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
        let text = std::fs::read_to_string(file).map_err(|error| ConfigError {
            file: file.to_path_buf(),
            key: String::new(),
            line: None,
            message: format!("cannot read the file: {error}"),
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
                e.message().to_string(),
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
        }
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
    validate_scan(config)
}

fn validate_potentials(potentials: &PotentialsConfig) -> Result<(), Invalid> {
    check(
        !potentials.inverse_power.is_empty() || !potentials.lennard_jones.is_empty(),
        "potentials",
        "lists no potential: give `inverse_power = [6]` or `lennard_jones = [1.0]`",
    )?;
    for (k, &n) in potentials.inverse_power.iter().enumerate() {
        check(
            n.is_finite() && n > 1.0,
            format!("potentials.inverse_power[{k}]"),
            format!("n = {n} must be a finite number > 1 (the potential tail must be integrable)"),
        )?;
    }
    for (k, &theta) in potentials.lennard_jones.iter().enumerate() {
        check(
            theta.is_finite() && theta > 0.0,
            format!("potentials.lennard_jones[{k}]"),
            format!("theta = kT/eps = {theta} must be a finite number > 0"),
        )?;
    }
    check_unique(&potentials.inverse_power, "potentials.inverse_power")?;
    check_unique(&potentials.lennard_jones, "potentials.lennard_jones")
}

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

fn validate_grid(grid: &ScanGrid, prefix: &str) -> Result<(), Invalid> {
    check(
        grid.offset_min.is_finite() && grid.offset_max.is_finite(),
        format!("{prefix}offset_min"),
        "offsets must be finite",
    )?;
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
        !scan.launch.is_empty(),
        "scan.launch",
        "lists no launch pair",
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
/// the spanned document tree.
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    let root = DeTable::parse(text).ok()?;
    let mut current: toml::Spanned<DeValue> =
        toml::Spanned::new(root.span(), DeValue::Table(root.into_inner()));
    for segment in key.split('.').filter(|s| !s.is_empty()) {
        let (name, index) = match segment.split_once('[') {
            Some((name, rest)) => (name, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (segment, None),
        };
        let DeValue::Table(table) = current.into_inner() else {
            return None;
        };
        current = table
            .into_iter()
            .find(|(k, _)| k.get_ref().as_ref() == name)?
            .1;
        if let Some(index) = index {
            let DeValue::Array(array) = current.into_inner() else {
                return None;
            };
            current = array.into_iter().nth(index)?;
        }
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
}
