//! The `pulls` stage: every cross-check of the study as a pull, and their
//! distribution against N(0, 1) (`calibration`).

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "pulls";

/// `pulls.parquet`: one row per cross-check.
pub mod checks {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "pulls",
        description: "every quantity the study computes two independent ways, or holds against a value that must be exact, with its pull (a - b) / combined error: N(0, 1) when both errors are right",
    };
    /// What is compared.
    pub const CHECK: Col<String> = Col::text("check", "what is compared, and against what");
    /// For which instance.
    pub const SUBJECT: Col<String> =
        Col::text("subject", "the potential (and detail) it is compared for");
    /// Unit of the two estimates.
    pub const UNIT: Col<String> = Col::text("unit", "unit of first and second");
    /// The first estimate.
    pub const FIRST: Pair = pair!(
        "first",
        UNIT_PER_ROW,
        "the first estimate",
        "its standard error"
    );
    /// The second estimate or the exact value.
    pub const SECOND: Pair = pair!(
        "second",
        UNIT_PER_ROW,
        "the second, independent estimate, or the exact value",
        "its standard error (0 for an exact value)"
    );
    /// The pull.
    pub const PULL: Col<f64> = Col::f64(
        "pull",
        "1",
        "(first - second) / sqrt(first_stderr^2 + second_stderr^2)",
    )
    .or_null("neither estimate has an error");

    /// What `ternary run --details` and the HTML report print of the table,
    /// after the summary's verdict (not among the stages' tables).
    pub const LARGEST: Printout = Printout {
        table: TABLE,
        title: "the {count} largest pulls (a: first estimate, b: second or exact; units per check)",
        layout: Layout::Joined,
        rows: Selection::Largest {
            col: PULL,
            count: 10,
        },
        columns: &[
            Printed::new("pull", Shown::Fixed(PULL, 2)),
            Printed::new("subject", Shown::Text(SUBJECT)),
            Printed::new("a", Shown::Estimate(FIRST, "-")),
            Printed::new("b", Shown::Estimate(SECOND, "-")),
            Printed::new("check", Shown::Text(CHECK)),
        ],
        footnote: Footnote::None,
    };
}

/// `pulls_summary.parquet`: one row.
pub mod summary {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "pulls_summary",
        description: "the pulls' distribution against N(0, 1): their number, mean, spread and largest, and the verdict",
    };
    /// Pulls with a value.
    pub const PULLS: Col<u32> = Col::u32("pulls", "1", "pulls with a value");
    /// Their mean.
    pub const MEAN: Pair = pair!(
        "mean",
        "1",
        "mean pull: 0 +- 1/sqrt(pulls) without bias",
        "spread / sqrt(pulls) (the pulls taken as independent)"
    )
    .or_null("fewer than two pulls");
    /// Their spread.
    pub const SPREAD: Col<f64> = Col::f64(
        "spread",
        "1",
        "sample standard deviation of the pulls: 1 when the errors are right, below when overstated, above when understated",
    )
    .or_null("fewer than two pulls");
    /// The largest.
    pub const WORST_CHECK: Col<String> = Col::text(
        "worst_check",
        "the check of the largest |pull| (empty: none)",
    );
    /// Its subject.
    pub const WORST_SUBJECT: Col<String> =
        Col::text("worst_subject", "the subject of the largest |pull|");
    /// Its value.
    pub const WORST_PULL: Col<f64> =
        Col::f64("worst_pull", "1", "the largest |pull|, signed").or_null("no pulls");
    /// The verdict.
    pub const VERDICT: Col<String> = Col::text(
        "verdict",
        "calibrated (at least 50 pulls, |mean| < 0.3, spread in [0.7, 1.3]), else what is wrong",
    );

    /// What `ternary run` and the HTML report print of the table, after
    /// the paper's numbers.
    pub const HEADLINE: Printout = Printout {
        table: TABLE,
        title: "cross-checks: pulls (a - b) / combined error of every quantity computed two independent ways or held against an exact value (recombination three ways, detailed balance); N(0, 1) when the errors are right (pulls.parquet lists each)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new("pulls", Shown::Count(PULLS)),
            Printed::new("mean", Shown::Estimate(MEAN, "-")),
            Printed::new("spread", Shown::Fixed(SPREAD, 2)),
            Printed::new("largest", Shown::Fixed(WORST_PULL, 2)),
            Printed::new(
                "where",
                Shown::Composite(
                    "{}: {}",
                    &[Shown::Text(WORST_SUBJECT), Shown::Text(WORST_CHECK)],
                ),
            ),
            Printed::new("verdict", Shown::Text(VERDICT)),
        ],
        footnote: Footnote::None,
    };
}
