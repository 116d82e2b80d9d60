//! What the command line prints: the run summary, the DAG, verification and
//! garbage-collection reports, and artifact listings. Reads artifacts with
//! polars, as any user would, by the columns the stages declare
//! (`contract`). Numbers are printed to the digits their errors justify
//! ([`with_error`]); a number that does not exist says why.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs::File;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use polars::prelude::{DataFrame, ParquetReader, SerReader};

use crate::contract::{self, Col, Pair, TableSpec};
use crate::pipeline::executor::{self, Audit, InstanceReport, Verbosity};
use crate::pipeline::shards;
use crate::pipeline::store::{Depth, Store, is_live_staging, listing_problem};
use crate::pipeline::table::{is_table_file, read_parquet};
use crate::pipeline::{Cost, InstanceId, Stage};

/// Significant digits of a value printed without an error to round it to.
const BARE_DIGITS: i32 = 6;

/// Significant digits of a value above which its error is written in the
/// concise form `1.23456789(12)` rather than as `± 0.00000012`.
const CONCISE_DIGITS: i32 = 8;

/// `value ± error` to the digits the error justifies: the error with two
/// significant digits, the value to the same decimal place; in fixed
/// notation for magnitudes from `1e-4` to `1e6`, otherwise as
/// `(m ± e)e<exponent>` with one shared exponent. A value known to more than
/// [`CONCISE_DIGITS`] digits is written `m(ee)`, the error in units of the
/// last digit. A value that is not a number (NaN, infinite) prints
/// `undefined`, which says why; a zero error prints as `± 0` after six
/// significant digits, a missing one as `(no error estimate)`.
pub fn with_error(value: f64, error: f64, undefined: &str) -> String {
    written(value, error, undefined, CONCISE_DIGITS)
}

/// `value(error)` as [`with_error`] writes values known to many digits,
/// whatever their digits: the short form of a table cell.
fn concise(value: f64, error: f64, undefined: &str) -> String {
    written(value, error, undefined, 0)
}

/// [`with_error`], in the form `m(ee)` from `concise_digits` digits on.
fn written(value: f64, error: f64, undefined: &str, concise_digits: i32) -> String {
    if !value.is_finite() {
        return undefined.to_string();
    }
    if !error.is_finite() {
        return format!("{} (no error estimate)", significant(value));
    }
    if error == 0.0 {
        return format!("{} ± 0", significant(value));
    }
    let error = error.abs();
    // Decimal exponent of the error's second significant digit, after
    // rounding it to two digits (9.96 rounds to 10: one place up).
    let mut last = libm::log10(error).floor() as i32 - 1;
    if (error / 10f64.powi(last)).round() >= 100.0 {
        last += 1;
    }
    let digits = (error / 10f64.powi(last)).round();
    let rounded = digits * 10f64.powi(last);
    let magnitude = libm::log10(value.abs().max(rounded)).floor() as i32;
    let concise = magnitude - last + 1 > concise_digits;
    if (-4..=5).contains(&magnitude) {
        // Errors of 100 and more round the value to tens, hundreds, ...
        let value = if last > 0 {
            (value / 10f64.powi(last)).round() * 10f64.powi(last)
        } else {
            value
        };
        let decimals = (-last).max(0) as usize;
        if concise {
            format!("{}({digits})", fixed(value, decimals))
        } else {
            format!("{} ± {}", fixed(value, decimals), fixed(rounded, decimals))
        }
    } else {
        let scale = 10f64.powi(magnitude);
        let decimals = (magnitude - last) as usize;
        if concise {
            format!("{}({digits})e{magnitude}", fixed(value / scale, decimals))
        } else {
            format!(
                "({} ± {})e{magnitude}",
                fixed(value / scale, decimals),
                fixed(rounded / scale, decimals)
            )
        }
    }
}

/// `x` with `decimals` decimals; a value that rounds to zero has no sign.
fn fixed(x: f64, decimals: usize) -> String {
    let text = format!("{x:.decimals$}");
    match text.strip_prefix('-') {
        Some(unsigned) if unsigned.chars().all(|c| c == '0' || c == '.') => unsigned.to_string(),
        _ => text,
    }
}

/// `x` to [`BARE_DIGITS`] significant digits without trailing zeros, in
/// fixed notation for magnitudes from `1e-4` to `1e6`.
fn significant(x: f64) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    let magnitude = libm::log10(x.abs()).floor() as i32;
    let trim = |digits: &str| -> String {
        if digits.contains('.') {
            digits
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        } else {
            digits.to_string()
        }
    };
    if (-4..=5).contains(&magnitude) {
        let decimals = (BARE_DIGITS - 1 - magnitude).max(0) as usize;
        trim(&fixed(x, decimals))
    } else {
        let text = format!("{x:.*e}", (BARE_DIGITS - 1) as usize);
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        format!("{}e{exponent}", trim(mantissa))
    }
}

/// `x` as `format` shows it, or `undefined` when it is not a number.
fn or_why(x: f64, format: impl Fn(f64) -> String, undefined: &str) -> String {
    if x.is_finite() {
        format(x)
    } else {
        undefined.to_string()
    }
}

