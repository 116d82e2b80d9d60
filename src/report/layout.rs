//! Text tables sized to their content: every column as wide as its widest
//! cell (its heading included) and two spaces from the next, so no cell runs
//! into its neighbour, and every `value ± error` of a column in one notation.
//! (A few lines of our own rather than `comfy-table`, which polars builds:
//! its borderless preset still draws the borders as blanks and pads both
//! sides of a cell, and it knows nothing of a column's notation;
//! docs/crates.md.)

use std::fmt;

use super::numbers::{Notation, natural_notation, written};

/// How a column's cells line up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// Text and `value ± error`.
    Left,
    /// Counts and bare numbers.
    Right,
}

/// One cell of a [`Columns`] table.
#[derive(Clone, Debug)]
pub enum Cell {
    /// Shown as it is.
    Text(String),
    /// `value ± error`, in the notation its column shares; `undefined` when
    /// the value is not a number.
    Estimate {
        value: f64,
        error: f64,
        undefined: String,
    },
}

impl Cell {
    /// A text cell.
    pub fn text(text: impl Into<String>) -> Cell {
        Cell::Text(text.into())
    }

    /// A `value ± error` cell.
    pub fn estimate(value: f64, error: f64, undefined: &str) -> Cell {
        Cell::Estimate {
            value,
            error,
            undefined: undefined.to_string(),
        }
    }

    /// The notation of an estimate alone (`None` for text).
    fn notation(&self) -> Option<Notation> {
        match self {
            Cell::Text(_) => None,
            Cell::Estimate { value, error, .. } => Some(natural_notation(*value, *error)),
        }
    }

    /// The cell as written in a column whose estimates take `notation`.
    fn shown(&self, notation: Notation) -> String {
        match self {
            Cell::Text(text) => text.clone(),
            Cell::Estimate {
                value,
                error,
                undefined,
            } => written(*value, *error, undefined, notation),
        }
    }
}

/// A cell alone: an estimate in its own notation.
impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let notation = self.notation().unwrap_or_default();
        f.write_str(&self.shown(notation))
    }
}

/// A table of headed columns, written with [`Columns::render`].
pub struct Columns {
    heads: Vec<(String, Align)>,
    rows: Vec<Vec<Cell>>,
}

impl Columns {
    /// A table with these headings and alignments, no rows yet.
    pub fn new(heads: &[(&str, Align)]) -> Columns {
        Columns {
            heads: heads
                .iter()
                .map(|&(head, align)| (head.to_string(), align))
                .collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row: one cell per heading.
    pub fn push(&mut self, row: Vec<Cell>) {
        debug_assert_eq!(row.len(), self.heads.len(), "one cell per column");
        self.rows.push(row);
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The headings and alignments.
    pub fn heads(&self) -> &[(String, Align)] {
        &self.heads
    }

    /// Every row's cells as written, each estimate in its column's notation.
    pub fn shown_rows(&self) -> Vec<Vec<String>> {
        let notations: Vec<Notation> = (0..self.heads.len())
            .map(|k| {
                self.rows
                    .iter()
                    .filter_map(|row| row[k].notation())
                    .fold(Notation::default(), Notation::covering)
            })
            .collect();
        self.rows
            .iter()
            .map(|row| {
                row.iter()
                    .zip(&notations)
                    .map(|(cell, &notation)| cell.shown(notation))
                    .collect()
            })
            .collect()
    }

    /// The heading line and one line per row, each column as wide as its
    /// widest cell, two spaces apart, without trailing spaces.
    pub fn render(&self) -> String {
        let lines: Vec<Vec<String>> = std::iter::once(
            self.heads
                .iter()
                .map(|(head, _)| head.clone())
                .collect::<Vec<String>>(),
        )
        .chain(self.shown_rows())
        .collect();
        let widths: Vec<usize> = (0..self.heads.len())
            .map(|k| {
                lines
                    .iter()
                    .map(|line| line[k].chars().count())
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let mut out = String::new();
        for line in &lines {
            let cells: Vec<String> = line
                .iter()
                .zip(&widths)
                .zip(&self.heads)
                .map(|((cell, &width), (_, align))| match align {
                    Align::Left => format!("{cell:<width$}"),
                    Align::Right => format!("{cell:>width$}"),
                })
                .collect();
            out.push_str(cells.join("  ").trim_end());
            out.push('\n');
        }
        out
    }
}

/// Where the summaries go, block by block: plain text for the terminal
/// (`String`) or HTML for the study report (`html::Tables`).
pub trait Sink {
    /// The sentence that introduces the next table (or lines).
    fn title(&mut self, text: &str);
    /// A table.
    fn table(&mut self, table: &Columns);
    /// A line of text: a note under a table.
    fn line(&mut self, text: &str);
}

/// Text: a title after a blank line, tables as [`Columns::render`] writes them.
impl Sink for String {
    fn title(&mut self, text: &str) {
        self.push('\n');
        self.push_str(text);
        self.push('\n');
    }

    fn table(&mut self, table: &Columns) {
        self.push_str(&table.render());
    }

    fn line(&mut self, text: &str) {
        self.push_str(text);
        self.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns take the width of their widest cell, so a long instance name
    /// or a long estimate never pushes into the next column, and a column
    /// with one tiny value writes all its estimates with exponents.
    #[test]
    fn columns_fit_their_widest_cell_and_share_a_notation() {
        let mut table = Columns::new(&[
            ("instance", Align::Left),
            ("rate", Align::Left),
            ("n", Align::Right),
        ]);
        table.push(vec![
            Cell::text("collisions[ipp-6_balance_u-3]"),
            Cell::estimate(0.0004006195, 0.0000000080, "-"),
            Cell::text("12"),
        ]);
        table.push(vec![
            Cell::text("kernel[a]"),
            Cell::estimate(3.69e-6, 7.0e-7, "-"),
            Cell::text("3"),
        ]);
        assert_eq!(
            table.render(),
            "instance                       rate                       n\n\
             collisions[ipp-6_balance_u-3]  (4.006195 ± 0.000080)e-4  12\n\
             kernel[a]                      (3.69 ± 0.70)e-6           3\n"
        );
    }
}
