//! The `figures` stage: one instance per figure.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "figures";

/// `points.parquet`: one row per plotted point. Units of `x` and `y` are
/// per panel, in the file's `ternary.axes` metadata (the figure's layout):
/// their declared unit is [`UNIT_PER_PANEL`].
pub mod points {
    use super::*;

    /// Panel the point is drawn in.
    pub const PANEL: Col<String> = Col::text("panel", "panel of the figure, top to bottom");
    /// Series (a legend entry).
    pub const SERIES: Col<String> = Col::text("series", "series: one legend entry");
    /// Horizontal coordinate.
    pub const X: Col<f64> = Col::f64(
        "x",
        UNIT_PER_PANEL,
        "horizontal coordinate (unit: the panel's x axis)",
    );
    /// Vertical coordinate.
    pub const Y: Col<f64> = Col::f64(
        "y",
        UNIT_PER_PANEL,
        "vertical coordinate (unit: the panel's y axis)",
    )
    .or_null("no value at this point: a null in the plotted table");
    /// Its standard error (0 where the series has none).
    pub const Y_ERROR: Col<f64> = Col::f64(
        "y_error",
        UNIT_PER_PANEL,
        "standard error of y (0 for lines without errors: fits, closed forms)",
    )
    .or_null("no error at this point: a null in the plotted table");
}