/// Cell `col` of `row` as a number (NaN when null).
fn number(frame: &DataFrame, row: usize, col: Col<f64>) -> Result<f64> {
    Ok(frame.column(col.name)?.f64()?.get(row).unwrap_or(f64::NAN))
}

/// Cells `pair` of `row` as `value ± error` ([`with_error`]).
fn estimate(frame: &DataFrame, row: usize, pair: Pair, undefined: &str) -> Result<String> {
    Ok(with_error(
        number(frame, row, pair.value)?,
        number(frame, row, pair.stderr)?,
        undefined,
    ))
}

/// Cell `col` of `row` as a count (0 when null).
fn count(frame: &DataFrame, row: usize, col: Col<u32>) -> Result<u32> {
    Ok(frame.column(col.name)?.u32()?.get(row).unwrap_or(0))
}

/// Cell `col` of `row` as text (empty when null).
fn text(frame: &DataFrame, row: usize, col: Col<String>) -> Result<String> {
    Ok(frame
        .column(col.name)?
        .str()?
        .get(row)
        .unwrap_or_default()
        .to_string())
}

/// The row whose label in `col` is `label`.
fn row_of(frame: &DataFrame, col: Col<String>, label: &str) -> Result<usize> {
    (0..frame.height())
        .find(|&row| text(frame, row, col).is_ok_and(|l| l == label))
        .with_context(|| format!("no {} `{label}`", col.name))
}

fn read_frame(path: &Path) -> Result<DataFrame> {
    let file = File::open(path).with_context(|| format!("opening {}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .with_context(|| format!("reading {}", path.display()))
}

/// The study table (when computed), the convergence study and the scan peaks
/// of a run, readable.
pub fn summary(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = study_table(store, reports)?;
    out.push_str(&gases_table(store, reports)?);
    out.push_str(&convergence_table(store, reports)?);
    out.push_str(&evolve_table(store, reports)?);
    out.push_str(&md_table(store, reports)?);
    out.push_str(&compare_table(store, reports)?);
    out.push_str(&scan_table(store, reports)?);
    out.push_str(&balance_table(store, reports)?);
    out.push_str(&paper_table(store, reports)?);
    Ok(out)
}

/// The sweeps' joint detailed-balance tests.
fn balance_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use crate::kernel::equilibrium::DOMINATED_SHARE;
    use contract::sweep::balance_tests::*;
    let frames = table_frames(store, reports, &TABLE)?;
    let mut out = String::new();
    if frames.is_empty() {
        return Ok(out);
    }
    writeln!(
        out,
        "\ndetailed balance, joint over the pairs of each separation (sum of relative imbalances, correlations from the randomizations; pairs whose error one randomization carries left out)"
    )?;
    writeln!(
        out,
        "{:<10} {:>10} {:>13} {:<26} {:>7}",
        "potential", "b - a", "pairs counted", "joint imbalance", "z"
    )?;
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            let share = number(&frame, row, JOINT_LARGEST_SHARE)?;
            let z = number(&frame, row, JOINT_Z)?;
            let verdict = if share <= DOMINATED_SHARE {
                format!("{z:>7.2}")
            } else if share.is_nan() {
                "no evidence: no kicks or no pairs".to_string()
            } else {
                format!(
                    "{z:>7.2}  no evidence: one randomization carries {:.0}% of the spread",
                    100.0 * share
                )
            };
            writeln!(
                out,
                "{:<10} {:>10.3} {:>13} {:<26} {verdict}",
                instance,
                number(&frame, row, SEPARATION)?,
                format!(
                    "{}/{}",
                    count(&frame, row, COUNTED)?,
                    count(&frame, row, PAIRS)?
                ),
                estimate(&frame, row, JOINT_IMBALANCE, "-")?,
            )?;
        }
    }
    Ok(out)
}

/// The `paper` stage's output: published numbers against ours.
fn paper_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::paper::*;
    let mut out = String::new();
    let Some((_, frame)) = table_frames(store, reports, &TABLE)?.into_iter().next() else {
        return Ok(out);
    };
    writeln!(
        out,
        "\nthe paper (Phys. Rev. E 110, 014114): published against ours under its definition (+- standard errors; published: +- as printed, else rounding); converged: ours under our definition where it differs"
    )?;
    let table_i: Vec<usize> = (0..frame.height())
        .filter(|&row| number(&frame, row, TABLE_I_N).is_ok_and(f64::is_finite))
        .collect();
    out.push_str(&table_i_matrix(&frame, &table_i)?);
    let rest: Vec<usize> = (0..frame.height())
        .filter(|row| !table_i.contains(row))
        .collect();
    writeln!(
        out,
        "{:<4} {:<26} {:<28} {:>9} {:>7}  {:<28} {:<14} quantity [source]",
        "", "published", "ours", "ours/pub", "z", "converged", "unit"
    )?;
    for &row in &rest {
        let converged_undefined = text(&frame, row, CONVERGED)?;
        writeln!(
            out,
            "{:<4} {:<26} {:<28} {:>9} {:>7}  {:<28} {:<14} {} [{}]",
            row + 1,
            estimate(&frame, row, PUBLISHED, "-")?,
            estimate(&frame, row, OURS, "-")?,
            format!("{:.4}", 1.0 + number(&frame, row, RELATIVE_DIFFERENCE)?),
            or_why(number(&frame, row, Z)?, |z| format!("{z:.2}"), "-"),
            estimate(&frame, row, OURS_CONVERGED, &converged_undefined)?,
            text(&frame, row, UNIT)?,
            text(&frame, row, QUANTITY)?,
            text(&frame, row, SOURCE)?,
        )?;
    }
    for &row in &rest {
        writeln!(
            out,
            "{:<4} {}",
            format!("{}.", row + 1),
            text(&frame, row, NOTE)?
        )?;
    }
    Ok(out)
}

