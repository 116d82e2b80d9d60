//! The run summary `ternary run` prints: `a_n` per potential (the `table`
//! stage), the paper's Table I against ours, where the figures are, and
//! with details every stage's table ([`super::tables`]).

use anyhow::Result;
use polars::prelude::DataFrame;

use super::layout::{Align, Cell, Columns, Sink};
use super::numbers::{Notation, fixed, natural_notation, or_why, significant, written};
use crate::contract;
use crate::contract::{near_integrable::fits, pulls};
use crate::pipeline::executor::InstanceReport;
use crate::pipeline::store::Store;

use super::printout::print;
use super::{estimate, number, table_frames, text};

/// What a run computed, readable: `a_n` and the kernel shape, the paper
/// table and where the figures are; with `details`, then every stage's
/// table (rates of gases, convergence, evolution, MD and its comparison,
/// scans, detailed balance), else a line saying how to get them. Velocity
/// changes up to `kick_floor` (`v_th`, the study's `kernel.kick_floor`)
/// are the engine's error floor.
pub fn summary(
    store: &Store,
    reports: &[InstanceReport],
    kick_floor: f64,
    details: bool,
) -> Result<String> {
    let mut out = String::new();
    print(
        &mut out,
        store,
        reports,
        &contract::table::PRINTOUT,
        kick_floor,
    )?;
    print(&mut out, store, reports, &fits::PRINTOUT, kick_floor)?;
    paper_table(&mut out, store, reports)?;
    print(
        &mut out,
        store,
        reports,
        &pulls::summary::PRINTOUT,
        kick_floor,
    )?;
    figures_line(&mut out, store, reports);
    if details {
        print(
            &mut out,
            store,
            reports,
            &pulls::checks::PRINTOUT,
            kick_floor,
        )?;
        stage_tables(&mut out, store, reports, kick_floor)?;
    } else {
        out.title(
            "per-stage tables (gases, convergence, evolution, spectra, MD, scans, detailed balance): `ternary run --details`",
        );
    }
    Ok(out)
}

/// Every stage's table beyond `a_n` and the paper's: rates of gases,
/// convergence, evolution, spectra, MD and its comparison, scans, detailed balance
/// (velocity changes up to `kick_floor`, `v_th`, are the engine's error floor).
pub(super) fn stage_tables(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
    kick_floor: f64,
) -> Result<()> {
    for printout in contract::DETAILS {
        print(out, store, reports, printout, kick_floor)?;
    }
    Ok(())
}

/// How many figures the run's store holds and where (nothing when none).
fn figures_line(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) {
    let stage = contract::figures::STAGE;
    let drawn = reports
        .iter()
        .filter(|report| report.id.stage == stage && report.action.has_artifact())
        .count();
    if drawn > 0 {
        out.title(&format!(
            "figures: {drawn}, one artifact each under {} (`ternary show {stage}` lists their files)",
            store.artifact_dir(stage, "").display()
        ));
    }
}

