//! What the command line prints: the run summary, the DAG, verification and
//! garbage-collection reports, and artifact listings. Reads artifacts with
//! polars, as any user would, by the columns the stages declare
//! (`contract`). Numbers are printed to the digits their errors justify
//! ([`with_error`]); a number that does not exist says why.

mod dag;
pub mod html;
mod layout;
mod numbers;

pub use dag::{DagFormat, dag};
pub use numbers::with_error;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs::File;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use polars::prelude::{DataFrame, ParquetReader, SerReader};

use crate::contract::{self, Col, Pair, TableSpec};
use crate::pipeline::executor::{self, Audit, Freshness, InstanceReport, StatusLine, Verbosity};
use crate::pipeline::shards;
use crate::pipeline::store::{Depth, Store, is_live_staging, listing_problem};
use crate::pipeline::table::{is_table_file, read_parquet};
use crate::pipeline::{Cost, InstanceId, Stage};
use layout::{Align, Cell, Columns, Sink};
use numbers::{Notation, fixed, natural_notation, or_why, significant, written};

/// Cell `col` of `row` as a number (NaN when null).
fn number(frame: &DataFrame, row: usize, col: Col<f64>) -> Result<f64> {
    Ok(frame.column(col.name)?.f64()?.get(row).unwrap_or(f64::NAN))
}

/// Cells `pair` of `row` as a `value ± error` cell (`undefined` when the
/// value is not a number).
fn estimate(frame: &DataFrame, row: usize, pair: Pair, undefined: &str) -> Result<Cell> {
    Ok(Cell::estimate(
        number(frame, row, pair.value)?,
        number(frame, row, pair.stderr)?,
        undefined,
    ))
}

/// Cells `pair` of `row`, a variance of velocities `[v_th^2]`: one whose
/// value and error are both below the square of the study's kick floor
/// (`kick_floor`, `v_th`: by default 1000x the engine's velocity error) is
/// the integrator's rounding, not a spread (the integrable n = 2 ring
/// printed `(3.83 ± 0.72)e-23`), and says so.
fn variance(frame: &DataFrame, row: usize, pair: Pair, kick_floor: f64) -> Result<Cell> {
    let floor = kick_floor.powi(2);
    let (value, error) = (
        number(frame, row, pair.value)?,
        number(frame, row, pair.stderr)?,
    );
    Ok(if value != 0.0 && value.abs() + error < floor {
        Cell::text(format!("< {floor:e} (engine floor)"))
    } else {
        Cell::estimate(value, error, "-")
    })
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
    study_table(&mut out, store, reports)?;
    paper_table(&mut out, store, reports)?;
    figures_line(&mut out, store, reports);
    if details {
        stage_tables(&mut out, store, reports, kick_floor)?;
    } else {
        out.title(
            "per-stage tables (gases, convergence, evolution, MD, scans, detailed balance): `ternary run --details`",
        );
    }
    Ok(out)
}