/// Table I as the paper prints it, rows `rows` of the `paper` table: one
/// line per `n`, each cell `published | ours z` (ours under the paper's
/// definition; the table's rows and notes have the rest).
fn table_i_matrix(frame: &DataFrame, rows: &[usize]) -> Result<String> {
    use contract::paper::*;
    let mut out = String::new();
    if rows.is_empty() {
        return Ok(out);
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
            concise(value, error, "-")
        };
        let z = or_why(number(frame, row, Z)?, |z| format!(" ({z:+.1})"), "");
        Ok(format!(
            "{} | {ours}{z}",
            significant(number(frame, row, PUBLISHED.value)?)
        ))
    };
    let mut cells = Vec::new();
    for &n in &exponents {
        cells.push(
            columns
                .iter()
                .map(|column| cell(n, column))
                .collect::<Result<Vec<_>>>()?,
        );
    }
    let widths: Vec<usize> = (0..columns.len())
        .map(|k| {
            cells
                .iter()
                .map(|line| line[k].len())
                .chain([columns[k].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    writeln!(
        out,
        "Table I, published | ours (z) (rows {}-{} of the table; a_n at |u - u'| <= 0.04; shape: our fit up to 0.04, statistical and protocol errors combined; |u1f,max| to 6 digits, its error bound below 1e-6)",
        rows[0] + 1,
        rows[rows.len() - 1] + 1
    )?;
    write!(out, "{:>4}", "n")?;
    for (column, width) in columns.iter().zip(&widths) {
        write!(out, "  {column:<width$}")?;
    }
    writeln!(out)?;
    for (n, line) in exponents.iter().zip(&cells) {
        write!(out, "{n:>4}")?;
        for (shown, width) in line.iter().zip(&widths) {
            write!(out, "  {shown:<width$}")?;
        }
        writeln!(out)?;
    }
    Ok(out)
}

/// The table `spec` of every intact artifact of its stage in a run.
fn table_frames(
    store: &Store,
    reports: &[InstanceReport],
    spec: &TableSpec,
) -> Result<Vec<(String, DataFrame)>> {
    reports
        .iter()
        .filter(|r| r.id.stage == spec.stage)
        .filter(|r| r.action.has_artifact())
        .filter_map(|r| r.key.as_ref().map(|key| (r, key)))
        .map(|(report, key)| {
            let frame = read_frame(
                &store
                    .artifact_dir(spec.stage, key)
                    .join(format!("{}.parquet", spec.name)),
            )?;
            Ok((report.id.instance.clone(), frame))
        })
        .collect()
}

/// The `table` stage's output: `a_n` with standard errors per potential.
fn study_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::table::*;
    let mut out = String::new();
    let Some((_, frame)) = table_frames(store, reports, &TABLE)?.into_iter().next() else {
        return Ok(out);
    };
    writeln!(
        out,
        "\nthermalization constants a_n = self variance rate at u' = 0, dilute limit [rho^2 l v_th]; kernel shape near u' (+- standard errors; shape: statistical and fit-protocol errors combined)"
    )?;
    writeln!(
        out,
        "{:<10} {:<26} {:>8} {:<26} {:<20} {:<22} {:>13}",
        POTENTIAL.name,
        "a_n (|u-u'| <= window/2)",
        "rel.err",
        "a_n untruncated",
        BETA.value.name,
        "sigma [v_th]",
        "failed"
    )?;
    for row in 0..frame.height() {
        let (a, a_err) = (
            number(&frame, row, A_N.value)?,
            number(&frame, row, A_N.stderr)?,
        );
        let relative = if a == 0.0 {
            "-".to_string()
        } else {
            format!("{:.3}%", 100.0 * a_err / a.abs())
        };
        // No shape to fit when nothing was kicked (the integrable n = 2).
        let no_shape = if a == 0.0 && a_err == 0.0 {
            "no kicks"
        } else {
            "no fit"
        };
        writeln!(
            out,
            "{:<10} {:<26} {:>8} {:<26} {:<20} {:<22} {:>13}",
            text(&frame, row, POTENTIAL)?,
            with_error(a, a_err, "-"),
            relative,
            estimate(&frame, row, A_N_UNTRUNCATED, "-")?,
            estimate(&frame, row, BETA, no_shape)?,
            estimate(&frame, row, SIGMA, no_shape)?,
            format!(
                "{}/{}",
                count(&frame, row, FAILED_EVENTS)?,
                count(&frame, row, EVENTS)?
            ),
        )?;
    }
    Ok(out)
}

/// The `gases` stage's output: rates in physical units.
fn gases_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::gases::*;
    let mut out = String::new();
    let Some((_, frame)) = table_frames(store, reports, &TABLE)?.into_iter().next() else {
        return Ok(out);
    };
    writeln!(
        out,
        "\nthermalization rates in physical units (Gamma = a_n rho^2 l v_th, +- standard error)"
    )?;
    writeln!(
        out,
        "{:<22} {:<8} {:>9} {:>11} {:<26} {:<26} {:<24}",
        GAS.name,
        POTENTIAL.name,
        "kT [eV]",
        "rho l",
        "Gamma [1/ns] (dilute)",
        "paper's rule at rho l *",
        "1/Gamma [ns]"
    )?;
    for row in 0..frame.height() {
        writeln!(
            out,
            "{:<22} {:<8} {:>9.3e} {:>11.3e} {:<26} {:<26} {:<24}",
            text(&frame, row, GAS)?,
            text(&frame, row, POTENTIAL)?,
            number(&frame, row, KT)?,
            number(&frame, row, RHO_L)?,
            estimate(&frame, row, GAMMA, "-")?,
            estimate(&frame, row, GAMMA_AT_DENSITY, "-")?,
            estimate(&frame, row, RELAXATION_TIME, "never: no kicks")?,
        )?;
    }
    writeln!(
        out,
        "* Gamma times the paper's launch rule's finite-density factor exp(-r |delay|) in a box of L = kernel.launch_length: an artifact of that algorithm (it depends on L), not the gas's rate at rho l; MD's finite-density change has the opposite sign (finite_size table)"
    )?;
    Ok(out)
}

/// The `convergence` stage's output: shifts of `a_n` against the defaults.
fn convergence_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::convergence::*;
    let mut out = String::new();
    for (instance, frame) in table_frames(store, reports, &TABLE)? {
        writeln!(
            out,
            "\nconvergence of a_n for {} (shift = a_n - default, paired over randomizations)",
            instance
        )?;
        writeln!(
            out,
            "{:<14} {:>10} {:<30} {:<28} {:>16}",
            PARAMETER.name, VALUE.name, A_N.value.name, SHIFT.value.name, "shift / a_n error"
        )?;
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<14} {:>10} {:<30} {:<28} {:>16}",
                text(&frame, row, PARAMETER)?,
                // The default row has no value: it is the configuration itself.
                or_why(number(&frame, row, VALUE)?, |v| format!("{v:.3e}"), "-"),
                estimate(&frame, row, A_N, "-")?,
                estimate(&frame, row, SHIFT, "-")?,
                or_why(
                    number(&frame, row, SHIFT_OVER_ERROR)?,
                    |z| format!("{z:.3}"),
                    "-"
                ),
            )?;
        }
    }
    Ok(out)
}

