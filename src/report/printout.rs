//! The one printer of every table a stage declares a
//! [`Printout`](contract::printout::Printout) for: its title, its rows and
//! each printed column's cells, as the console and the HTML report show them.

use anyhow::Result;
use polars::prelude::DataFrame;

use super::layout::{Align, Cell, Columns, Sink};
use super::numbers::{Notation, fixed, natural_notation, or_why, significant, written};
use super::{count, estimate, number, pair_of, table_frames, text, variance};
use crate::contract::printout::{Footnote, Layout, Printed, Printout, Selection, Shown};
use crate::contract::{Col, Pair};
use crate::pipeline::executor::InstanceReport;
use crate::pipeline::store::Store;
use crate::stats::ChiSquare;
use crate::thresholds::DOMINATED_SHARE;

/// `printout`'s table of every instance in `reports` that has it (nothing
/// when none has a row to print); variances below `kick_floor^2` (`v_th`,
/// the study's `kernel.kick_floor`) are the engine's rounding.
pub(super) fn print(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
    printout: &Printout,
    kick_floor: f64,
) -> Result<()> {
    let frames = table_frames(store, reports, &printout.table)?;
    let title = match printout.rows {
        Selection::Largest { count, .. } => printout.title.replace("{count}", &count.to_string()),
        _ => printout.title.to_string(),
    };
    let tables: Vec<(String, Columns)> = match printout.layout {
        Layout::Joined => vec![(title, columns(&frames, printout, kick_floor)?)],
        Layout::PerInstance => frames
            .chunks(1)
            .map(|one| {
                let title = title.replace("{instance}", &one[0].0);
                Ok((title, columns(one, printout, kick_floor)?))
            })
            .collect::<Result<_>>()?,
        Layout::Pivot { lines, across } => {
            vec![(title, grid(&frames, printout, (lines, across), kick_floor)?)]
        }
    };
    let shown: Vec<_> = tables
        .iter()
        .filter(|(_, table)| !table.is_empty())
        .collect();
    for (title, table) in &shown {
        out.title(title);
        out.table(table);
    }
    if !shown.is_empty() {
        footnote(out, &frames, printout)?;
    }
    Ok(())
}

/// What `printout` prints after its table of `frames`.
fn footnote(out: &mut dyn Sink, frames: &[(String, DataFrame)], printout: &Printout) -> Result<()> {
    match printout.footnote {
        Footnote::None => {}
        Footnote::Line(line) => out.line(line),
        Footnote::PerRow(col) => {
            for (_, frame) in frames {
                for row in selected(frame, printout.rows)? {
                    let number = format!("{}.", row + 1);
                    out.line(&format!("{number:<4} {}", text(frame, row, col)?));
                }
            }
        }
    }
    Ok(())
}

/// The [`Layout::Pivot`] grid of `frames`' selected rows: a line per
/// distinct value of `lines`, a column per distinct text of `across`, each
/// cell the first printed column's.
fn grid(
    frames: &[(String, DataFrame)],
    printout: &Printout,
    (lines, across): (Col<f64>, Col<String>),
    kick_floor: f64,
) -> Result<Columns> {
    let Some(Printed { head, shown }) = printout.columns.first() else {
        return Ok(Columns::new(&[]));
    };
    let mut cells: Vec<(f64, String, Cell)> = Vec::new();
    for (instance, frame) in frames {
        for row in selected(frame, printout.rows)? {
            cells.push((
                number(frame, row, lines)?,
                text(frame, row, across)?,
                cell(frame, row, instance, shown, kick_floor)?,
            ));
        }
    }
    let mut labels: Vec<f64> = cells.iter().map(|(line, ..)| *line).collect();
    labels.sort_by(f64::total_cmp);
    labels.dedup();
    let mut heads: Vec<&str> = Vec::new();
    for (_, column, _) in &cells {
        if !heads.contains(&column.as_str()) {
            heads.push(column);
        }
    }
    let columns: Vec<(&str, Align)> = std::iter::once((*head, Align::Right))
        .chain(heads.iter().map(|column| (*column, Align::Left)))
        .collect();
    let mut table = Columns::new(&columns);
    for label in labels {
        let at = |column: &&str| {
            cells
                .iter()
                .find(|(line, across, _)| *line == label && across == column)
                .map_or_else(|| Cell::text("-"), |(.., cell)| cell.clone())
        };
        let line = std::iter::once(Cell::text(significant(label)));
        table.push(line.chain(heads.iter().map(at)).collect());
    }
    Ok(table)
}