/// Every stage's table beyond `a_n` and the paper's: rates of gases,
/// convergence, evolution, MD and its comparison, scans, detailed balance
/// (velocity changes up to `kick_floor`, `v_th`, are the engine's error floor).
fn stage_tables(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
    kick_floor: f64,
) -> Result<()> {
    gases_table(out, store, reports)?;
    convergence_table(out, store, reports)?;
    evolve_table(out, store, reports)?;
    md_table(out, store, reports, kick_floor)?;
    compare_table(out, store, reports)?;
    scan_table(out, store, reports)?;
    balance_table(out, store, reports)
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

/// The sweeps' joint detailed-balance tests.
fn balance_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use crate::thresholds::DOMINATED_SHARE;
    use contract::sweep::balance_tests::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "detailed balance, joint over the pairs of each separation (sum of relative imbalances, correlations from the randomizations; pairs whose error one randomization carries left out)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("potential", Align::Left),
        ("b - a", Align::Right),
        ("pairs counted", Align::Right),
        ("joint imbalance", Align::Left),
        ("z", Align::Right),
        ("", Align::Left),
    ]);
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            let share = number(&frame, row, JOINT_LARGEST_SHARE)?;
            let z = or_why(number(&frame, row, JOINT_Z)?, |z| fixed(z, 2), "-");
            let verdict = if share <= DOMINATED_SHARE {
                String::new()
            } else if share.is_nan() {
                "no evidence: no kicks or no pairs".to_string()
            } else {
                format!(
                    "no evidence: one randomization carries {:.0}% of the spread",
                    100.0 * share
                )
            };
            table.push(vec![
                Cell::text(instance.as_str()),
                Cell::text(fixed(number(&frame, row, SEPARATION)?, 3)),
                Cell::text(format!(
                    "{}/{}",
                    count(&frame, row, COUNTED)?,
                    count(&frame, row, PAIRS)?
                )),
                estimate(&frame, row, JOINT_IMBALANCE, "-")?,
                Cell::text(z),
                Cell::text(verdict),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// The `paper` stage's output: published numbers against ours.
fn paper_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
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

/// One table of each instance that has it: the instance and its frame.
type InstanceFrames = Vec<(String, DataFrame)>;

/// The frames of `spec`'s table, after `title` goes to `out` (nothing goes
/// when no instance has the table).
fn titled_frames(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
    spec: &TableSpec,
    title: &str,
) -> Result<InstanceFrames> {
    let frames = table_frames(store, reports, spec)?;
    if !frames.is_empty() {
        out.title(title);
    }
    Ok(frames)
}

/// The table `spec` of every intact artifact of its stage in a run.
fn table_frames(
    store: &Store,
    reports: &[InstanceReport],
    spec: &TableSpec,
) -> Result<InstanceFrames> {
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
fn study_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::table::*;
    let Some((_, frame)) = table_frames(store, reports, &TABLE)?.into_iter().next() else {
        return Ok(());
    };
    out.title(
        "thermalization constants a_n = self variance rate at u' = 0, dilute limit, of scenes whose three atoms leave free, where converged: |u-u'| <= window/2, untruncated with a well [rho^2 l v_th]; recombination: rate of encounters leaving a bound pair [rho^2 l v_th]; kernel shape near u' (+- standard errors; shape: statistical and fit-protocol errors combined)",
    );
    let mut table = Columns::new(&[
        (POTENTIAL.name, Align::Left),
        ("a_n (converged)", Align::Left),
        ("rel.err", Align::Right),
        ("a_n untruncated", Align::Left),
        ("recombination", Align::Left),
        (BETA.value.name, Align::Left),
        ("sigma [v_th]", Align::Left),
        ("failed", Align::Right),
    ]);
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
        table.push(vec![
            Cell::text(text(&frame, row, POTENTIAL)?),
            Cell::estimate(a, a_err, "-"),
            Cell::text(relative),
            estimate(&frame, row, A_N_UNTRUNCATED, "-")?,
            recombination(&frame, row)?,
            estimate(&frame, row, BETA, no_shape)?,
            estimate(&frame, row, SIGMA, no_shape)?,
            Cell::text(format!(
                "{}/{}",
                count(&frame, row, FAILED_EVENTS)?,
                count(&frame, row, EVENTS)?
            )),
        ]);
    }
    out.table(&table);
    Ok(())
}

/// The recombination rate of a `table` row: "-" without a well (exactly
/// zero, no scene can bind).
fn recombination(frame: &DataFrame, row: usize) -> Result<Cell> {
    use contract::table::RECOMBINATION_RATE;
    let rate = number(frame, row, RECOMBINATION_RATE.value)?;
    let error = number(frame, row, RECOMBINATION_RATE.stderr)?;
    Ok(if rate == 0.0 && error == 0.0 {
        Cell::text("-".to_string())
    } else {
        Cell::estimate(rate, error, "-")
    })
}

/// The `gases` stage's output: rates in physical units.
fn gases_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::gases::*;
    let Some((_, frame)) = table_frames(store, reports, &TABLE)?.into_iter().next() else {
        return Ok(());
    };
    out.title(
        "thermalization rates in physical units (Gamma = a_n rho^2 l v_th, +- standard error)",
    );
    let mut table = Columns::new(&[
        (GAS.name, Align::Left),
        (POTENTIAL.name, Align::Left),
        ("kT [eV]", Align::Right),
        ("rho l", Align::Right),
        ("Gamma [1/ns] (dilute)", Align::Left),
        ("paper's rule at rho l *", Align::Left),
        ("1/Gamma [ns]", Align::Left),
    ]);
    for row in 0..frame.height() {
        table.push(vec![
            Cell::text(text(&frame, row, GAS)?),
            Cell::text(text(&frame, row, POTENTIAL)?),
            Cell::text(format!("{:.3e}", number(&frame, row, KT)?)),
            Cell::text(format!("{:.3e}", number(&frame, row, RHO_L)?)),
            estimate(&frame, row, GAMMA, "-")?,
            estimate(&frame, row, GAMMA_AT_DENSITY, "-")?,
            estimate(&frame, row, RELAXATION_TIME, "never: no kicks")?,
        ]);
    }
    out.table(&table);
    out.line(
        "* Gamma times the paper's launch rule's finite-density factor exp(-r |delay|) in a box of L = kernel.launch_length: an artifact of that algorithm (it depends on L), not the gas's rate at rho l; MD's finite-density change has the opposite sign (finite_size table)",
    );
    Ok(())
}