/// The `evolve` stage's summary: spread and approach to equilibrium of `h`.
fn evolve_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::evolve::evolution_summary::*;
    let mut out = String::new();
    for (instance, frame) in table_frames(store, reports, &TABLE)? {
        writeln!(
            out,
            "\nevolution of h from delta(u - u') for {instance}: full = linearized operator, tagged = special particle, fokker_planck (+- jackknife errors)"
        )?;
        writeln!(
            out,
            "{:<14} {:>10} {:>9} {:<28} {:<26} {:<26}",
            PROCESS.name,
            "t Gamma",
            "t [ns]",
            "<(u-u')^2>, |u-u'|<=X",
            "<(u-u')^2>",
            "L1 distance to equilibrium"
        )?;
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<14} {:>10.3e} {:>9} {:<28} {:<26} {:<26}",
                text(&frame, row, PROCESS)?,
                number(&frame, row, TIME_GAMMA)?,
                // Times given in 1/Gamma have no time in ns.
                or_why(number(&frame, row, TIME_NS)?, |t| format!("{t:.0}"), "-"),
                estimate(&frame, row, WINDOW_VARIANCE, "-")?,
                estimate(&frame, row, VARIANCE, "-")?,
                estimate(&frame, row, DISTANCE_TO_EQUILIBRIUM, "-")?,
            )?;
        }
    }
    Ok(out)
}