/// The table of `frames`' selected rows.
fn columns(
    frames: &[(String, DataFrame)],
    printout: &Printout,
    kick_floor: f64,
) -> Result<Columns> {
    let heads: Vec<(&str, Align)> = printout
        .columns
        .iter()
        .map(|printed| (printed.head, alignment(&printed.shown)))
        .collect();
    let mut table = Columns::new(&heads);
    for (instance, frame) in frames {
        for row in selected(frame, printout.rows)? {
            let shown = |printed: &Printed| cell(frame, row, instance, &printed.shown, kick_floor);
            table.push(printout.columns.iter().map(shown).collect::<Result<_>>()?);
        }
    }
    Ok(table)
}

/// Text, estimates and verdicts line up left, numbers right; a composite as
/// its first part.
fn alignment(shown: &Shown) -> Align {
    match shown {
        Shown::Instance
        | Shown::Text(_)
        | Shown::Estimate(..)
        | Shown::EstimateElse(..)
        | Shown::Concise(_)
        | Shown::Variance(_)
        | Shown::Evidence(_) => Align::Left,
        Shown::Composite(_, parts) => parts.first().map_or(Align::Left, alignment),
        Shown::Unless(_, _, shown) => alignment(shown),
        _ => Align::Right,
    }
}

/// The rows of `frame` that `selection` prints, in the order printed.
fn selected(frame: &DataFrame, selection: Selection) -> Result<Vec<usize>> {
    let rows = 0..frame.height();
    Ok(match selection {
        Selection::All => rows.collect(),
        Selection::NonZero(col) => {
            let mut kept = Vec::new();
            for row in rows {
                if number(frame, row, col)? != 0.0 {
                    kept.push(row);
                }
            }
            kept
        }
        Selection::Largest { col, count } => {
            let mut ranked: Vec<(usize, f64)> = rows
                .map(|row| Ok((row, number(frame, row, col)?)))
                .collect::<Result<_>>()?;
            ranked.retain(|(_, x)| x.is_finite());
            ranked.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            ranked.into_iter().take(count).map(|(row, _)| row).collect()
        }
        Selection::Given(col) | Selection::Missing(col) => {
            let given = matches!(selection, Selection::Given(_));
            let mut kept = Vec::new();
            for row in rows {
                if number(frame, row, col)?.is_finite() == given {
                    kept.push(row);
                }
            }
            kept
        }
    })
}

/// Cell `shown` of `row` of `instance`'s `frame`.
fn cell(
    frame: &DataFrame,
    row: usize,
    instance: &str,
    shown: &Shown,
    kick_floor: f64,
) -> Result<Cell> {
    let bare = |x: f64, format: &dyn Fn(f64) -> String| Cell::text(or_why(x, format, "-"));
    Ok(match *shown {
        Shown::Instance => Cell::text(instance),
        Shown::Row => Cell::text((row + 1).to_string()),
        Shown::Text(col) => Cell::text(text(frame, row, col)?),
        Shown::Count(col) => Cell::text(count(frame, row, col)?.to_string()),
        Shown::Estimate(pair, undefined) => estimate(frame, row, pair, undefined)?,
        Shown::Variance(pair) => variance(frame, row, pair, kick_floor)?,
        Shown::Fixed(col, decimals) => bare(number(frame, row, col)?, &|x| fixed(x, decimals)),
        Shown::Appended(col, decimals) => Cell::text(or_why(
            number(frame, row, col)?,
            |x| format!(" ({x:+.decimals$})"),
            "",
        )),
        Shown::Significant(col) => bare(number(frame, row, col)?, &significant),
        Shown::Percent(col, decimals) => bare(number(frame, row, col)?, &|x| {
            format!("{}%", fixed(100.0 * x, decimals))
        }),
        Shown::Scientific(col, decimals) => {
            bare(number(frame, row, col)?, &|x| format!("{x:.decimals$e}"))
        }
        Shown::Quotient(numerator, denominator, decimals) => bare(
            number(frame, row, numerator)? / number(frame, row, denominator)?,
            &|x| fixed(x, decimals),
        ),
        Shown::PerDof(chi2, dof) => bare(
            number(frame, row, chi2)? / f64::from(count(frame, row, dof)?),
            &|x| fixed(x, 2),
        ),
        Shown::PValue(chi2, dof) => Cell::text(chi_square(frame, row, chi2, dof)?.p_digits()),
        Shown::Test(chi2, dof) => {
            let test = chi_square(frame, row, chi2, dof)?;
            bare(test.chi2, &|_| test.p_text())
        }
        Shown::Evidence(share) => Cell::text(evidence_verdict(number(frame, row, share)?)),
        Shown::Relative(_)
        | Shown::Unless(..)
        | Shown::Composite(..)
        | Shown::EstimateElse(..)
        | Shown::Concise(_) => compound(frame, row, instance, shown, kick_floor)?,
    })
}

