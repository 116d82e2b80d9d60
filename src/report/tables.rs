//! Every stage's table beyond `a_n` and the paper's, as `ternary run
//! --details` prints them: rates of gases, convergence, evolution, MD and
//! its comparison, scans, bound pairs, detailed balance.

use anyhow::Result;

use super::layout::{Align, Cell, Columns, Sink};
use super::numbers::{fixed, or_why, significant};
use crate::contract;
use crate::pipeline::executor::InstanceReport;
use crate::pipeline::store::Store;
use crate::stats::ChiSquare;
use polars::prelude::DataFrame;

use super::{count, estimate, number, row_of, table_frames, text, titled_frames, variance};

/// The sweeps' joint tests of the drift against stationarity.
pub(super) fn stationarity_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::sweep::stationarity::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "Fokker-Planck stationarity, joint over u' < 0: the drift's relative excess along P = (D2' - u D2)/2, sum s (D1 - P) / sum |P| (s the sign of P; correlations from the randomizations; below 0 the drift is weaker than stationarity requires)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("potential", Align::Left),
        ("points", Align::Right),
        ("relative residual", Align::Left),
        ("z", Align::Right),
        ("", Align::Left),
    ]);
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            let share = number(&frame, row, LARGEST_SHARE)?;
            table.push(vec![
                Cell::text(instance.as_str()),
                Cell::text(count(&frame, row, POINTS)?.to_string()),
                estimate(&frame, row, RELATIVE_RESIDUAL, "-")?,
                Cell::text(or_why(number(&frame, row, JOINT_Z)?, |z| fixed(z, 2), "-")),
                Cell::text(evidence_verdict(share)),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// Whether a joint test whose spread one randomization carries `share` of
/// is evidence: empty when it is, else why not.
fn evidence_verdict(share: f64) -> String {
    use crate::thresholds::DOMINATED_SHARE;
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

/// The sweeps' joint detailed-balance tests.
pub(super) fn balance_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
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
            let verdict = evidence_verdict(share);
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

/// The `gases` stage's output: rates in physical units.
pub(super) fn gases_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
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
pub(super) fn convergence_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
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
pub(super) fn evolve_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
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
            ("relative entropy", Align::Left),
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
                estimate(&frame, row, ENTROPY, "-")?,
            ]);
        }
        out.table(&table);
    }
    Ok(())
}