/// The `md` stage's summaries: moments of `h(u, t_f)` by both estimators.
fn md_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::md::summary::*;
    let mut out = String::new();
    let frames = table_frames(store, reports, &TABLE)?;
    if frames.is_empty() {
        return Ok(out);
    }
    writeln!(
        out,
        "\nring molecular dynamics: h(u, t_f) within the window (+- standard errors over runs)"
    )?;
    writeln!(
        out,
        "{:<22} {:<10} {:<24} {:<28}",
        contract::compare::RING.name,
        ESTIMATOR.name,
        "sum h du",
        "<(u-u')^2>_window [v_th^2]"
    )?;
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<22} {:<10} {:<24} {:<28}",
                instance,
                text(&frame, row, ESTIMATOR)?,
                estimate(&frame, row, NUMBER, "-")?,
                estimate(&frame, row, WINDOW_VARIANCE, "-")?,
            )?;
        }
    }
    out.push_str(&bound_pairs_table(store, reports)?);
    Ok(out)
}

/// The `compare` stage: goodness of fit of MD against Boltzmann and of the
/// scaling collapse, and the finite-size and density study.
fn compare_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::compare::{finite_size, goodness};
    use contract::estimator;
    let mut out = String::new();
    for (_, frame) in table_frames(store, reports, &goodness::TABLE)? {
        writeln!(
            out,
            "\nMD against Boltzmann and the scaling collapse: chi2 per degree of freedom with the variance MD would have if it followed the reference, its p-value, and (sample) with the runs' own errors"
        )?;
        writeln!(
            out,
            "{:<22} {:<22} {:<10} {:>8} {:>5} {:>9} {:>15}",
            goodness::RING.name,
            goodness::REFERENCE.name,
            goodness::ESTIMATOR.name,
            "chi2/dof",
            goodness::DOF.name,
            "p",
            "sample chi2/dof"
        )?;
        for row in 0..frame.height() {
            // No bin with a variance: nothing to compare.
            let reduced = |col| -> Result<String> {
                Ok(or_why(
                    number(&frame, row, col)?,
                    |c| format!("{c:.2}"),
                    "no bins",
                ))
            };
            writeln!(
                out,
                "{:<22} {:<22} {:<10} {:>8} {:>5} {:>9} {:>15}",
                text(&frame, row, goodness::RING)?,
                text(&frame, row, goodness::REFERENCE)?,
                text(&frame, row, goodness::ESTIMATOR)?,
                reduced(goodness::CHI2_PER_DOF)?,
                count(&frame, row, goodness::DOF)?,
                or_why(
                    number(&frame, row, goodness::P_VALUE)?,
                    |p| format!("{p:.2e}"),
                    "-"
                ),
                format!(
                    "{} ({})",
                    reduced(goodness::SAMPLE_CHI2_PER_DOF)?,
                    count(&frame, row, goodness::SAMPLE_DOF)?
                ),
            )?;
        }
    }
    for (_, frame) in table_frames(store, reports, &finite_size::TABLE)? {
        writeln!(
            out,
            "\nfinite size and density: window variance at t_f, MD / Boltzmann (+- standard errors); tagged: starts near u', thermal: every start"
        )?;
        writeln!(
            out,
            "{:<22} {:>5} {:>10} {:>16} {:<24} {:<24}",
            finite_size::RING.name,
            "N",
            "rho l",
            "rho^2 l v_th t_f",
            estimator::TAGGED,
            estimator::THERMAL
        )?;
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<22} {:>5} {:>10.3e} {:>16.4e} {:<24} {:<24}",
                text(&frame, row, finite_size::RING)?,
                count(&frame, row, finite_size::PARTICLES)?,
                number(&frame, row, finite_size::DENSITY)?,
                number(&frame, row, finite_size::SCALED_TIME)?,
                estimate(&frame, row, finite_size::RATIO, "0/0: no spread")?,
                estimate(&frame, row, finite_size::THERMAL_RATIO, "0/0: no spread")?,
            )?;
        }
    }
    Ok(out)
}

/// The `scan` stages' peaks: largest `|u1f|` per launch pair.
fn scan_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::scan::{LAUNCH, peak::*};
    let mut out = String::new();
    for (k, (instance, frame)) in table_frames(store, reports, &TABLE)?
        .into_iter()
        .enumerate()
    {
        if k == 0 {
            writeln!(
                out,
                "\nmono-energetic scans: largest |u1f| (error bound) and its arrival offset"
            )?;
            writeln!(
                out,
                "{:<10} {:<12} {:<34} {:<30} {:>6} {:>12}",
                contract::POTENTIAL.name,
                LAUNCH.name,
                "|u1f,max| [v_th]",
                "offset [l/v_th]",
                "failed",
                "max |dE/E|"
            )?;
        }
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<10} {:<12} {:<34} {:<30} {:>6} {:>12.1e}",
                instance,
                text(&frame, row, LAUNCH)?,
                estimate(&frame, row, U1_FINAL_MAX_ABS, "-")?,
                estimate(&frame, row, ARRIVAL_OFFSET_AT_MAX, "no peak")?,
                count(&frame, row, FAILED_SCENES)?,
                number(&frame, row, WORST_ENERGY_ERROR)?,
            )?;
        }
    }
    Ok(out)
}

