//! The run summary `ternary run` prints: `a_n` per potential (the `table`
//! stage), the paper's Table I against ours, where the figures are, and
//! with details every stage's table (each printed as its contract declares:
//! [`super::printout`]).

use anyhow::Result;

use super::layout::Sink;
use crate::contract;
use crate::contract::{near_integrable::fits, pulls};
use crate::pipeline::executor::InstanceReport;
use crate::pipeline::store::Store;

use super::printout::print;

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
        &contract::table::HEADLINE,
        kick_floor,
    )?;
    print(&mut out, store, reports, &fits::HEADLINE, kick_floor)?;
    for printout in contract::paper::HEADLINES {
        print(&mut out, store, reports, printout, kick_floor)?;
    }
    print(
        &mut out,
        store,
        reports,
        &pulls::summary::HEADLINE,
        kick_floor,
    )?;
    figures_line(&mut out, store, reports);
    if details {
        print(
            &mut out,
            store,
            reports,
            &pulls::checks::LARGEST,
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