/// The `convergence` stage's output: shifts of `a_n` against the defaults.
fn convergence_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::convergence::*;
    for (instance, frame) in table_frames(store, reports, &TABLE)? {
        out.title(&format!(
            "convergence of a_n for {} (shift = a_n - default, paired over randomizations)",
            instance
        ));
        let mut table = Columns::new(&[
            (PARAMETER.name, Align::Left),
            (VALUE.name, Align::Right),
            (A_N.value.name, Align::Left),
            (SHIFT.value.name, Align::Left),
            ("shift / a_n error", Align::Right),
        ]);
        for row in 0..frame.height() {
            table.push(vec![
                Cell::text(text(&frame, row, PARAMETER)?),
                // The default row has no value: it is the configuration itself.
                Cell::text(or_why(
                    number(&frame, row, VALUE)?,
                    |v| format!("{v:.3e}"),
                    "-",
                )),
                estimate(&frame, row, A_N, "-")?,
                estimate(&frame, row, SHIFT, "-")?,
                Cell::text(or_why(
                    number(&frame, row, SHIFT_OVER_ERROR)?,
                    |z| fixed(z, 3),
                    "-",
                )),
            ]);
        }
        out.table(&table);
    }
    Ok(())
}

/// The `evolve` stage's summary: spread and approach to equilibrium of `h`.
fn evolve_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::evolve::evolution_summary::*;
    for (instance, frame) in table_frames(store, reports, &TABLE)? {
        out.title(&format!(
            "evolution of h from delta(u - u') for {instance}: full = linearized operator, tagged = special particle, fokker_planck (+- jackknife errors)"
        ));
        let mut table = Columns::new(&[
            (PROCESS.name, Align::Left),
            ("t Gamma", Align::Right),
            ("t [ns]", Align::Right),
            ("<(u-u')^2>, |u-u'|<=X", Align::Left),
            ("<(u-u')^2>", Align::Left),
            ("L1 distance to equilibrium", Align::Left),
        ]);
        for row in 0..frame.height() {
            table.push(vec![
                Cell::text(text(&frame, row, PROCESS)?),
                Cell::text(format!("{:.3e}", number(&frame, row, TIME_GAMMA)?)),
                // Times given in 1/Gamma have no time in ns.
                Cell::text(or_why(number(&frame, row, TIME_NS)?, |t| fixed(t, 0), "-")),
                estimate(&frame, row, WINDOW_VARIANCE, "-")?,
                estimate(&frame, row, VARIANCE, "-")?,
                estimate(&frame, row, DISTANCE_TO_EQUILIBRIUM, "-")?,
            ]);
        }
        out.table(&table);
    }
    Ok(())
}

/// The `md` stage's summaries: moments of `h(u, t_f)` by both estimators
/// (variances below `kick_floor^2` are the engine's rounding, [`variance`]).
fn md_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
    kick_floor: f64,
) -> Result<()> {
    use contract::md::summary::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "ring molecular dynamics: h(u, t_f) within the window (+- standard errors over runs)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        (contract::compare::RING.name, Align::Left),
        (ESTIMATOR.name, Align::Left),
        ("sum h du", Align::Left),
        ("<(u-u')^2>_window [v_th^2]", Align::Left),
    ]);
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            table.push(vec![
                Cell::text(instance.as_str()),
                Cell::text(text(&frame, row, ESTIMATOR)?),
                estimate(&frame, row, NUMBER, "-")?,
                variance(&frame, row, WINDOW_VARIANCE, kick_floor)?,
            ]);
        }
    }
    out.table(&table);
    bound_pairs_table(out, store, reports)?;
    Ok(())
}

