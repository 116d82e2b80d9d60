//! The `md` stage.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "md";

/// `h.parquet`: one row per bin.
pub mod h {
    pub use super::super::{BIN_CENTRE, DU};
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "h",
        description: "h(u, t_f) of a ring by molecular dynamics",
    };
    /// Published estimator.
    pub const H_PUBLISHED: Pair = pair!(
        "h_published",
        DENSITY,
        "published estimator: velocities in the bin minus (N - 1) f0, per bin width, averaged over the sample times",
        OVER_RUNS
    );
    /// Tagged-velocity estimator.
    pub const H_TAGGED: Pair = pair!(
        "h_tagged",
        DENSITY,
        "tagged-velocity estimator: change of every velocity lineage starting within start_band of u', per lineage and bin width",
        OVER_RUNS
    );
}

/// `summary.parquet`: one row per estimator ([`estimator`]).
pub mod summary {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "summary",
        description: "moments of h(u, t_f) within the window",
    };
    /// Which estimator.
    pub const ESTIMATOR: Col<String> = Col::text(
        "estimator",
        "published (background subtracted), tagged (velocity lineages starting within start_band of u'), or thermal (every lineage starting with |u| <= 3: number = fraction whose change stays within the window, window_variance = mean of its square there)",
    );
    /// Mass in the window.
    pub const NUMBER: Pair = pair!("number", "1", "sum h dx over the window", OVER_RUNS);
    /// Variance in the window.
    pub const WINDOW_VARIANCE: Pair = pair!(
        "window_variance",
        "v_th^2",
        "sum (u - u')^2 h dx over the window",
        OVER_RUNS
    );

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "ring molecular dynamics: h(u, t_f) within the window (+- standard errors over runs)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new(super::RING, Shown::Instance),
            Printed::new(ESTIMATOR.name, Shown::Text(ESTIMATOR)),
            Printed::new("sum h du", Shown::Estimate(NUMBER, "-")),
            Printed::new(
                "<(u-u')^2>_window [v_th^2]",
                Shown::Variance(WINDOW_VARIANCE),
            ),
        ],
        footnote: Footnote::None,
    };
}

/// `runs.parquet`: one row per run.
pub mod runs {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "runs",
        description: "conservation diagnostics and work per run",
    };
    /// Run index.
    pub const RUN: Col<u32> = Col::u32("run", "1", "run index");
    /// Its seed.
    pub const SEED: Col<String> = Col::text("seed", "seed of the run's initial state");
    /// Tagged lineages.
    pub const LINEAGES: Col<f64> = Col::f64("lineages", "1", "lineages in the tagged estimator");
    /// Thermal lineages.
    pub const THERMAL_LINEAGES: Col<f64> = Col::f64(
        "thermal_lineages",
        "1",
        "lineages in the thermal estimator (|u| <= 3 at the start)",
    );
    /// Energy error.
    pub const ENERGY_ERROR: Col<f64> = Col::f64("energy_error", "1", "|E(t_end) - E(0)| / E(0)");
    /// Momentum error.
    pub const MOMENTUM_ERROR: Col<f64> = Col::f64("momentum_error", "v_th", "|P(t_end) - P(0)|");
    /// Macro steps.
    pub const MACRO_STEPS: Col<f64> = Col::f64(
        "macro_steps",
        "1",
        "macro steps of the cluster stepping (accepted steps of a whole ring)",
    );
    /// Pair forces.
    pub const PAIR_FORCES: Col<f64> = Col::f64("pair_forces", "1", "pair-force evaluations");
    /// Bound pairs at the start.
    pub const BOUND_PAIRS_START: Col<u32> = Col::u32(
        "bound_pairs_start",
        "1",
        "bound neighbour pairs (w^2/4 + U < 0) in the initial state",
    );
    /// Bound pairs at the end.
    pub const BOUND_PAIRS_END: Col<u32> = Col::u32(
        "bound_pairs_end",
        "1",
        "bound neighbour pairs at the last sample time",
    );
    /// Sutherland invariants' drift.
    pub const INVARIANT_DRIFT: Col<f64> = Col::f64(
        "invariant_drift",
        "v_th",
        "largest change of a Lax eigenvalue (rapidity) over the run: the n = 2 Sutherland ring's conservation check",
    )
    .or_null("not the n = 2 Sutherland ring: no conserved rapidities to check");
}

/// The tables of a shard of a ring's runs (stage `md.shard`): every run's
/// estimators and diagnostics, exactly, for the merge into the ring's tables.
pub mod shard {
    pub use super::runs::{
        BOUND_PAIRS_END, BOUND_PAIRS_START, ENERGY_ERROR, INVARIANT_DRIFT, LINEAGES, MACRO_STEPS,
        MOMENTUM_ERROR, PAIR_FORCES, RUN, THERMAL_LINEAGES,
    };
    use super::*;

    /// One row per run.
    pub const RESULTS: TableSpec = TableSpec {
        stage: STAGE,
        name: "run_results",
        description: "each run's diagnostics and thermal-lineage estimates (a shard of the runs)",
    };
    /// Thermal lineages within the window.
    pub const THERMAL_NUMBER: Col<f64> = Col::f64(
        "thermal_number",
        "1",
        "fraction of thermal lineages whose change stays within the window",
    );
    /// Their mean square change.
    pub const THERMAL_WINDOW_VARIANCE: Col<f64> = Col::f64(
        "thermal_window_variance",
        "v_th^2",
        "mean square change of the thermal lineages within the window",
    );
    /// One row per run and bin.
    pub const BINS: TableSpec = TableSpec {
        stage: STAGE,
        name: "run_bins",
        description: "each run's estimators per bin (a shard of the runs)",
    };
    /// Bin index.
    pub const BIN: Col<u32> = Col::u32("bin", "1", "bin index");
    /// The run's published estimator.
    pub const PUBLISHED: Col<f64> = Col::f64(
        "published",
        "1/v_th",
        "the run's published estimator, averaged over the sample times",
    );
    /// The run's tagged estimator.
    pub const TAGGED: Col<f64> = Col::f64(
        "tagged",
        "1/v_th",
        "the run's tagged-velocity estimator, averaged over the sample times",
    );
}

/// `pairs.parquet`: one row per state.
pub mod pairs {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "pairs",
        description: "bound neighbour pairs of the ring: sampler, dynamics and dilute limit",
    };
    /// Which state.
    pub const STATE: Col<String> = Col::text(
        "state",
        "initial (sampled), final (after MD), or dilute_limit (rho K_b)",
    );
    /// Bound fraction.
    pub const BOUND_FRACTION: Pair = pair!(
        "bound_fraction",
        "1",
        "bound neighbour pairs per gap",
        "standard error over runs (0 for the closed form; its O(rho l) correction is not included)"
    );
    /// Row of the sampled initial states.
    pub const INITIAL: &str = "initial";
    /// Row after the dynamics.
    pub const FINAL: &str = "final";
    /// Row of the closed form `rho K_b`.
    pub const DILUTE_LIMIT: &str = "dilute_limit";

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "bound neighbour pairs per gap of the rings with a well: sampled at the start, after the dynamics, and the dilute limit rho K_b (+- standard errors over runs)",
        layout: Layout::Joined,
        rows: Selection::NonZero(BOUND_FRACTION.value),
        columns: &[
            Printed::new(super::RING, Shown::Instance),
            Printed::new(STATE.name, Shown::Text(STATE)),
            Printed::new("bound pairs per gap", Shown::Estimate(BOUND_FRACTION, "-")),
        ],
        footnote: Footnote::None,
    };
}
