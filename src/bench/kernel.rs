//! The kernel benchmark: shape and `a_n` errors against wall time for the
//! study's sampler variants (offset proposals, pilot, skipping).

use std::fmt::Write as _;
use std::time::Instant;

use ternary::figures::{Layout, Style};
use ternary::kernel::Target;
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{OffsetIntegration, OffsetProposal, SamplingPlan, SceneRecord};
use ternary::physics::scene::EngineSettings;

use super::integrators::velocity_error;
use super::quadrature::{inner_rule_convergence, quadrature_work_precision, run_quadrature};
use super::sampler::{
    KernelBenchOptions, KernelRun, Variant, plan_for, precision_cells, run_sampler,
};
use super::*;

/// The baseline of numerics.md: offsets uniform within +-30 collision times.
fn uniform_offsets() -> OffsetProposal {
    OffsetProposal {
        core_weight: 0.0,
        tail_weight: 0.0,
        uniform_weight: 1.0,
        uniform_range: 30.0,
        ..OffsetProposal::default()
    }
}

/// One row of the sampler comparison, gains as figure-of-merit ratios against `base`.
fn comparison_row(name: &str, run: &KernelRun, base: &KernelRun) -> String {
    let relative = |run: &KernelRun| run.a_n.stderr / run.a_n.mean;
    let gain =
        |error: f64, base_error: f64| merit(error, run.seconds) / merit(base_error, base.seconds);
    format!(
        "| {} | {} | {:.2} | {:.6e} +- {:.1e} | {:.2e} | x{:.1} | {:.2e} | x{:.2} | {:.2e} | x{:.1} |\n",
        name,
        run.scenes,
        run.seconds,
        run.a_n.mean,
        run.a_n.stderr,
        relative(run),
        gain(relative(run), relative(base)),
        run.near_bins,
        gain(run.near_bins, base.near_bins),
        run.far_bins,
        gain(run.far_bins, base.far_bins),
    )
}

/// Figure of merit `1 / (relative variance x seconds)`.
fn merit(relative_error: f64, seconds: f64) -> f64 {
    1.0 / (relative_error * relative_error * seconds)
}