/// Bound neighbour pairs of the rings with a well: sampled, after the
/// dynamics, and the dilute limit.
fn bound_pairs_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    use contract::md::pairs::*;
    let mut out = String::new();
    for (instance, frame) in table_frames(store, reports, &TABLE)? {
        let bound = |state: &str| -> Result<String> {
            estimate(&frame, row_of(&frame, STATE, state)?, BOUND_FRACTION, "-")
        };
        let dilute = number(
            &frame,
            row_of(&frame, STATE, DILUTE_LIMIT)?,
            BOUND_FRACTION.value,
        )?;
        if dilute > 0.0 {
            writeln!(
                out,
                "{instance}: bound neighbour pairs per gap {} initial, {} final, {} dilute limit rho K_b",
                bound(INITIAL)?,
                bound(FINAL)?,
                significant(dilute),
            )?;
        }
    }
    Ok(out)
}

/// The DAG as text: one line per instance with its inputs.
pub fn dag(stages: &[Box<dyn Stage>]) -> String {
    let mut out = String::new();
    for stage in stages {
        let inputs: Vec<String> = stage.inputs().iter().map(ToString::to_string).collect();
        let from = if inputs.is_empty() {
            "(source)".to_string()
        } else {
            format!("<- {}", inputs.join(", "))
        };
        let _ = writeln!(out, "{:<24} {from}", stage.id().to_string());
    }
    out
}

/// Checks every artifact down to its tables' content hashes (and, for stages
/// of the study, that it holds exactly the tables the stage writes): the
/// report and the number of damaged artifacts.
pub fn verify(store: &Store, stages: &[Box<dyn Stage>]) -> Result<(String, usize)> {
    let outputs: BTreeMap<InstanceId, Vec<String>> = stages
        .iter()
        .map(|stage| (stage.id(), executor::output_files(stage.as_ref())))
        .collect();
    let mut out = String::new();
    let mut damaged = 0;
    let artifacts = store.artifacts()?;
    for (stage, key) in &artifacts {
        let inspected = store
            .inspect(stage, key, None, Depth::Contents)
            .and_then(|manifest| {
                let id = InstanceId::new(stage, &manifest.instance);
                match outputs
                    .get(&id)
                    .and_then(|files| listing_problem(&manifest, files))
                {
                    Some(problem) => Err(vec![problem]),
                    None => Ok(manifest),
                }
            });
        match inspected {
            Ok(_) => writeln!(out, "ok       {stage}/{key}")?,
            Err(problems) => {
                damaged += 1;
                writeln!(out, "DAMAGED  {stage}/{key}: {}", problems.join("; "))?;
            }
        }
    }
    for path in store.foreign_entries()? {
        writeln!(
            out,
            "foreign  {} (not written by ternary: left alone)",
            path.display()
        )?;
    }
    let (live, debris): (Vec<PathBuf>, Vec<PathBuf>) =
        store.staging_debris()?.into_iter().partition(|path| {
            path.file_name()
                .is_some_and(|name| is_live_staging(&name.to_string_lossy()))
        });
    if !live.is_empty() {
        writeln!(
            out,
            "{} staging entries of runs in progress (not checked: not yet artifacts)",
            live.len()
        )?;
    }
    if !debris.is_empty() {
        writeln!(
            out,
            "{} staging entries from interrupted runs are ignored (the next run or gc removes them)",
            debris.len()
        )?;
    }
    writeln!(
        out,
        "verify: {} artifacts, {} intact, {} damaged",
        artifacts.len(),
        artifacts.len() - damaged,
        damaged
    )?;
    Ok((out, damaged))
}

/// The sum of `costs`.
pub fn total_cost<'a>(costs: impl IntoIterator<Item = &'a Cost>) -> Cost {
    costs.into_iter().fold(Cost::default(), |sum, cost| Cost {
        cpu_seconds: sum.cpu_seconds + cost.cpu_seconds,
        bytes: sum.bytes + cost.bytes,
        rows: sum.rows + cost.rows,
    })
}

/// The closing line of `status`: the estimated CPU time and store size of
/// the whole study and of the instances in `unfresh` (still to compute).
pub fn cost_estimate(costs: &[(InstanceId, Cost)], unfresh: &BTreeSet<InstanceId>) -> String {
    let whole = total_cost(costs.iter().map(|(_, cost)| cost));
    let pending = total_cost(
        costs
            .iter()
            .filter(|(id, _)| unfresh.contains(id))
            .map(|(_, cost)| cost),
    );
    format!(
        "estimate: {} CPU-hours and {} of store for the whole study; {} CPU-hours of it still to compute (an order of magnitude, from the default study's speed on a 2-core VM)\n",
        hours(whole.cpu_seconds),
        size(whole.bytes),
        hours(pending.cpu_seconds)
    )
}

/// CPU-seconds as hours, two significant digits.
pub fn hours(seconds: f64) -> String {
    two_digits(seconds / 3600.0)
}

/// Bytes in MB or GB, two significant digits.
pub fn size(bytes: f64) -> String {
    if bytes >= 1e9 {
        format!("{} GB", two_digits(bytes / 1e9))
    } else {
        format!("{} MB", two_digits(bytes / 1e6))
    }
}

