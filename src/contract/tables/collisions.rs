//! The `collisions` stage: `events.parquet`, one row per integrated scene.

pub use super::scan::{ARRIVAL_OFFSET, FORCE_EVALUATIONS, OUT_FAST, OUT_MIDDLE, OUTCOME};
use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "collisions";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "events",
    description: "integrated three-body scenes for the collision kernel",
};
/// Replicate.
pub const RANDOMIZATION: Col<u32> = Col::u32(
    "randomization",
    "1",
    "independent randomization (replicate) of the point set",
);
/// Stratum index.
pub const STRATUM: Col<u32> = Col::u32(
    "stratum",
    "1",
    "sign pattern: 0 opposite sides (u2 > 0 > u3), 1 same side (u2, u3 > 0; mirror image stands for both < 0)",
);
/// Sobol' point index.
pub const POINT: Col<u32> = Col::u32("point", "1", "index of the scrambled Sobol' point");
/// Node of the offset rule.
pub const NODE: Col<u32> = Col::u32(
    "node",
    "1",
    "node of the arrival-offset rule within the point's launch pair (0 when the offset is sampled)",
);
/// Error bound of the pair's offset rule.
pub const QUADRATURE_ERROR: Col<f64> = Col::f64(
    "quadrature_error",
    "v_th^2 l/v_th",
    "change of the launch pair's offset rule on int self_kick^2 d(arrival_offset) at its last halving: a bound on its error for a potential without a well, where the kick is smooth in the offset; with a well (orbiting and bound pairs) only a measure of roughness (0 when the offset is sampled)",
);
/// Launch velocity of the first arrival.
pub const U2: Col<f64> = Col::f64(
    "u2",
    "v_th",
    "launch velocity of the first arrival, special particle's frame",
);
/// Launch velocity of the second arrival.
pub const U3: Col<f64> = Col::f64("u3", "v_th", "launch velocity of the second arrival");
/// Proposal density.
pub const PROPOSAL_DENSITY: Col<f64> = Col::f64(
    "proposal_density",
    "1/(v_th^2 l/v_th)",
    "joint sampling density of (|u2|, |u3|, arrival_offset) within the stratum; for a quadrature node, the launch pair's density over the node's weight",
);
/// Slowest outgoing velocity.
pub const OUT_SLOW: Col<f64> = Col::f64(
    "out_slow",
    "v_th",
    "slowest outgoing velocity, special particle's frame",
)
.or_null("the scene failed (see outcome): no outgoing state");
/// The special particle's kick.
pub const SELF_KICK: Col<f64> = Col::f64(
    "self_kick",
    "v_th",
    "velocity change of the special particle (sorted matching)",
)
.or_null("the scene failed (see outcome): no outgoing state");
/// Relative energy error.
pub const ENERGY_ERROR: Col<f64> = Col::f64(
    "energy_error",
    "1",
    "(E_out - E_in) / (E_in + well depth) of the relative motion",
)
.or_null("the scene failed (see outcome): no outgoing state");
/// Internal energy of the bound pair.
pub const BINDING_ENERGY: Col<f64> = Col::f64(
    "binding_energy",
    "kT",
    "internal energy w^2/4 + U of the pair left bound (w its members' relative velocity), in (-D, 0) with D the well depth: minus the energy that binds it",
)
.or_null("the scene did not recombine (see outcome): no bound pair");
