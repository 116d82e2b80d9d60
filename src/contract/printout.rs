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
    /// What is printed after the table.
    pub footnote: Footnote,
}

/// What a printout prints after its table.
#[derive(Clone, Copy, Debug)]
pub enum Footnote {
    /// Nothing.
    None,
    /// One line (what a column's marker means).
    Line(&'static str),
    /// A line per printed row, `<row>. <text>`: the row's number in its
    /// table (as [`Shown::Row`] prints it) and its text in the column.
    PerRow(Col<String>),
}

/// How a table's instances are laid out.
#[derive(Clone, Copy, Debug)]
pub enum Layout {
    /// One table under one title, the instances' rows one after another.
    Joined,
    /// One titled table per instance.
    PerInstance,
    /// One table of the selected rows as a grid: a line per distinct value
    /// of `lines` (ascending, labelled by it to six significant digits under
    /// the first printed column's head), a column per distinct text of
    /// `across` (in the order they first appear, headed by it), each cell
    /// the first printed column's cell of the row with that line and
    /// column (`-` where there is none). Table I, `n` against its columns.
    Pivot {
        /// The column whose values label the lines.
        lines: Col<f64>,
        /// The column whose texts head the grid's columns.
        across: Col<String>,
    },
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
    /// The rows whose `col` is a number (not null or NaN).
    Given(Col<f64>),
    /// The rows whose `col` is not a number.
    Missing(Col<f64>),
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
    /// The row's number in its instance's table, counted from 1.
    Row,
    /// A label.
    Text(Col<String>),
    /// A count.
    Count(Col<u32>),
    /// `value ± error` to the digits the error justifies, or the text given
    /// when the value is not a number.
    Estimate(Pair, &'static str),
    /// The same, or the row's text in the column given when the value is
    /// not a number (why there is none).
    EstimateElse(Pair, Col<String>),
    /// `value(error)`, the error in units of the value's last digit; the
    /// value alone to six significant digits when its error is below a
    /// part in 1e6 (a bound that adds no digit a reader compares).
    Concise(Pair),
    /// A variance of velocities `[v_th^2]`: below the square of the study's
    /// kick floor it is the engine's rounding and says so.
    Variance(Pair),
    /// A number to fixed decimals.
    Fixed(Col<f64>, usize),
    /// A number with its sign to fixed decimals in parentheses after a
    /// space (` (+1.2)`), nothing when it is not a number: a z-score
    /// appended to another cell.
    Appended(Col<f64>, usize),
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