/// `value` rounded to two significant digits, in exponent form beyond 1e6.
fn two_digits(value: f64) -> String {
    let text = format!("{value:.1e}");
    match text.parse::<f64>() {
        Ok(rounded) if rounded.abs() < 1e6 => rounded.to_string(),
        _ => text,
    }
}

/// `verify --recompute`: every current artifact of the stages in `only` (all
/// when empty) recomputed from its stored inputs and compared byte for byte
/// (one line per instance as it is checked); the summary, and the number of
/// instances that differ or could not be checked.
pub fn audit(store: &Store, stages: &[Box<dyn Stage>], only: &[String]) -> Result<(String, usize)> {
    let audits = executor::recompute(store, stages, only, Verbosity::Normal)?;
    let count = |wanted: fn(&Audit) -> bool| audits.iter().filter(|(_, a)| wanted(a)).count();
    let same = count(|a| matches!(a, Audit::Same { .. }));
    let differ = count(|a| matches!(a, Audit::Differs(_)));
    let unchecked = count(|a| matches!(a, Audit::NotFresh(_)));
    let mut out = String::new();
    writeln!(
        out,
        "verify --recompute: {} instances, {same} same bytes, {differ} same key with different bytes, {unchecked} not checked",
        audits.len()
    )?;
    Ok((out, differ + unchecked))
}

/// Removes artifacts that neither the current key nor the last computed key of
/// a current instance names (shards are kept while their current artifact
/// waits to be merged), and staging debris. Only names ternary gives are
/// removed; foreign entries are reported and kept.
pub fn gc(store: &Store, stages: &[Box<dyn Stage>]) -> Result<String> {
    let lock = store.lock()?;
    let mut keep: BTreeSet<(String, String)> = BTreeSet::new();
    for line in executor::status(store, stages, 1)? {
        if let Some(key) = line.key {
            keep.insert((line.id.stage.clone(), key));
        }
        if let Some(entry) = store.read_ref(&line.id.stage, &line.id.instance) {
            keep.insert((line.id.stage, entry.key));
        }
    }
    let mut removed = 0;
    let mut bytes = 0;
    let awaiting_merge = |stage: &str, key: &str| {
        let whole = store
            .inspect(stage, key, None, Depth::Sizes)
            .ok()
            .as_ref()
            .and_then(shards::whole_of);
        whole.is_some_and(|(stage, key)| {
            !store.artifact_dir(&stage, &key).is_dir() && keep.contains(&(stage, key))
        })
    };
    let mut held = Vec::new();
    for (stage, key) in store.artifacts()? {
        if !keep.contains(&(stage.clone(), key.clone())) && !awaiting_merge(&stage, &key) {
            if store.foreign_in_artifact(&stage, &key, &[]).is_empty() {
                bytes += store.remove_artifact(&lock, &stage, &key)?;
                removed += 1;
            } else {
                held.push(store.artifact_dir(&stage, &key));
            }
        }
    }
    let debris = store.clean_staging(&lock)?;
    let mut out =
        format!("gc: removed {removed} artifacts ({bytes} bytes) and {debris} staging entries\n");
    for dir in held {
        writeln!(
            out,
            "gc: kept {} (unreferenced, but it holds entries ternary did not write; remove them to let gc remove it)",
            dir.display()
        )?;
    }
    for path in store.foreign_entries()? {
        writeln!(out, "gc: kept {} (not written by ternary)", path.display())?;
    }
    Ok(out)
}

/// Sum of a numeric column in row order (nulls skipped), `None` for text.
fn column_sum(column: &arrow::array::ArrayRef) -> Option<f64> {
    let as_f64 = arrow::compute::cast(column, &arrow::datatypes::DataType::Float64).ok()?;
    if !column.data_type().is_numeric() {
        return None;
    }
    let values = as_f64
        .as_any()
        .downcast_ref::<arrow::array::Float64Array>()?;
    Some(values.iter().flatten().sum())
}

/// Metadata, schema with units, and the first rows of a Parquet file.
fn show_file(path: &Path, rows: usize) -> Result<String> {
    let mut out = String::new();
    let (batch, metadata) = read_parquet(path)?;
    writeln!(out, "== {} ({} rows)", path.display(), batch.num_rows())?;
    for (key, value) in metadata.iter().filter(|(k, _)| k.starts_with("ternary.")) {
        writeln!(out, "  {key}: {value}")?;
    }
    writeln!(out, "  columns (sum of the numbers, in row order):")?;
    for (field, column) in batch.schema().fields().iter().zip(batch.columns()) {
        let meta = field.metadata();
        let unit = meta.get("unit").map(String::as_str).unwrap_or("");
        let description = meta.get("description").map(String::as_str).unwrap_or("");
        let sum = column_sum(column).map_or(String::new(), |sum| format!("{sum:e}"));
        writeln!(
            out,
            "    {:<28} {:<8} {sum:<24} [{unit}] {description}",
            field.name(),
            field.data_type().to_string()
        )?;
    }
    writeln!(out, "{}", read_frame(path)?.head(Some(rows)))?;
    Ok(out)
}