/// Cell `shown` of `row` of `instance`'s `frame`, for the kinds built from
/// other cells or from a value and its error together.
fn compound(
    frame: &DataFrame,
    row: usize,
    instance: &str,
    shown: &Shown,
    kick_floor: f64,
) -> Result<Cell> {
    Ok(match *shown {
        Shown::EstimateElse(pair, why) => estimate(frame, row, pair, &text(frame, row, why)?)?,
        Shown::Concise(pair) => Cell::text(concise(frame, row, pair)?),
        Shown::Relative(pair) => {
            let estimate = pair_of(frame, row, pair)?;
            let relative = if estimate.mean == 0.0 {
                f64::NAN
            } else {
                estimate.stderr / estimate.mean.abs()
            };
            Cell::text(or_why(relative, |r| format!("{:.3}%", 100.0 * r), "-"))
        }
        Shown::Unless(pair, text, shown) => {
            let estimate = pair_of(frame, row, pair)?;
            if estimate.mean == 0.0 && estimate.stderr == 0.0 {
                Cell::text(text)
            } else {
                cell(frame, row, instance, shown, kick_floor)?
            }
        }
        Shown::Composite(template, parts) => {
            let mut pieces = template.split("{}");
            let mut composed = pieces.next().unwrap_or_default().to_string();
            for (part, piece) in parts.iter().zip(pieces) {
                composed += &cell(frame, row, instance, part, kick_floor)?.to_string();
                composed += piece;
            }
            Cell::text(composed)
        }
        _ => cell(frame, row, instance, shown, kick_floor)?,
    })
}

/// `pair` of `row` as `value(error)`, or the value alone to six
/// significant digits when its error is below a part in 1e6.
fn concise(frame: &DataFrame, row: usize, pair: Pair) -> Result<String> {
    let estimate = pair_of(frame, row, pair)?;
    let (value, error) = (estimate.mean, estimate.stderr);
    if error < 1e-6 * value.abs() {
        return Ok(significant(value));
    }
    let notation = Notation {
        concise: true,
        ..natural_notation(value, error)
    };
    Ok(written(value, error, "-", notation))
}

/// The chi-square in `row`'s columns `chi2` and `dof`.
fn chi_square(frame: &DataFrame, row: usize, chi2: Col<f64>, dof: Col<u32>) -> Result<ChiSquare> {
    Ok(ChiSquare {
        chi2: number(frame, row, chi2)?,
        dof: count(frame, row, dof)? as usize,
    })
}

