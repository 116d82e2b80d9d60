//! The `moments` stage: `moments.parquet`, one row per truncation.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "moments";

/// Standard error of every rate.
const SPREAD: &str = "standard error from the spread of randomizations";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "moments",
    description: "drift and variance rates against truncation, units of rho^2 l v_th",
};
/// Truncation half-width.
pub const TRUNCATION: Col<f64> = Col::f64(
    "truncation",
    "v_th",
    "half-width X: only |u - u'| <= X counts",
)
.or_null("no truncation: every |u - u'| counts");
/// Self drift rate.
pub const SELF_DRIFT: Pair = pair!(
    "self_drift",
    RATE,
    "drift rate d<u - u'>/dt of the special particle",
    SPREAD
);
/// Self variance rate (`a_n`).
pub const SELF_VARIANCE: Pair = pair!(
    "self_variance",
    RATE,
    "variance rate d<(u - u')^2>/dt of the special particle in scenes whose three atoms leave free (a_n at u' = 0)",
    SPREAD
);
/// Window drift rate.
pub const WINDOW_DRIFT: Pair = pair!(
    "window_drift",
    RATE,
    "drift rate of all particles within the truncation",
    SPREAD
);
/// Window variance rate.
pub const WINDOW_VARIANCE: Pair = pair!(
    "window_variance",
    RATE,
    "variance rate of all particles within the truncation (untruncated: 0 by energy conservation up to the engine's error, energy_error_bound)",
    SPREAD
);
/// What the integrator's energy error contributes to the untruncated
/// window variance.
pub const ENERGY_ERROR_BOUND: Col<f64> = Col::f64(
    "energy_error_bound",
    RATE,
    "sum over scenes of weight |sum_particles (u_out^2 - u_in^2)|, mean over randomizations: the energy the scenes' velocities gained or lost, summed without its sign (the scattering engine's error, and the kick floor's, which sets velocity changes below it to zero). Energy conservation makes the untruncated window_variance exactly 0, so its value is theirs and |window_variance| <= this bound (its standard error measures the scatter, not this)",
)
.or_null("a truncated row: particles crossing the edge move variance in or out, so it is not 0");
/// Recombination rate (the same in every row).
pub const RECOMBINATION_RATE: Pair = pair!(
    "recombination_rate",
    RATE,
    "rate at which the special particle takes part in a three-body encounter that leaves a bound pair and a free atom (such scenes are no part of the free-atom rates in the other columns; 0 without a well; the same in every row)",
    SPREAD
);
/// Scenes that recombined.
pub const RECOMBINED_EVENTS: Col<u32> = Col::u32(
    "recombined_events",
    "1",
    "scenes that left a bound pair and a free atom",
);
/// Scenes drawn.
pub const EVENTS: Col<u32> = Col::u32(super::EVENTS, "1", "scenes drawn");
/// Scenes failed.
pub const FAILED_EVENTS: Col<u32> = Col::u32(
    super::FAILED_EVENTS,
    "1",
    "scenes that failed (counted as drawn, contributing nothing)",
);