/// An artifact (by key or unique key prefix, or its directory) or a Parquet
/// file, and the number of problems of an artifact looked up by key (checked
/// to its file hashes; a damaged one is shown under a warning).
pub fn show(store: Option<&Store>, target: &str, rows: usize) -> Result<(String, usize)> {
    let path = Path::new(target);
    if path.is_file() {
        return Ok((show_file(path, rows)?, 0));
    }
    let mut problems = Vec::new();
    let dir = if path.is_dir() {
        path.to_path_buf()
    } else {
        let Some(store) = store else {
            bail!(
                "`{target}` is neither a file nor a directory, and no store is open to look up keys"
            )
        };
        if target.len() < 6 {
            bail!("`{target}`: give at least 6 characters of a key, or a path");
        }
        let matches: Vec<(String, String)> = store
            .artifacts()?
            .into_iter()
            .filter(|(_, key)| key.starts_with(target))
            .collect();
        match matches.as_slice() {
            [(stage, key)] => {
                if let Err(found) = store.inspect(stage, key, None, Depth::Hashes) {
                    problems = found;
                }
                store.artifact_dir(stage, key)
            }
            [] => bail!(
                "no artifact key starts with `{target}` in {}",
                store.root().display()
            ),
            _ => bail!("`{target}` is ambiguous: {} artifacts match", matches.len()),
        }
    };
    let manifest_path = dir.join("manifest.json");
    let manifest = std::fs::read_to_string(&manifest_path)
        .with_context(|| format!("reading {}", manifest_path.display()))?;
    let mut out = String::new();
    if !problems.is_empty() {
        writeln!(
            out,
            "DAMAGED {}: {} (not to be trusted; the next run recomputes it)",
            dir.display(),
            problems.join("; ")
        )?;
    }
    writeln!(out, "{manifest}")?;
    let value: serde_json::Value = serde_json::from_str(&manifest)?;
    for file in value["files"].as_array().into_iter().flatten() {
        let name = file["name"].as_str().unwrap_or_default();
        if is_table_file(name) {
            out.push_str(&show_file(&dir.join(name), rows)?);
        } else {
            writeln!(
                out,
                "== {} ({} bytes)",
                dir.join(name).display(),
                file["bytes"]
            )?;
        }
    }
    Ok((out, problems.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two significant digits of the error, the value to the same place.
    #[test]
    fn values_are_rounded_to_the_error() {
        assert_eq!(
            with_error(3.1234e-4, 1.234e-6, "-"),
            "0.0003123 ± 0.0000012"
        );
        assert_eq!(with_error(1.23456, 0.0123, "-"), "1.235 ± 0.012");
        assert_eq!(with_error(12345.0, 234.0, "-"), "12350 ± 230");
    }

    /// A value known to more digits than fit a line gives its error in units
    /// of its last digit.
    #[test]
    fn precise_values_are_concise() {
        assert_eq!(
            with_error(-0.51370614225, 7.7e-10, "-"),
            "-0.51370614225(77)"
        );
        assert_eq!(
            with_error(3.0787446190007e7, 6.0e-2, "-"),
            "3.0787446190(60)e7"
        );
        assert_eq!(
            with_error(0.012345678, 1.2e-8, "-"),
            "0.012345678 ± 0.000000012"
        );
    }

    /// An error that rounds up to the next power of ten keeps two digits.
    #[test]
    fn an_error_rounding_up_keeps_two_digits() {
        assert_eq!(with_error(0.5, 0.00996, "-"), "0.500 ± 0.010");
    }

    /// Very small or large magnitudes share one exponent.
    #[test]
    fn small_and_large_magnitudes_share_an_exponent() {
        assert_eq!(with_error(2.5e-9, 1.2e-11, "-"), "(2.500 ± 0.012)e-9");
        assert_eq!(with_error(4.14864e6, 6.6e4, "-"), "(4.149 ± 0.066)e6");
        assert_eq!(with_error(-1.85e-17, 1.8e-15, "-"), "(0.0 ± 1.8)e-15");
    }

    /// A value that rounds to zero carries no sign.
    #[test]
    fn a_value_rounding_to_zero_has_no_sign() {
        assert_eq!(with_error(-1e-9, 1e-3, "-"), "0.0000 ± 0.0010");
    }

    /// Zero and missing errors, and values that are not numbers, say so.
    #[test]
    fn missing_numbers_say_why() {
        assert_eq!(with_error(0.0, 0.0, "-"), "0 ± 0");
        assert_eq!(with_error(1.1637580872059066, 0.0, "-"), "1.16376 ± 0");
        assert_eq!(with_error(2.0, f64::NAN, "-"), "2 (no error estimate)");
        assert_eq!(with_error(f64::NAN, f64::NAN, "no fit"), "no fit");
        assert_eq!(with_error(f64::INFINITY, f64::NAN, "never"), "never");
        assert_eq!(significant(4.14864123e7), "4.14864e7");
        assert_eq!(significant(0.0154299), "0.0154299");
    }
}
