//! The `convergence` stage: `convergence.parquet`, one row per setting.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "convergence";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "convergence",
    description: "a_n under changes of the numerical settings",
};
/// Which setting.
pub const PARAMETER: Col<String> = Col::text(
    "parameter",
    "default, density (rho l), offset_bound (|tau| <= B T), tolerance, bin_width (a_n from the binned kernel)",
);
/// Labels of [`PARAMETER`].
pub mod parameter {
    /// The configured settings.
    pub const DEFAULT: &str = "default";
    /// `rho l` of the literal algorithm.
    pub const DENSITY: &str = "density";
    /// A bound `|tau| <= B T` on the arrival offset.
    pub const OFFSET_BOUND: &str = "offset_bound";
    /// The integrator tolerance.
    pub const TOLERANCE: &str = "tolerance";
    /// The bin width of the binned kernel.
    pub const BIN_WIDTH: &str = "bin_width";

    /// Unit of a setting's value: `rho l`, the bound `B` (in units of
    /// the crossing time `T`) and the tolerance are pure numbers, a bin
    /// width is in `v_th`; the default row has no value.
    pub fn unit(parameter: &str) -> &'static str {
        match parameter {
            DENSITY | OFFSET_BOUND | TOLERANCE => "1",
            BIN_WIDTH => "v_th",
            _ => "",
        }
    }
}
/// The setting's value.
pub const VALUE: Col<f64> = Col::f64("value", UNIT_PER_ROW, "the setting's value")
    .or_null("the default row: no setting varied");
/// Unit of the setting's value.
pub const UNIT: Col<String> = Col::text(
    "unit",
    "unit of this row's value: 1 (density, offset_bound, tolerance), v_th (bin_width), empty (default)",
);
/// `a_n` at the setting.
pub const A_N: Pair = Pair {
    value: Col::f64(
        super::A_N,
        RATE,
        "self variance rate at u' = 0 within half the window (tolerance rows: of the launch pairs re-integrated)",
    ),
    stderr: Col::f64(
        "a_n_stderr",
        RATE,
        "standard error (spread of randomizations)",
    ),
};
/// Paired shift against the default.
pub const SHIFT: Pair = pair!(
    "shift",
    RATE,
    "a_n minus the default's on the same launch pairs, per replicate, averaged",
    "standard error of the paired shift"
);
/// Shift over the default's error.
pub const SHIFT_OVER_ERROR: Col<f64> = Col::f64(
    "shift_over_error",
    "1",
    "shift divided by the default's standard error: |value| << 1 means converged",
);

/// What `ternary run --details` and the HTML report print of the table.
pub const PRINTOUT: Printout = Printout {
    table: TABLE,
    title: "convergence of a_n for {instance} (shift = a_n - default, paired over randomizations)",
    layout: Layout::PerInstance,
    rows: Selection::All,
    columns: &[
        Printed::new(PARAMETER.name, Shown::Text(PARAMETER)),
        Printed::new(VALUE.name, Shown::Scientific(VALUE, 3)),
        Printed::new(A_N.value.name, Shown::Estimate(A_N, "-")),
        Printed::new(SHIFT.value.name, Shown::Estimate(SHIFT, "-")),
        Printed::new("shift / a_n error", Shown::Fixed(SHIFT_OVER_ERROR, 3)),
    ],
    footnote: Footnote::None,
};
