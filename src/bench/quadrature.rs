//! The offset-quadrature benchmark: quadrature against sampled offsets,
//! and the inner rule's convergence.

use std::fmt::Write as _;
use std::time::Instant;

use rayon::prelude::*;

use ternary::kernel::Target;
use ternary::physics::offset_quadrature::{OffsetIntegral, OffsetRule};
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{LaunchProposal, OffsetIntegration, SamplingPlan};
use ternary::physics::scan::LaunchPair;

use super::sampler::{KernelRun, StudySettings, Variant, plan_for, precision_cells, run_sampler};
use super::*;

/// A quadrature run and the time its pilot took (included in `run.seconds`).
pub(super) struct QuadratureRun {
    pub(super) run: KernelRun,
    pub(super) pilot_seconds: f64,
}

/// The quadrature sampler with `pairs` launch pairs per randomization, the
/// strata split by its own pilot (timed with the run).
pub(super) fn run_quadrature(
    potential: &Potential,
    variant: &Variant,
    options: &KernelBenchOptions,
    pairs: u32,
) -> QuadratureRun {
    let started = Instant::now();
    let probe = plan_for(variant, options.seed, options.randomizations, pairs);
    let fraction = ternary::kernel::pilot_same_side_fraction(
        &probe,
        potential,
        &options.study.engine,
        &[Target::dilute(0.0)],
        1024,
    )
    .unwrap_or(variant.same_side_fraction);
    let pilot_seconds = started.elapsed().as_secs_f64();
    let split = Variant {
        same_side_fraction: fraction,
        ..*variant
    };
    let plan = plan_for(&split, options.seed, options.randomizations, pairs);
    let mut run = run_sampler(potential, &plan, &options.study);
    run.seconds += pilot_seconds;
    QuadratureRun { run, pilot_seconds }
}

/// Work-precision of `a_n` and the near bins with the quadrature sampler: error
/// against launch pairs and wall time.
pub(super) fn quadrature_work_precision(
    potential: &Potential,
    quadrature: &Variant,
    options: &KernelBenchOptions,
) -> (String, Vec<KernelRun>) {
    let mut out = format!(
        "\nWork-precision of a_n with the offset quadrature ({} randomizations; seconds include the pilot):\n\n",
        options.randomizations
    );
    out.push_str("| pairs per randomization | scenes | seconds | a_n | relative standard error | near-bin rel. error | far-bin rel. error |\n|---|---|---|---|---|---|---|\n");
    let shifted = KernelBenchOptions {
        seed: options.seed + 1,
        ..*options
    };
    let mut runs = Vec::new();
    // 3x: at the default 4096 points, 12288 = 8192 + 4096 pairs for a
    // same-side share near 1/3 (each stratum a power of two).
    let sizes = [(1, 64), (1, 16), (1, 4), (1, 1), (2, 1), (3, 1)];
    for pairs in work_precision_sizes(options.points, &sizes) {
        let QuadratureRun { run, .. } = run_quadrature(potential, quadrature, &shifted, pairs);
        let _ = writeln!(
            out,
            "{} {:.2e} |",
            precision_cells(pairs, &run),
            run.far_bins
        );
        runs.push(run);
    }
    (out, runs)
}

/// The inner rule's error against its nodes: for thermal launch pairs, the
/// relative error of `int kick^2 dtau` after each halving, against the rule
/// with three more halvings, and the bound the refinement reports.
pub(super) fn inner_rule_convergence(
    potential: &Potential,
    study: &StudySettings,
    seed: u64,
) -> String {
    const PAIRS: u32 = 64;
    const HALVINGS: u32 = 4;
    let plan = SamplingPlan {
        seed,
        randomizations: 1,
        opposite_points: PAIRS,
        same_side_points: PAIRS,
        proposal: study.proposal,
        quasi_random: false,
        launch: LaunchProposal::THERMAL,
        offsets: OffsetIntegration::Sampled,
    };
    let launches: Vec<(LaunchPair, f64)> = plan
        .launch_points(0..1)
        .iter()
        .map(|point| (point.launch, point.offset_coordinate))
        .collect();
    let fixed = |halvings: u32| OffsetRule {
        halvings,
        ..study.quadrature
    };
    let integrals = |rule: OffsetRule| -> Vec<OffsetIntegral> {
        launches
            .par_iter()
            .map(|&(launch, shift)| rule.integrate(potential, &study.engine, launch, shift))
            .collect()
    };
    let reference = integrals(fixed(HALVINGS + 3));
    let mut out = format!(
        "\nInner rule (tau = T sinh(s), step {} halved, |s| <= {:.2}; the study halves {} times): relative error of int kick^2 dtau against {} halvings, {} thermal pairs per stratum:\n\n",
        study.quadrature.coarse_step,
        study.quadrature.half_range,
        study.quadrature.halvings,
        HALVINGS + 3,
        PAIRS
    );
    out.push_str("| halvings | nodes per pair | median rel. error | largest rel. error | smallest bound / error (>= 1: bounds hold) |\n|---|---|---|---|---|\n");
    for halvings in 1..=HALVINGS {
        let results = integrals(fixed(halvings));
        let mut errors: Vec<f64> = results
            .iter()
            .zip(&reference)
            .filter(|(_, r)| r.self_variance > 0.0)
            .map(|(a, r)| (a.self_variance - r.self_variance).abs() / r.self_variance)
            .collect();
        // Differences at the integration's own precision (1e-12) say nothing of the rule.
        let covered = results
            .iter()
            .zip(&reference)
            .filter(|(a, r)| (a.self_variance - r.self_variance).abs() > 1e-12 * r.self_variance)
            .map(|(a, r)| a.error / (a.self_variance - r.self_variance).abs())
            .fold(f64::INFINITY, f64::min);
        errors.sort_by(f64::total_cmp);
        let _ = writeln!(
            out,
            "| {halvings} | {} | {:.1e} | {:.1e} | {:.1e} |",
            results[0].nodes.len(),
            errors[errors.len() / 2],
            errors[errors.len() - 1],
            covered,
        );
    }
    out
}