/// Whether a joint test whose spread one randomization carries `share` of
/// is evidence: empty when it is, else why not.
fn evidence_verdict(share: f64) -> String {
    if share <= DOMINATED_SHARE {
        String::new()
    } else if share.is_nan() {
        "no evidence: no kicks or no pairs".to_string()
    } else {
        format!(
            "no evidence: one randomization carries {:.0}% of the spread",
            100.0 * share
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use polars::prelude::{IntoColumn, NamedFrom, Series};

    const PULL: Col<f64> = Col::f64("pull", "1", "a pull");
    const LABEL: Col<String> = Col::text("label", "which");
    const COUNTED: Col<u32> = Col::u32("counted", "1", "counted");
    const PAIRS: Col<u32> = Col::u32("pairs", "1", "pairs");
    const ZERO: Col<f64> = Col::f64("zero", "1", "nothing measured");
    /// The pulls as their own errors.
    const OWN: Pair = Pair {
        value: PULL,
        stderr: PULL,
    };
    /// `0 ± 0` in every row.
    const NOTHING: Pair = Pair {
        value: ZERO,
        stderr: ZERO,
    };
    const FIT: Shown = Shown::Estimate(OWN, "no fit");
    /// The pulls with no error at all.
    const EXACT: Pair = Pair {
        value: PULL,
        stderr: ZERO,
    };

    /// Four rows: pulls 0.5, -3, NaN, 0 labelled a..d, 2 of 4 counted.
    fn frame() -> DataFrame {
        DataFrame::new(
            4,
            vec![
                Series::new(PULL.name.into(), vec![0.5, -3.0, f64::NAN, 0.0]).into_column(),
                Series::new(LABEL.name.into(), vec!["a", "b", "c", "d"]).into_column(),
                Series::new(COUNTED.name.into(), vec![2u32; 4]).into_column(),
                Series::new(PAIRS.name.into(), vec![4u32; 4]).into_column(),
                Series::new(ZERO.name.into(), vec![0.0; 4]).into_column(),
            ],
        )
        .expect("a frame")
    }

    /// The largest rows come largest |value| first, without non-numbers;
    /// rows whose value is zero are left out on request.
    #[test]
    fn selections_rank_and_filter_rows() {
        let frame = frame();
        let largest = Selection::Largest {
            col: PULL,
            count: 2,
        };
        assert_eq!(selected(&frame, largest).unwrap(), vec![1, 0]);
        assert_eq!(
            selected(&frame, Selection::NonZero(PULL)).unwrap(),
            vec![0, 1, 2]
        );
        assert_eq!(selected(&frame, Selection::All).unwrap().len(), 4);
    }

    /// A composite fills its template's places in order; shares print as
    /// percentages, non-numbers as `-`.
    #[test]
    fn cells_show_what_their_column_declares() {
        let frame = frame();
        let shown = |row: usize, shown: Shown| cell(&frame, row, "ipp-6", &shown, 1e-9).unwrap();
        let counted = Shown::Composite(
            "{} of {} ({})",
            &[
                Shown::Count(COUNTED),
                Shown::Count(PAIRS),
                Shown::Text(LABEL),
            ],
        );
        assert_eq!(shown(1, counted).to_string(), "2 of 4 (b)");
        assert_eq!(shown(0, Shown::Percent(PULL, 1)).to_string(), "50.0%");
        assert_eq!(shown(2, Shown::Fixed(PULL, 2)).to_string(), "-");
        assert_eq!(shown(1, Shown::Instance).to_string(), "ipp-6");
        assert_eq!(shown(0, Shown::Scientific(PULL, 1)).to_string(), "5.0e-1");
        // A relative error; `0 ± 0` says why there is no estimate.
        assert_eq!(shown(0, Shown::Relative(OWN)).to_string(), "100.000%");
        assert_eq!(shown(3, Shown::Relative(OWN)).to_string(), "-");
        let unless = |row, pair| shown(row, Shown::Unless(pair, "no kicks", &FIT)).to_string();
        assert_eq!(unless(0, NOTHING), "no kicks");
        assert_eq!(unless(2, OWN), "no fit");
        // A z-score appended, nothing for a non-number; the row's number
        // from 1; a concise estimate, or the value alone within 1e-6.
        assert_eq!(shown(1, Shown::Appended(PULL, 1)).to_string(), " (-3.0)");
        assert_eq!(shown(2, Shown::Appended(PULL, 1)).to_string(), "");
        assert_eq!(shown(2, Shown::Row).to_string(), "3");
        assert_eq!(shown(0, Shown::Concise(OWN)).to_string(), "0.50(50)");
        assert_eq!(shown(0, Shown::Concise(EXACT)).to_string(), "0.5");
        let why = |row| shown(row, Shown::EstimateElse(OWN, LABEL)).to_string();
        assert_eq!(why(2), "c");
    }

    /// A pivot's one printed column: its head labels the lines.
    const CELLS: [Printed; 1] = [Printed::new("n", Shown::Fixed(ZERO, 2))];

    /// A pivot lays the selected rows out as a grid: a line per value of
    /// one column (ascending), a column per text of another (in order of
    /// appearance), `-` where no row has the pair; rows whose line value is
    /// not a number are left to another printout.
    #[test]
    fn a_pivot_lays_rows_out_as_a_grid() {
        let frame = DataFrame::new(
            4,
            vec![
                Series::new(PULL.name.into(), vec![6.0, 2.0, 6.0, f64::NAN]).into_column(),
                Series::new(LABEL.name.into(), vec!["a_n", "a_n", "beta", "note"]).into_column(),
                Series::new(ZERO.name.into(), vec![0.25, 0.0, 1.5, 9.0]).into_column(),
            ],
        )
        .expect("a frame");
        let printout = Printout {
            table: crate::contract::TableSpec {
                stage: "paper",
                name: "paper",
                description: "a test",
            },
            title: "pivot",
            layout: Layout::Pivot {
                lines: PULL,
                across: LABEL,
            },
            rows: Selection::Given(PULL),
            columns: &CELLS,
            footnote: Footnote::None,
        };
        let frames = [("study".to_string(), frame)];
        let table = grid(&frames, &printout, (PULL, LABEL), 1e-9).unwrap();
        let heads: Vec<&str> = table.heads().iter().map(|(h, _)| h.as_str()).collect();
        assert_eq!(heads, ["n", "a_n", "beta"]);
        assert_eq!(
            table.shown_rows(),
            [["2", "0.00", "-"], ["6", "0.25", "1.50"]]
        );
        let rest = selected(&frames[0].1, Selection::Missing(PULL)).unwrap();
        assert_eq!(rest, [3]);
    }
}
