//! What the console (`ternary run --details`) and the HTML report print of a
//! table, declared beside the table: its title, how its instances are laid
//! out, which rows, and one printed column per cell, each read from the
//! table's own declared columns. The report has one printer for them all
//! (`report::printout`), so a new stage writes no printer.
//!
//! Nothing here is reached from a stage's code: a change to what is printed
//! re-keys no artifact.

use super::{Col, Pair, TableSpec};

/// A table as printed.
pub struct Printout {
    /// The table printed (every instance of its stage that has it).
    pub table: TableSpec,
    /// The title; in [`Layout::PerInstance`], `{instance}` in it is replaced
    /// by the instance.
    pub title: &'static str,
    /// One table for all instances, or one per instance.
    pub layout: Layout,
    /// Which rows of each instance's table are printed.
    pub rows: Selection,
    /// The printed columns, left to right.
    pub columns: &'static [Printed],
    /// A line printed after the table (what a column's marker means).
    pub footnote: Option<&'static str>,
}

/// How a table's instances are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// One table under one title, the instances' rows one after another.
    Joined,
    /// One titled table per instance.
    PerInstance,
}

/// Which rows of an instance's table are printed.
#[derive(Clone, Copy, Debug)]
pub enum Selection {
    /// Every row, in file order.
    All,
    /// The rows whose `col` is not zero (a zero says there is nothing to
    /// show, e.g. no bound pairs without a well).
    NonZero(Col<f64>),
    /// The `count` rows of largest `|col|`, largest first (non-numbers left
    /// out).
    Largest {
        /// The column ranked by its magnitude.
        col: Col<f64>,
        /// How many rows.
        count: usize,
    },
}

/// One printed column: its head and what each cell shows.
#[derive(Clone, Copy, Debug)]
pub struct Printed {
    /// The column head.
    pub head: &'static str,
    /// What each cell shows.
    pub shown: Shown,
}

/// What a printed cell shows of its row. Numbers that are not numbers
/// (nulls) print as `-` unless an entry says otherwise.
#[derive(Clone, Copy, Debug)]
pub enum Shown {
    /// The instance the row belongs to.
    Instance,
    /// A label.
    Text(Col<String>),
    /// A count.
    Count(Col<u32>),
    /// `value ± error` to the digits the error justifies, or the text given
    /// when the value is not a number.
    Estimate(Pair, &'static str),
    /// A variance of velocities `[v_th^2]`: below the square of the study's
    /// kick floor it is the engine's rounding and says so.
    Variance(Pair),
    /// A number to fixed decimals.
    Fixed(Col<f64>, usize),
    /// A number to six significant digits.
    Significant(Col<f64>),
    /// A share as a percentage to the given decimals (`12.5%`).
    Percent(Col<f64>, usize),
    /// A number in scientific notation to the given decimals.
    Scientific(Col<f64>, usize),
    /// A ratio of two numbers to fixed decimals.
    Quotient(Col<f64>, Col<f64>, usize),
    /// A chi-square over its degrees of freedom, to two decimals.
    PerDof(Col<f64>, Col<u32>),
    /// The p-value of a chi-square with its degrees of freedom.
    PValue(Col<f64>, Col<u32>),
    /// The same, or `no test` with fewer degrees of freedom than a test needs.
    Test(Col<f64>, Col<u32>),
    /// Whether a joint test is evidence, given the share of its spread one
    /// randomization carries: empty when it is, else why not.
    Evidence(Col<f64>),
    /// Several cells' texts in one: each `{}` of the template, in order,
    /// takes the next part's text.
    Composite(&'static str, &'static [Shown]),
    /// A standard error relative to its value, as a percentage to three
    /// decimals (`-` for a zero value).
    Relative(Pair),
    /// The text given where the pair is exactly `0 ± 0` (nothing to
    /// measure: no kicks, no well), else the cell shown.
    Unless(Pair, &'static str, &'static Shown),
}

impl Printed {
    /// The column `head` showing `shown`.
    pub const fn new(head: &'static str, shown: Shown) -> Printed {
        Printed { head, shown }
    }
}