/// The `spectrum` stage's summaries: per potential and generator the
/// variance rate, the gap and the gap over it, and the modes noise makes grow.
pub(super) fn spectrum_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::spectrum::summary::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "relaxation spectrum: the gap (slowest rate above the growing noise modes) of the linearized operator (full: the gas) and of the tagged particle, over Gamma = the tagged variance rate at u' = 0 [rho^2 l v_th] (+- jackknife errors; docs/spectrum.md)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("potential", Align::Left),
        (GENERATOR.name, Align::Left),
        ("Gamma", Align::Left),
        ("gap", Align::Left),
        ("gap / Gamma", Align::Left),
        ("growing modes", Align::Right),
    ]);
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            table.push(vec![
                Cell::text(instance.as_str()),
                Cell::text(text(&frame, row, GENERATOR)?),
                estimate(&frame, row, VARIANCE_RATE, "-")?,
                estimate(&frame, row, GAP, "-")?,
                estimate(&frame, row, GAP_OVER_VARIANCE_RATE, "-: no kicks")?,
                Cell::text(count(&frame, row, GROWING_MODES)?.to_string()),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// The `near_integrable` stage's fits: how the rates vanish at `n = 2`.
pub(super) fn near_integrable_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::near_integrable::fits::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "near the Calogero point n = 2: rate = A (n - 2)^p exp(q (n - 2)), generalized least squares with the rates' covariance across n over the resolved rates (positive by 3 standard errors; four needed) [A: rho^2 l v_th, or 1 for a ratio] (+- fit errors; z: p against first-order perturbation theory with the law's truncation error, |p - p with s (n - 2)^2|, added; docs/spectrum.md)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        (QUANTITY.name, Align::Left),
        ("p", Align::Left),
        ("expected", Align::Right),
        ("z", Align::Right),
        ("A", Align::Left),
        ("q", Align::Left),
        ("chi2/dof", Align::Right),
        ("p-value", Align::Right),
        ("fitted", Align::Left),
    ]);
    for (_, frame) in frames {
        for row in 0..frame.height() {
            let (chi2, dof) = (number(&frame, row, CHI2)?, count(&frame, row, DOF)?);
            table.push(vec![
                Cell::text(text(&frame, row, QUANTITY)?),
                estimate(&frame, row, EXPONENT, "-")?,
                Cell::text(fixed(number(&frame, row, EXPECTED_EXPONENT)?, 0)),
                Cell::text(or_why(
                    number(&frame, row, EXPONENT_Z)?,
                    |z| fixed(z, 2),
                    "-",
                )),
                estimate(&frame, row, AMPLITUDE, "-")?,
                estimate(&frame, row, CORRECTION, "-")?,
                Cell::text(or_why(chi2 / f64::from(dof), |c| fixed(c, 2), "-")),
                Cell::text(
                    ChiSquare {
                        chi2,
                        dof: dof as usize,
                    }
                    .p_digits(),
                ),
                Cell::text(text(&frame, row, FITTED)?),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// The `md` stage's summaries: moments of `h(u, t_f)` by both estimators
/// (variances below `kick_floor^2` are the engine's rounding, [`variance`]).
pub(super) fn md_table(
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
pub(super) fn compare_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::compare::{finite_size, goodness};
    use contract::estimator;
    for (_, frame) in table_frames(store, reports, &goodness::TABLE)? {
        out.title(
            "MD against Boltzmann and the scaling collapse: the shape's chi2 per degree of freedom with the variance MD would have if it followed the reference, its p-value, and (sample) with the runs' own errors; the window variance over the reference's and its z; the verdict of both (differs: p < 1e-3 or |z| > 3.29)",
        );
        let mut table = Columns::new(&[
            (goodness::RING.name, Align::Left),
            (goodness::REFERENCE.name, Align::Left),
            (goodness::ESTIMATOR.name, Align::Left),
            ("chi2/dof", Align::Right),
            (goodness::DOF.name, Align::Right),
            ("p", Align::Right),
            ("sample chi2/dof", Align::Right),
            ("variance / reference", Align::Right),
            ("z", Align::Right),
            (goodness::VERDICT.name, Align::Left),
        ]);
        for row in 0..frame.height() {
            // Null: no shape test, or too few degrees of freedom for one.
            let reduced = |col| -> Result<String> {
                Ok(or_why(number(&frame, row, col)?, |c| fixed(c, 2), "-"))
            };
            table.push(vec![
                Cell::text(text(&frame, row, goodness::RING)?),
                Cell::text(text(&frame, row, goodness::REFERENCE)?),
                Cell::text(text(&frame, row, goodness::ESTIMATOR)?),
                Cell::text(reduced(goodness::CHI2_PER_DOF)?),
                Cell::text(count(&frame, row, goodness::DOF)?.to_string()),
                Cell::text({
                    // Null chi2: no shape test at all (the thermal estimator).
                    let chi2 = number(&frame, row, goodness::CHI2)?;
                    let dof = count(&frame, row, goodness::DOF)? as usize;
                    or_why(chi2, |chi2| ChiSquare { chi2, dof }.p_text(), "-")
                }),
                Cell::text(format!(
                    "{} ({})",
                    reduced(goodness::SAMPLE_CHI2_PER_DOF)?,
                    count(&frame, row, goodness::SAMPLE_DOF)?
                )),
                estimate(&frame, row, goodness::VARIANCE_RATIO, "-")?,
                Cell::text(reduced(goodness::VARIANCE_Z)?),
                Cell::text(text(&frame, row, goodness::VERDICT)?),
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
pub(super) fn scan_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
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

/// The `pulls` stage's summary: whether the study's errors are calibrated
/// by its own cross-checks.
pub(super) fn pulls_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::pulls::summary::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "cross-checks: pulls (a - b) / combined error of every quantity computed two independent ways or held against an exact value (recombination three ways, detailed balance); N(0, 1) when the errors are right (pulls.parquet lists each)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("pulls", Align::Right),
        ("mean", Align::Left),
        ("spread", Align::Right),
        ("largest", Align::Right),
        ("where", Align::Left),
        ("verdict", Align::Left),
    ]);
    for (_, frame) in frames {
        for row in 0..frame.height() {
            let worst = format!(
                "{}: {}",
                text(&frame, row, WORST_SUBJECT)?,
                text(&frame, row, WORST_CHECK)?
            );
            table.push(vec![
                Cell::text(count(&frame, row, PULLS)?.to_string()),
                estimate(&frame, row, MEAN, "-")?,
                Cell::text(or_why(number(&frame, row, SPREAD)?, |s| fixed(s, 2), "-")),
                Cell::text(or_why(
                    number(&frame, row, WORST_PULL)?,
                    |z| fixed(z, 2),
                    "-",
                )),
                Cell::text(worst),
                Cell::text(text(&frame, row, VERDICT)?),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// Pulls listed by [`largest_pulls_table`].
const LARGEST_PULLS: usize = 10;

/// The `pulls` stage's largest pulls, largest |pull| first.
pub(super) fn largest_pulls_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::pulls::checks::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        &format!(
            "the {LARGEST_PULLS} largest pulls (a: first estimate, b: second or exact; units per check)"
        ),
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("pull", Align::Right),
        ("subject", Align::Left),
        ("a", Align::Left),
        ("b", Align::Left),
        ("check", Align::Left),
    ]);
    for (_, frame) in frames {
        let mut rows: Vec<(usize, f64)> = (0..frame.height())
            .map(|row| Ok((row, number(&frame, row, PULL)?)))
            .collect::<Result<_>>()?;
        rows.retain(|(_, pull)| pull.is_finite());
        rows.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        for &(row, pull) in rows.iter().take(LARGEST_PULLS) {
            table.push(vec![
                Cell::text(fixed(pull, 2)),
                Cell::text(text(&frame, row, SUBJECT)?),
                estimate(&frame, row, FIRST, "-")?,
                estimate(&frame, row, SECOND, "-")?,
                Cell::text(text(&frame, row, CHECK)?),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// The kernel models' goodness of fit, one row per kernel (`fit` stage).
pub(super) fn kernel_model_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::fit::model_fit::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "kernel model: ln G (part total) and ln G_self (part self) a natural cubic spline in ln|du| + |du| / x_c on each side of u', fitted to kernel_log's groups; chi2 against its mean and spread under flipped randomizations (a wild bootstrap), p the share of flips reaching it (docs/kernel-model.md)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("kernel", Align::Left),
        ("part", Align::Left),
        ("knots", Align::Right),
        ("groups", Align::Right),
        ("chi2", Align::Right),
        ("expected", Align::Left),
        ("chi2/expected", Align::Right),
        ("p", Align::Right),
        ("status", Align::Left),
    ]);
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            let chi2 = number(&frame, row, CHI2)?;
            let expected = number(&frame, row, CHI2_EXPECTED)?;
            let spread = number(&frame, row, CHI2_SPREAD)?;
            table.push(vec![
                Cell::text(instance.as_str()),
                Cell::text(text(&frame, row, contract::fit::model::PART)?),
                Cell::text(count(&frame, row, KNOTS)?.to_string()),
                Cell::text(count(&frame, row, GROUPS)?.to_string()),
                Cell::text(or_why(chi2, |c| fixed(c, 1), "-")),
                Cell::text(or_why(
                    expected,
                    |e| format!("{} ± {}", fixed(e, 1), fixed(spread, 1)),
                    "-",
                )),
                Cell::text(or_why(chi2 / expected, |r| fixed(r, 2), "-")),
                Cell::text(or_why(number(&frame, row, P_VALUE)?, |p| fixed(p, 3), "-")),
                Cell::text(text(&frame, row, STATUS)?),
            ]);
        }
    }
    out.table(&table);
    Ok(())
}

/// How well the kernel models interpolate (`interpolation` stage): per
/// coordinate, every computed kernel held out and predicted from its
/// neighbours, summed over the kernels.
pub(super) fn kernel_interpolation_table(
    out: &mut dyn Sink,
    store: &Store,
    reports: &[InstanceReport],
) -> Result<()> {
    use contract::interpolation::summary::*;
    let frames = titled_frames(
        out,
        store,
        reports,
        &TABLE,
        "kernel models between the computed kernels: each held out and predicted from its neighbours' models as `ternary kernel` interpolates them; z = ln(model / predicted) in the error `ternary kernel` states (its interpolation estimate and statistical error in quadrature) per log group, |z| > 2 for 4.6% of the groups and median |z| (the median of the held-out kernels') 0.674 when the errors are right (kernel_interpolation.parquet lists each group; docs/kernel-model.md)",
    )?;
    if frames.is_empty() {
        return Ok(());
    }
    let mut table = Columns::new(&[
        ("in", Align::Left),
        ("held out", Align::Right),
        ("groups", Align::Right),
        ("|z| > 2", Align::Right),
        ("median |z|", Align::Right),
        ("largest |z|", Align::Right),
        ("where", Align::Left),
        ("largest deviation", Align::Right),
    ]);
    for (_, frame) in frames {
        let coordinates: Vec<String> = (0..frame.height())
            .map(|row| text(&frame, row, COORDINATE))
            .collect::<Result<_>>()?;
        let mut seen: Vec<&String> = coordinates.iter().collect();
        seen.dedup();
        for coordinate in seen {
            let rows: Vec<usize> = (0..frame.height())
                .filter(|&row| &coordinates[row] == coordinate)
                .collect();
            table.push(interpolation_row(&frame, coordinate, &rows)?);
        }
    }
    out.table(&table);
    Ok(())
}

/// One coordinate's row of [`kernel_interpolation_table`]: the sums over
/// the summary's `rows` of it.
fn interpolation_row(frame: &DataFrame, coordinate: &str, rows: &[usize]) -> Result<Vec<Cell>> {
    use contract::interpolation::summary::*;
    let sum = |col| -> Result<u32> { rows.iter().map(|&row| count(frame, row, col)).sum() };
    let values =
        |col| -> Result<Vec<f64>> { rows.iter().map(|&row| number(frame, row, col)).collect() };
    let (groups, beyond) = (sum(GROUPS)?, sum(BEYOND_TWO)?);
    let largest = values(LARGEST_ABS_Z)?;
    let worst = (0..rows.len()).fold(0, |w, k| if largest[k] > largest[w] { k } else { w });
    let row = rows[worst];
    let deviation = values(LARGEST_DEVIATION)?.into_iter().fold(0.0, f64::max);
    Ok(vec![
        Cell::text(coordinate),
        Cell::text(rows.len().to_string()),
        Cell::text(groups.to_string()),
        Cell::text(format!(
            "{beyond} ({}%)",
            fixed(100.0 * f64::from(beyond) / f64::from(groups.max(1)), 1)
        )),
        Cell::text(fixed(crate::stats::median(&values(MEDIAN_ABS_Z)?), 2)),
        Cell::text(fixed(largest[worst], 2)),
        Cell::text(format!(
            "{} u' = {}",
            text(frame, row, contract::POTENTIAL)?,
            number(frame, row, U_PRIME)?
        )),
        Cell::text(format!("{}%", fixed(100.0 * deviation, 1))),
    ])
}
