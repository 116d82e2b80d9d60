//! The `launches` stage: `launches.parquet`, one row per launch pair drawn.

pub use super::collisions::{POINT, RANDOMIZATION, STRATUM, U2, U3};
use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "launches";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "launches",
    description: "launch pairs of the collision kernel's point set, before integration",
};
/// Proposal density of the launch pair.
pub const LAUNCH_DENSITY: Col<f64> = Col::f64(
    "launch_density",
    "1/v_th^2",
    "proposal density of (|u2|, |u3|) within the stratum",
);
/// Third coordinate of the point.
pub const OFFSET_COORDINATE: Col<f64> = Col::f64(
    "offset_coordinate",
    "1",
    "third coordinate of the scrambled Sobol' point in (0, 1): the arrival offset's when offsets are sampled",
);