/// The `compare` stage: goodness of fit of MD against Boltzmann and of the
/// scaling collapse, and the finite-size and density study.
fn compare_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::compare::{finite_size, goodness};
    use contract::estimator;
    for (_, frame) in table_frames(store, reports, &goodness::TABLE)? {
        out.title(
            "MD against Boltzmann and the scaling collapse: chi2 per degree of freedom with the variance MD would have if it followed the reference, its p-value, and (sample) with the runs' own errors",
        );
        let mut table = Columns::new(&[
            (goodness::RING.name, Align::Left),
            (goodness::REFERENCE.name, Align::Left),
            (goodness::ESTIMATOR.name, Align::Left),
            ("chi2/dof", Align::Right),
            (goodness::DOF.name, Align::Right),
            ("p", Align::Right),
            ("sample chi2/dof", Align::Right),
        ]);
        for row in 0..frame.height() {
            // No bin with a variance: nothing to compare.
            let reduced = |col| -> Result<String> {
                Ok(or_why(
                    number(&frame, row, col)?,
                    |c| fixed(c, 2),
                    "no bins",
                ))
            };
            table.push(vec![
                Cell::text(text(&frame, row, goodness::RING)?),
                Cell::text(text(&frame, row, goodness::REFERENCE)?),
                Cell::text(text(&frame, row, goodness::ESTIMATOR)?),
                Cell::text(reduced(goodness::CHI2_PER_DOF)?),
                Cell::text(count(&frame, row, goodness::DOF)?.to_string()),
                Cell::text(or_why(
                    number(&frame, row, goodness::P_VALUE)?,
                    |p| format!("{p:.2e}"),
                    "-",
                )),
                Cell::text(format!(
                    "{} ({})",
                    reduced(goodness::SAMPLE_CHI2_PER_DOF)?,
                    count(&frame, row, goodness::SAMPLE_DOF)?
                )),
            ]);
        }
        out.table(&table);
    }
    for (_, frame) in table_frames(store, reports, &finite_size::TABLE)? {
        out.title(
            "finite size and density: window variance at t_f, MD / Boltzmann (+- standard errors); tagged: starts near u', thermal: every start",
        );
        let mut table = Columns::new(&[
            (finite_size::RING.name, Align::Left),
            ("N", Align::Right),
            ("rho l", Align::Right),
            ("rho^2 l v_th t_f", Align::Right),
            (estimator::TAGGED, Align::Left),
            (estimator::THERMAL, Align::Left),
        ]);
        for row in 0..frame.height() {
            table.push(vec![
                Cell::text(text(&frame, row, finite_size::RING)?),
                Cell::text(count(&frame, row, finite_size::PARTICLES)?.to_string()),
                Cell::text(format!(
                    "{:.3e}",
                    number(&frame, row, finite_size::DENSITY)?
                )),
                Cell::text(format!(
                    "{:.4e}",
                    number(&frame, row, finite_size::SCALED_TIME)?
                )),
                estimate(&frame, row, finite_size::RATIO, "0/0: no spread")?,
                estimate(&frame, row, finite_size::THERMAL_RATIO, "0/0: no spread")?,
            ]);
        }
        out.table(&table);
    }
    Ok(())
}

