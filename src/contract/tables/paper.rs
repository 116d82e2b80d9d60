//! The `paper` stage: `paper.parquet`, one row per published number.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "paper";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "paper",
    description: "published numbers of Phys. Rev. E 110, 014114 (2024) against ours under the paper's definition",
};
/// What the number is.
pub const QUANTITY: Col<String> = Col::text("quantity", "the published quantity");
/// Where the paper gives it.
pub const SOURCE: Col<String> = Col::text("source", "where the paper gives it");
/// Unit of the published value and ours.
pub const UNIT: Col<String> = Col::text("unit", "unit of the value columns of this row");
/// The row's `n` in Table I.
pub const TABLE_I_N: Col<f64> =
    Col::f64("table_i_n", "1", "exponent n of the row's Table I cell").or_null("not in Table I");
/// The row's column in Table I.
pub const TABLE_I_COLUMN: Col<String> = Col::text(
    "table_i_column",
    "column of the row's Table I cell: a_n, alpha, beta, sigma or |u1f,max| (empty: not in Table I)",
);
/// The published value.
pub const PUBLISHED: Pair = pair!(
    "published",
    UNIT_PER_ROW,
    "the published value",
    "its uncertainty: as printed, else half a unit of its last printed digit"
);
/// Ours under the paper's definition.
pub const OURS: Pair = pair!(
    "ours",
    UNIT_PER_ROW,
    "ours under the paper's definition",
    "standard error"
)
.or_null("the study lacks what this row is computed from (see note)");
/// `ours / published - 1`.
pub const RELATIVE_DIFFERENCE: Col<f64> =
    Col::f64("relative_difference", "1", "ours / published - 1")
        .or_null("ours is missing (see note), or the published value is zero");
/// z-score of the difference.
pub const Z: Col<f64> = Col::f64(
    "z",
    "1",
    "(ours - published) / sqrt(ours_stderr^2 + published_stderr^2)",
)
.or_null("no measurement: ours holds by construction, or is missing");
/// Ours under our (converged) definition, where it differs.
pub const OURS_CONVERGED: Pair = pair!(
    "ours_converged",
    UNIT_PER_ROW,
    "ours under our definition where it differs from the paper's",
    "standard error"
)
.or_null("see converged: our definition is the paper's, or missing");
/// Whether ours under our definition differs.
pub const CONVERGED: Col<String> = Col::text(
    "converged",
    "differs (ours_converged holds it), same (our definition is the paper's) or missing",
);
/// Where the definitions differ, and how to read the row.
pub const NOTE: Col<String> = Col::text("note", "where the definitions differ");

/// Table I as the paper prints it: a line per `n`, each cell `published |
/// ours (z)`, ours under the paper's definition (the other rows and the
/// notes have the rest).
pub const TABLE_I: Printout = Printout {
    table: TABLE,
    title: "the paper (Phys. Rev. E 110, 014114), Table I: published | ours (z) (a_n at |u - u'| <= 0.04; shape: our fit up to 0.04, statistical and protocol errors combined; |u1f,max| to 6 digits, its error bound below 1e-6)",
    layout: Layout::Pivot {
        lines: TABLE_I_N,
        across: TABLE_I_COLUMN,
    },
    rows: Selection::Given(TABLE_I_N),
    columns: &[Printed::new(
        "n",
        Shown::Composite(
            "{} | {}{}",
            &[
                Shown::Significant(PUBLISHED.value),
                Shown::Concise(OURS),
                Shown::Appended(Z, 1),
            ],
        ),
    )],
    footnote: Footnote::None,
};

/// The paper's other numbers, each row with its note.
pub const OTHER_NUMBERS: Printout = Printout {
    table: TABLE,
    title: "the paper (Phys. Rev. E 110, 014114), its other numbers: published against ours under its definition (+- standard errors; published: +- as printed, else rounding); converged: ours under our definition where it differs",
    layout: Layout::Joined,
    rows: Selection::Missing(TABLE_I_N),
    columns: &[
        Printed::new("", Shown::Row),
        Printed::new("published", Shown::Estimate(PUBLISHED, "-")),
        Printed::new("ours", Shown::Estimate(OURS, "-")),
        Printed::new("ours/pub", Shown::Quotient(OURS.value, PUBLISHED.value, 4)),
        Printed::new("z", Shown::Fixed(Z, 2)),
        Printed::new("converged", Shown::EstimateElse(OURS_CONVERGED, CONVERGED)),
        Printed::new("unit", Shown::Text(UNIT)),
        Printed::new(
            "quantity [source]",
            Shown::Composite("{} [{}]", &[Shown::Text(QUANTITY), Shown::Text(SOURCE)]),
        ),
    ],
    footnote: Footnote::PerRow(NOTE),
};

/// What the summary and the report print of the paper table, in order.
pub const HEADLINES: [&Printout; 2] = [&TABLE_I, &OTHER_NUMBERS];