/// The `paper` stage's output: published numbers against ours.
pub(super) fn paper_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::paper::*;
    let Some((_, frame)) = table_frames(store, reports, &TABLE)?.into_iter().next() else {
        return Ok(());
    };
    out.title(
        "the paper (Phys. Rev. E 110, 014114): published against ours under its definition (+- standard errors; published: +- as printed, else rounding); converged: ours under our definition where it differs",
    );
    let table_i: Vec<usize> = (0..frame.height())
        .filter(|&row| number(&frame, row, TABLE_I_N).is_ok_and(f64::is_finite))
        .collect();
    table_i_matrix(out, &frame, &table_i)?;
    let rest: Vec<usize> = (0..frame.height())
        .filter(|row| !table_i.contains(row))
        .collect();
    if rest.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("", Align::Right),
        ("published", Align::Left),
        ("ours", Align::Left),
        ("ours/pub", Align::Right),
        ("z", Align::Right),
        ("converged", Align::Left),
        ("unit", Align::Left),
        ("quantity [source]", Align::Left),
    ]);
    for &row in &rest {
        let converged_undefined = text(&frame, row, CONVERGED)?;
        table.push(vec![
            Cell::text((row + 1).to_string()),
            estimate(&frame, row, PUBLISHED, "-")?,
            estimate(&frame, row, OURS, "-")?,
            Cell::text(or_why(
                1.0 + number(&frame, row, RELATIVE_DIFFERENCE)?,
                |ratio| fixed(ratio, 4),
                "-",
            )),
            Cell::text(or_why(number(&frame, row, Z)?, |z| fixed(z, 2), "-")),
            estimate(&frame, row, OURS_CONVERGED, &converged_undefined)?,
            Cell::text(text(&frame, row, UNIT)?),
            Cell::text(format!(
                "{} [{}]",
                text(&frame, row, QUANTITY)?,
                text(&frame, row, SOURCE)?
            )),
        ]);
    }
    out.table(&table);
    for &row in &rest {
        out.line(&format!(
            "{:<4} {}",
            format!("{}.", row + 1),
            text(&frame, row, NOTE)?
        ));
    }
    Ok(())
}

/// Table I as the paper prints it, rows `rows` of the `paper` table: one
/// line per `n`, each cell `published | ours z` (ours under the paper's
/// definition; the table's rows and notes have the rest).
fn table_i_matrix(out: &mut dyn Sink, frame: &DataFrame, rows: &[usize]) -> Result<()> {
    use contract::paper::*;
    if rows.is_empty() {
        return Ok(());
    }
    let mut columns: Vec<String> = Vec::new();
    let mut exponents: Vec<f64> = Vec::new();
    for &row in rows {
        let column = text(frame, row, TABLE_I_COLUMN)?;
        if !columns.contains(&column) {
            columns.push(column);
        }
        let n = number(frame, row, TABLE_I_N)?;
        if !exponents.contains(&n) {
            exponents.push(n);
        }
    }
    exponents.sort_by(f64::total_cmp);
    let cell = |n: f64, column: &String| -> Result<String> {
        let Some(&row) = rows.iter().find(|&&row| {
            number(frame, row, TABLE_I_N).is_ok_and(|m| m == n)
                && text(frame, row, TABLE_I_COLUMN).is_ok_and(|c| &c == column)
        }) else {
            return Ok("-".to_string());
        };
        let (value, error) = (
            number(frame, row, OURS.value)?,
            number(frame, row, OURS.stderr)?,
        );
        // Errors below a part in 1e6 (the scan's bounds) add no digit a
        // reader compares.
        let ours = if error < 1e-6 * value.abs() {
            significant(value)
        } else {
            let notation = natural_notation(value, error);
            written(
                value,
                error,
                "-",
                Notation {
                    concise: true,
                    ..notation
                },
            )
        };
        let z = or_why(number(frame, row, Z)?, |z| format!(" ({z:+.1})"), "");
        Ok(format!(
            "{} | {ours}{z}",
            significant(number(frame, row, PUBLISHED.value)?)
        ))
    };
    out.line(&format!(
        "Table I, published | ours (z) (rows {}-{} of the table; a_n at |u - u'| <= 0.04; shape: our fit up to 0.04, statistical and protocol errors combined; |u1f,max| to 6 digits, its error bound below 1e-6)",
        rows[0] + 1,
        rows[rows.len() - 1] + 1
    ));
    let n_head = format!("{:>4}", "n");
    let heads: Vec<(&str, Align)> = std::iter::once((n_head.as_str(), Align::Right))
        .chain(columns.iter().map(|column| (column.as_str(), Align::Left)))
        .collect();
    let mut table = Columns::new(&heads);
    for &n in &exponents {
        let mut line = vec![Cell::text(format!("{n:>4}"))];
        for column in &columns {
            line.push(Cell::text(cell(n, column)?));
        }
        table.push(line);
    }
    out.table(&table);
    Ok(())
}