/// The `scan` stages' peaks: largest `|u1f|` per launch pair.
fn scan_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::scan::{LAUNCH, peak::*};
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "mono-energetic scans: largest |u1f| (error bound) and its arrival offset",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        (contract::POTENTIAL.name, Align::Left),
        (LAUNCH.name, Align::Left),
        ("|u1f,max| [v_th]", Align::Left),
        ("offset [l/v_th]", Align::Left),
        ("failed", Align::Right),
        ("max |dE/E|", Align::Right),
    ]);
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            table.push(vec![
                Cell::text(instance.as_str()),
                Cell::text(text(&frame, row, LAUNCH)?),
                estimate(&frame, row, U1_FINAL_MAX_ABS, "-")?,
                estimate(&frame, row, ARRIVAL_OFFSET_AT_MAX, "no peak")?,
                Cell::text(count(&frame, row, FAILED_SCENES)?.to_string()),
                Cell::text(format!("{:.1e}", number(&frame, row, WORST_ENERGY_ERROR)?)),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// Bound neighbour pairs of the rings with a well: sampled, after the
/// dynamics, and the dilute limit.
fn bound_pairs_table(out: &mut dyn Sink, store: &Store, reports: &[InstanceReport]) -> Result<()> {
    use contract::md::pairs::*;
    for (instance, frame) in table_frames(store, reports, &TABLE)? {
        let bound = |state: &str| -> Result<Cell> {
            estimate(&frame, row_of(&frame, STATE, state)?, BOUND_FRACTION, "-")
        };
        let dilute = number(
            &frame,
            row_of(&frame, STATE, DILUTE_LIMIT)?,
            BOUND_FRACTION.value,
        )?;
        if dilute > 0.0 {
            out.line(&format!(
                "{instance}: bound neighbour pairs per gap {} initial, {} final, {} dilute limit rho K_b",
                bound(INITIAL)?,
                bound(FINAL)?,
                significant(dilute),
            ));
        }
    }
    Ok(())
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

/// `status` before its estimate: the count of instances by freshness, then
/// one line per instance (only those not fresh when `changed`) with why, and
/// with `shards > 1` which shards of a shardable one are done.
pub fn status(lines: &[StatusLine], shards: u32, changed: bool) -> String {
    let shown: Vec<&StatusLine> = lines
        .iter()
        .filter(|line| !changed || line.freshness != Freshness::Fresh)
        .collect();
    let width = shown
        .iter()
        .map(|line| line.id.to_string().chars().count())
        .max()
        .unwrap_or(0);
    let mut out = status_summary(lines);
    for line in shown {
        let key = line.key.as_deref().map_or("", |key| &key[..12]);
        let state = match &line.freshness {
            Freshness::Fresh => format!("fresh (key {key})"),
            Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
            Freshness::Damaged(problems) => format!(
                "damaged (key {key}): {} (the next run recomputes it)",
                problems.join("; ")
            ),
            Freshness::Missing(reason) => format!("missing: {reason}"),
        };
        let progress = line.shards.as_ref().map_or(String::new(), |progress| {
            format!(
                " (shards: {} of {shards} done, missing {:?})",
                progress.done.len(),
                progress.missing
            )
        });
        let _ = writeln!(out, "{:<width$}  {state}{progress}", line.id.to_string());
    }
    out
}

/// The first line of `status`: `N instances: F fresh, S stale, M missing`,
/// and the damaged ones when there are any.
fn status_summary(lines: &[StatusLine]) -> String {
    let count = |name: &str| {
        lines
            .iter()
            .filter(|line| line.freshness.name() == name)
            .count()
    };
    let damaged = match count("damaged") {
        0 => String::new(),
        damaged => format!(", {damaged} damaged"),
    };
    format!(
        "{} instances: {} fresh, {} stale, {} missing{damaged}\n",
        lines.len(),
        count("fresh"),
        count("stale"),
        count("missing"),
    )
}

/// The closing line of `status`: the estimated CPU time and store size of
/// the whole study and of its instances in `lines` that are not fresh
/// (still to compute).
pub fn cost_estimate(costs: &[(InstanceId, Cost)], lines: &[StatusLine]) -> String {
    let unfresh: BTreeSet<&InstanceId> = lines
        .iter()
        .filter(|line| line.freshness != Freshness::Fresh)
        .map(|line| &line.id)
        .collect();
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

/// An instance's state and why: `stale: <reasons>`, `missing: <reason>`.
pub fn describe(freshness: &Freshness) -> String {
    match freshness {
        Freshness::Fresh => "fresh".into(),
        Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
        Freshness::Damaged(problems) => format!("damaged: {}", problems.join("; ")),
        Freshness::Missing(reason) => format!("missing: {reason}"),
    }
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
/// (each instance reported to `on_event` as it is checked); the summary, and
/// the number of instances that differ or could not be checked.
pub fn audit(
    store: &Store,
    stages: &[Box<dyn Stage>],
    only: &[String],
    on_event: &mut dyn FnMut(executor::Event<'_>),
) -> Result<(String, usize)> {
    let audits = executor::recompute(store, stages, only, Verbosity::Normal, on_event)?;
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

/// What `ternary show` shows, and the number of problems of an artifact
/// looked up in the store (checked to its file hashes; a damaged one is shown
/// under a warning). `target` is a Parquet file or an artifact directory; a
/// stage of `plan` (its current instances, their keys and files); an
/// instance `stage[instance]` (its current artifact); or an artifact key or
/// unique key prefix of at least 6 characters.
pub fn show(
    store: Option<&Store>,
    plan: &[Box<dyn Stage>],
    target: &str,
    rows: usize,
) -> Result<(String, usize)> {
    let path = Path::new(target);
    if path.is_file() {
        return Ok((show_file(path, rows)?, 0));
    }
    if path.is_dir() {
        return Ok((show_artifact(path, &[], rows)?, 0));
    }
    let Some(store) = store else {
        bail!("`{target}` is neither a file nor a directory, and no store is open to look up keys")
    };
    if plan.iter().any(|stage| stage.id().stage == target) {
        return Ok((show_stage(store, plan, target)?, 0));
    }
    let (stage, key) = match target.strip_suffix(']').and_then(|t| t.split_once('[')) {
        Some((stage, instance)) => {
            current_artifact(store, plan, &InstanceId::new(stage, instance))?
        }
        None => artifact_by_prefix(store, target)?,
    };
    let problems = store
        .inspect(&stage, &key, None, Depth::Hashes)
        .err()
        .unwrap_or_default();
    let text = show_artifact(&store.artifact_dir(&stage, &key), &problems, rows)?;
    Ok((text, problems.len()))
}

/// The current instances of `stage`: freshness and key of each, and the
/// files of those with an artifact under their current key.
fn show_stage(store: &Store, plan: &[Box<dyn Stage>], stage: &str) -> Result<String> {
    let lines: Vec<StatusLine> = executor::status(store, plan, 1)?
        .into_iter()
        .filter(|line| line.id.stage == stage)
        .collect();
    let mut out = String::new();
    writeln!(
        out,
        "{stage}: {} instances (`ternary show '{stage}[<instance>]'` shows one)",
        lines.len()
    )?;
    for line in &lines {
        let key = line.key.as_deref().unwrap_or("(inputs not computed)");
        writeln!(out, "{}  {}  key {key}", line.id, line.freshness.name())?;
        let Some(key) = line
            .key
            .as_deref()
            .filter(|_| matches!(line.freshness, Freshness::Fresh | Freshness::Damaged(_)))
        else {
            continue;
        };
        let dir = store.artifact_dir(stage, key);
        if let Ok(manifest) = store.inspect(stage, key, None, Depth::Sizes) {
            for file in &manifest.files {
                writeln!(
                    out,
                    "    {} ({})",
                    dir.join(&file.name).display(),
                    size(file.bytes as f64)
                )?;
            }
        }
    }
    Ok(out)
}

/// The stage and current key of instance `id` of `plan` when its artifact
/// exists (intact or damaged); otherwise why there is none.
fn current_artifact(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
) -> Result<(String, String)> {
    executor::check_stage_names(plan, std::slice::from_ref(&id.stage))
        .map_err(anyhow::Error::msg)?;
    let line = executor::status(store, plan, 1)?
        .into_iter()
        .find(|line| &line.id == id)
        .with_context(|| {
            format!(
                "no instance `{id}` in the study (`ternary show {}` lists them)",
                id.stage
            )
        })?;
    let why = match line.freshness {
        Freshness::Fresh | Freshness::Damaged(_) => {
            let key = line.key.with_context(|| format!("{id} has no key"))?;
            return Ok((id.stage.clone(), key));
        }
        Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
        Freshness::Missing(reason) => format!("missing: {reason}"),
    };
    bail!("{id} has no artifact under its current key ({why}); `ternary run` computes it")
}

/// The artifact whose key starts with `prefix` (at least 6 characters).
fn artifact_by_prefix(store: &Store, prefix: &str) -> Result<(String, String)> {
    if prefix.len() < 6 {
        bail!(
            "`{prefix}` is not a stage, an instance `stage[instance]` or a path; give at least 6 characters of a key"
        );
    }
    let mut matches: Vec<(String, String)> = store
        .artifacts()?
        .into_iter()
        .filter(|(_, key)| key.starts_with(prefix))
        .collect();
    match matches.len() {
        1 => Ok(matches.remove(0)),
        0 => bail!(
            "no stage, instance or artifact key `{prefix}` in {} (`ternary dag --stages` lists the stages)",
            store.root().display()
        ),
        n => bail!("`{prefix}` is ambiguous: {n} artifacts match"),
    }
}

/// The artifact in `dir`: its manifest, under a warning naming `problems`
/// when it has any, then each table ([`show_file`]) and other file.
fn show_artifact(dir: &Path, problems: &[String], rows: usize) -> Result<String> {
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
    Ok(out)
}
