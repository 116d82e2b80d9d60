//! `[scan]`: mono-energetic kick curves, with per-potential grid overrides.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check, check_name, check_unique, potential_named};
use crate::physics::potential::Potential;
use crate::physics::scene::EngineSettings;

/// `[scan]`: settings shared by all potentials, with per-potential overrides.
#[derive(Clone, Debug, Deserialize, Serialize)]
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
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize)]
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

/// Largest offsets per launch pair of a scan.
pub const MAX_SCAN_POINTS: u32 = 1 << 20;

/// Largest scenes of one scan (offsets x launch pairs).
pub const MAX_SCAN_SCENES: u64 = 1 << 22;

/// Largest `|offset|` of a scan grid (`l/v_th`): collision times are of
/// order `l/v_th`, so arrivals a thousand apart collide only in pairs.
pub const MAX_SCAN_OFFSET: f64 = 1e3;

/// Largest launch speed of a scan (`v_th`): no thermal particle is faster
/// (the kernel's point sets reach 6.8).
pub const MAX_LAUNCH_SPEED: f64 = 20.0;

/// Smallest launch speed `|u|` of a scan, `v_th`: a slower particle takes
/// longer than the step budget to cross the offsets.
pub const MIN_LAUNCH_SPEED: f64 = 1e-3;

/// Largest number of scan launch pairs.
pub const MAX_SCAN_LAUNCHES: usize = 64;

fn validate_grid(grid: &ScanGrid, prefix: &str) -> Result<(), Invalid> {
    for (name, value) in [
        ("offset_min", grid.offset_min),
        ("offset_max", grid.offset_max),
    ] {
        check(
            value.is_finite() && value.abs() <= MAX_SCAN_OFFSET,
            format!("{prefix}{name}"),
            format!(
                "{value} is outside [-{MAX_SCAN_OFFSET}, {MAX_SCAN_OFFSET}] (arrivals farther apart never meet in one collision)"
            ),
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

impl ScanConfig {
    /// Checks the grid (and every override's) and the launch pairs.
    pub(super) fn validate(&self, potentials: &[Potential]) -> Result<(), Invalid> {
        let scan = self;
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
                    (MIN_LAUNCH_SPEED..=MAX_LAUNCH_SPEED).contains(&u.abs()),
                    format!("scan.launch[{k}].{name}"),
                    format!(
                        "{u} must have a size in [{MIN_LAUNCH_SPEED}, {MAX_LAUNCH_SPEED}] v_th (a particle at rest never arrives)"
                    ),
                )?;
            }
            check(
                launch.u2 != launch.u3,
                format!("scan.launch[{k}].u3"),
                "equal velocities never collide",
            )?;
            check_name(&launch.name, format!("scan.launch[{k}].name"))?;
        }
        let names: Vec<&str> = scan.launch.iter().map(|l| l.name.as_str()).collect();
        check_unique(&names, |k| format!("scan.launch[{k}].name"))?;
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
        for id in scan.overrides.keys() {
            potential_named(id, potentials, format!("scan.overrides.{id}"))?;
            validate_grid(&scan.grid(id), &format!("scan.overrides.{id}."))?;
        }
        Ok(())
    }

    /// Resolved parameters of the scan of `potential`.
    pub fn params(&self, potential: Potential, engine: EngineSettings) -> ScanParams {
        ScanParams {
            potential,
            engine,
            launch_length: self.launch_length,
            grid: self.grid(&potential.id()),
            launches: self.launch.clone(),
        }
    }
}