/// Sampler comparison (each measure's gain as a ratio measured in this run) and
/// the work-precision table of `a_n` for the default sampler.
pub fn kernel(options: &KernelBenchOptions) -> (String, BenchFigure) {
    let potential = options.potential;
    let study = &options.study;
    let defaults = study.proposal;
    let variants = [
        Variant {
            name: "uniform offsets +-30 T, even strata, plain MC",
            proposal: uniform_offsets(),
            same_side_fraction: 0.5,
            quasi_random: false,
            offsets: OffsetIntegration::Sampled,
            slow_share: 0.0,
        },
        Variant {
            name: "+ mixture offset proposal",
            proposal: defaults,
            same_side_fraction: 0.5,
            quasi_random: false,
            offsets: OffsetIntegration::Sampled,
            slow_share: 0.0,
        },
        Variant {
            name: "+ strata 85/15 (opposite/same side)",
            proposal: defaults,
            same_side_fraction: 0.15,
            quasi_random: false,
            offsets: OffsetIntegration::Sampled,
            slow_share: 0.0,
        },
        Variant {
            name: "+ scrambled Sobol' points",
            proposal: defaults,
            same_side_fraction: 0.15,
            quasi_random: true,
            offsets: OffsetIntegration::Sampled,
            slow_share: 0.0,
        },
    ];
    let mut out = String::new();
    let _ = writeln!(
        out,
        "### Kernel sampler: {}, {} randomizations x ~{} scenes, seed {}\n",
        options.potential.id(),
        options.randomizations,
        options.points,
        options.seed
    );
    let _ = writeln!(
        out,
        "Figure of merit FOM = 1 / (relative variance x wall seconds); gains are FOM ratios against the first row, all measured in this run. Bins: median relative error of G over bins with 1e-4 <= |du| <= 2e-3 (near) and 1e-2 <= |du| <= 5e-2 (far), bin width 5e-5.\n"
    );
    let _ = writeln!(
        out,
        "| sampler | scenes | seconds | a_n | rel. error | a_n gain | near-bin rel. error | near gain | far-bin rel. error | far gain |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    let mut baseline: Option<KernelRun> = None;
    for variant in &variants {
        let run = run_sampler(
            &potential,
            &plan_for(
                variant,
                options.seed,
                options.randomizations,
                options.points,
            ),
            study,
        );
        let base = *baseline.get_or_insert(run);
        out.push_str(&comparison_row(variant.name, &run, &base));
    }
    let engine = study.engine;
    let target = Target::dilute(0.0);
    let probe = plan_for(
        &variants[3],
        options.seed,
        options.randomizations,
        options.points,
    );
    let started = Instant::now();
    let fraction =
        ternary::kernel::pilot_same_side_fraction(&probe, &potential, &engine, &[target], 1024)
            .unwrap_or(0.15);
    let pilot_seconds = started.elapsed().as_secs_f64();
    let piloted = Variant {
        name: "+ strata from a pilot (default)",
        proposal: defaults,
        same_side_fraction: fraction,
        quasi_random: true,
        offsets: OffsetIntegration::Sampled,
        slow_share: 0.0,
    };
    let piloted_plan = plan_for(
        &piloted,
        options.seed,
        options.randomizations,
        options.points,
    );
    let mut run = run_sampler(&potential, &piloted_plan, study);
    run.seconds += pilot_seconds;
    let name = format!(
        "{} (same side {fraction:.3}, pilot {pilot_seconds:.2} s included)",
        piloted.name
    );
    let base = baseline.unwrap_or(run);
    out.push_str(&comparison_row(&name, &run, &base));
    let quadrature = Variant {
        name: "offset quadrature, 2-D Sobol' launch pairs",
        offsets: OffsetIntegration::Quadrature(study.quadrature),
        ..piloted
    };
    let pairs = (options.points / study.quadrature.nodes()).max(16);
    let run = run_quadrature(&potential, &quadrature, options, pairs);
    let name = format!(
        "{} ({pairs} pairs per randomization, pilot {:.2} s included)",
        quadrature.name, run.pilot_seconds
    );
    out.push_str(&comparison_row(&name, &run.run, &base));
    let _ = writeln!(
        out,
        "\nWork-precision of a_n with the default sampler ({} randomizations):\n",
        options.randomizations
    );
    let _ = writeln!(
        out,
        "| scenes per randomization | scenes | seconds | a_n | relative standard error | near-bin rel. error | alpha rel. error | beta rel. error | sigma rel. error | fit chi2/dof |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    let default = &piloted;
    let mut sampled_runs = Vec::new();
    for points in work_precision_sizes(options.points, &[(1, 4), (1, 1), (4, 1), (16, 1)]) {
        let run = run_sampler(
            &potential,
            &plan_for(default, options.seed + 1, options.randomizations, points),
            study,
        );
        let [alpha, beta, sigma] = run.shape;
        let _ = writeln!(
            out,
            "{} {alpha:.2e} | {beta:.2e} | {sigma:.2e} | {:.1} |",
            precision_cells(points, &run),
            run.chi2_per_dof,
        );
        sampled_runs.push(run);
    }
    let (table, quadrature_runs) = quadrature_work_precision(&potential, &quadrature, options);
    out.push_str(&table);
    out.push_str(&inner_rule_convergence(&potential, study, options.seed));
    out.push_str(&skipping(&potential, &piloted_plan, study));
    let series = [
        ("sampled offsets", &sampled_runs),
        ("offset quadrature", &quadrature_runs),
    ];
    (out, kernel_figure(&series, options.randomizations))
}

/// A relative error a kernel run reports.
type Measure = fn(&KernelRun) -> f64;

/// Relative errors of `a_n` and of the near-`u'` bins against wall time, per
/// sampler. A standard error from `R` randomizations is itself uncertain by
/// `1 / sqrt(2 (R - 1))` of its value: the error bars.
fn kernel_figure(series: &[(&str, &Vec<KernelRun>)], randomizations: u32) -> BenchFigure {
    let spread = 1.0 / (2.0 * f64::from(randomizations - 1)).sqrt();
    let measures: [(&str, Measure); 2] = [
        ("a_n", |run| run.a_n.stderr / run.a_n.mean),
        ("near bins", |run| run.near_bins),
    ];
    let points = measures
        .iter()
        .flat_map(|&(panel, measure)| {
            series.iter().flat_map(move |&(name, runs)| {
                runs.iter().filter_map(move |run| {
                    let y = measure(run);
                    work_precision_point(panel, name, run.seconds, y, y * spread)
                })
            })
        })
        .collect();
    BenchFigure {
        name: "work_precision_kernel",
        layout: Layout {
            panels: vec![
                work_precision_panel("a_n", "wall time [s]", "rel. error of a_n", Style::Markers),
                work_precision_panel(
                    "near bins",
                    "wall time [s]",
                    "rel. error of G near u'",
                    Style::Markers,
                ),
            ],
        },
        points,
    }
}

/// Wall time of the default sampler's scenes with and without free-flight
/// skipping (same points), and the largest difference of outgoing velocities.
fn skipping(potential: &Potential, plan: &SamplingPlan, study: &StudySettings) -> String {
    let timed = |free_flight: bool| {
        let engine = EngineSettings {
            free_flight,
            ..study.engine
        };
        let started = Instant::now();
        let records = plan.integrate_all(potential, &engine, |_| ());
        (records, started.elapsed().as_secs_f64())
    };
    let (skipped, fast) = timed(true);
    let (integrated, slow) = timed(false);
    let difference = skipped
        .iter()
        .zip(&integrated)
        .map(|(a, b)| velocity_error(&a.collision, &b.collision))
        .fold(0.0, f64::max);
    let steps = |records: &[SceneRecord]| {
        records
            .iter()
            .map(|r| f64::from(r.collision.steps))
            .sum::<f64>()
            / records.len() as f64
    };
    format!(
        "\nFree-flight skipping on the default sampler's {} scenes: {:.2} s ({:.1} steps/scene) with, {:.2} s ({:.1} steps/scene) without: x{:.2}; largest outgoing-velocity difference {:.1e} v_th.\n",
        skipped.len(),
        fast,
        steps(&skipped),
        slow,
        steps(&integrated),
        slow / fast,
        difference
    )
}
