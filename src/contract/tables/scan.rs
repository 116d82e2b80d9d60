//! The `scan` stage.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "scan";

/// Name of the launch pair.
pub const LAUNCH: Col<String> = Col::text("launch", "name of the launch pair");
/// Velocity of the second arrival.
pub const U3: Col<f64> = Col::f64("u3", "v_th", "velocity of the second arrival");
/// Free-flight arrival offset (also in `collisions`' events).
pub const ARRIVAL_OFFSET: Col<f64> = Col::f64(
    "arrival_offset",
    "l/v_th",
    "free-flight arrival time of particle 3 minus that of particle 2 at the special particle",
);
/// Middle outgoing velocity (also in `collisions`' events).
pub const OUT_MIDDLE: Col<f64> = Col::f64("out_middle", "v_th", "middle outgoing velocity")
    .or_null("the scene failed (see outcome): no outgoing state");
/// Fastest outgoing velocity (also in `collisions`' events).
pub const OUT_FAST: Col<f64> = Col::f64("out_fast", "v_th", "fastest outgoing velocity")
    .or_null("the scene failed (see outcome): no outgoing state");
/// Outcome of a scene (also in `collisions`' events).
pub const OUTCOME: Col<String> = Col::text("outcome", "scattered, recombined or failed_*");
/// Force evaluations of a scene (also in `collisions`' events).
pub const FORCE_EVALUATIONS: Col<u32> = Col::u32(
    "force_evaluations",
    "1",
    "evaluations of the three pair forces",
);

/// `curve.parquet`: one row per launch pair and arrival offset.
pub mod curve {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "curve",
        description: "mono-energetic kick curves u1f(arrival offset)",
    };
    /// Launch velocity of the first arrival.
    pub const U2: Col<f64> = Col::f64(
        "u2",
        "v_th",
        "velocity of the first arrival (special particle at rest)",
    );
    /// Launch delay for entry at `-sign(u) L/2`.
    pub const LAUNCH_DELAY: Col<f64> = Col::f64(
        "launch_delay",
        "l/v_th",
        "launch time of particle 3 minus that of particle 2 for entry at -sign(u) L/2",
    );
    /// Final velocity of the special particle.
    pub const U1_FINAL: Col<f64> = Col::f64(
        "u1_final",
        "v_th",
        "final velocity of the special particle (sorted matching)",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
    /// Its tolerance sensitivity.
    pub const U1_FINAL_ERROR: Col<f64> = Col::f64(
        "u1_final_error",
        "v_th",
        "|u1_final - u1_final at 100x tighter tolerance|",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
    /// Slowest outgoing velocity.
    pub const OUT_SLOW: Col<f64> = Col::f64("out_slow", "v_th", "slowest outgoing velocity")
        .or_null("the scene failed (see outcome): no outgoing state");
    /// Relative energy error.
    pub const ENERGY_ERROR: Col<f64> = Col::f64(
        "energy_error",
        "1",
        "(E_out - E_in) / E_in of the relative motion",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
    /// Momentum error.
    pub const MOMENTUM_ERROR: Col<f64> = Col::f64(
        "momentum_error",
        "1",
        "|P_out - P_in| / relative-speed scale",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
    /// Accepted steps.
    pub const STEPS: Col<u32> = Col::u32("steps", "1", "accepted integrator steps");
    /// Rejected steps.
    pub const REJECTED_STEPS: Col<u32> =
        Col::u32("rejected_steps", "1", "rejected integrator steps");
}

/// `peak.parquet`: one row per launch pair.
pub mod peak {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "peak",
        description: "peak of each kick curve",
    };
    /// Launch velocity of the first arrival.
    pub const U2: Col<f64> = Col::f64("u2", "v_th", "velocity of the first arrival");
    /// Largest `|u1f|` with its error bound.
    pub const U1_FINAL_MAX_ABS: Pair = bounded!(
        "u1_final_max_abs",
        "v_th",
        "largest |u1f| over arrival offsets, refined between grid points",
        "error bound of u1_final_max_abs (tolerance sensitivity plus bracket spread)"
    )
    .or_null("no peak: every scene of the curve failed");
    /// Arrival offset of the maximum with the bracket's half-width.
    pub const ARRIVAL_OFFSET_AT_MAX: Pair = bounded!(
        "arrival_offset_at_max",
        "l/v_th",
        "arrival offset of the maximum",
        "half-width of the final bracket"
    )
    .or_null("the maximum was not located (no peak, or not bracketed by the offset grid)");
    /// Launch delay of the maximum.
    pub const LAUNCH_DELAY_AT_MAX: Col<f64> = Col::f64(
        "launch_delay_at_max",
        "l/v_th",
        "launch delay of the maximum for entry at -sign(u) L/2",
    )
    .or_null("no peak: every scene of the curve failed");
    /// Offset grid spacing.
    pub const GRID_SPACING: Col<f64> =
        Col::f64("grid_spacing", "l/v_th", "spacing of the offset grid");
    /// Failed scenes of the curve.
    pub const FAILED_SCENES: Col<u32> = Col::u32(
        "failed_scenes",
        "1",
        "scenes of the curve that failed (excluded)",
    );
    /// Worst energy error of the curve.
    pub const WORST_ENERGY_ERROR: Col<f64> = Col::f64(
        "worst_energy_error",
        "1",
        "largest |relative energy error| on the curve",
    );

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "mono-energetic scans: largest |u1f| (error bound) and its arrival offset",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new(super::super::POTENTIAL.name, Shown::Instance),
            Printed::new(LAUNCH.name, Shown::Text(LAUNCH)),
            Printed::new("|u1f,max| [v_th]", Shown::Estimate(U1_FINAL_MAX_ABS, "-")),
            Printed::new(
                "offset [l/v_th]",
                Shown::Estimate(ARRIVAL_OFFSET_AT_MAX, "no peak"),
            ),
            Printed::new("failed", Shown::Count(FAILED_SCENES)),
            Printed::new("max |dE/E|", Shown::Scientific(WORST_ENERGY_ERROR, 1)),
        ],
        footnote: Footnote::None,
    };
}
