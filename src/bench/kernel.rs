//! The kernel benchmark: shape and `a_n` errors against wall time for the
//! study's sampler variants (offset proposals, pilot, skipping).

use std::fmt::Write as _;
use std::time::Instant;

use ternary::binning::Bins;
use ternary::config::{KernelConfig, Study};
use ternary::figures::{Layout, Style};
use ternary::kernel::fit::{Protocol, Shape, Weighting, fit_kernel};
use ternary::kernel::{Draws, Event, Histogram, Target, histograms, moments};
use ternary::physics::offset_quadrature::OffsetRule;
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{
    LaunchProposal, OffsetIntegration, OffsetProposal, SamplingPlan, SceneRecord,
};
use ternary::physics::scene::{EngineSettings, Method};
use ternary::stats::Estimate;

use super::far_kernel::{far_group_error, largest_tail_z};
use super::integrators::{MAX_STEPS, velocity_error};
use super::quadrature::{inner_rule_convergence, quadrature_work_precision, run_quadrature};
use super::*;

/// What `ternary bench kernel` measures.
#[derive(Clone, Copy, Debug)]
pub struct KernelBenchOptions {
    /// The potential.
    pub potential: Potential,
    /// Randomizations (replicates) per run.
    pub randomizations: u32,
    /// Scenes per randomization in the sampler comparison.
    pub points: u32,
    /// Seed.
    pub seed: u64,
    /// The study's settings the samplers share.
    pub study: StudySettings,
}

/// The settings of a study that the kernel benchmark uses: its engine (with a
/// step budget no benchmark scene exhausts), its offset proposal (the
/// default sampler), its kernel bins and its fit range.
#[derive(Clone, Copy, Debug)]
pub struct StudySettings {
    /// Engine of every sampler.
    pub engine: EngineSettings,
    /// Offset proposal of the default sampler.
    pub proposal: OffsetProposal,
    /// Kernel window and bin width, `v_th`.
    pub window: f64,
    /// Bin width, `v_th`.
    pub bin_width: f64,
    /// Range of `|u - u'|` of the shape fit.
    pub fit_range: [f64; 2],
    /// Offset rule of the quadrature sampler.
    pub quadrature: OffsetRule,
}

impl StudySettings {
    /// The settings of `study`, or the defaults without one.
    pub fn of(study: Option<&Study>) -> StudySettings {
        let kernel = study.map_or_else(KernelConfig::default, |s| s.config.kernel.clone());
        let engine = study.map_or_else(
            || EngineSettings::new(Method::Dprkn12, 1e-12, MAX_STEPS),
            Study::engine,
        );
        StudySettings {
            engine: EngineSettings {
                max_steps: MAX_STEPS,
                ..engine
            },
            proposal: study.map_or_else(OffsetProposal::default, |s| s.config.collisions.proposal),
            window: kernel.window,
            bin_width: kernel.bin_width,
            fit_range: kernel.fit_range,
            quadrature: study.map_or_else(OffsetRule::default, |s| s.config.collisions.quadrature),
        }
    }
}

/// A sampler variant of the comparison.
pub(super) struct Variant {
    pub(super) name: &'static str,
    pub(super) proposal: OffsetProposal,
    pub(super) same_side_fraction: f64,
    pub(super) quasi_random: bool,
    pub(super) offsets: OffsetIntegration,
    /// Share of the launch coordinates drawn from the slow component.
    pub(super) slow_share: f64,
}

/// Upper end of the slow launch stratum's speeds in the benchmarks, `v_th`
/// (the study's default `collisions.slow_launch_speed`).
const SLOW_SPEED: f64 = 0.1;

/// Precision and cost of one sampler run.
#[derive(Clone, Copy)]
pub(super) struct KernelRun {
    pub(super) seconds: f64,
    pub(super) scenes: u64,
    pub(super) a_n: Estimate,
    /// `a_n` within the kernel window, `|du| <= window / 2` (the study's).
    pub(super) a_n_window: Estimate,
    /// Median relative standard error of `G` over bins with `|du|` in a band.
    pub(super) near_bins: f64,
    pub(super) far_bins: f64,
    /// Median relative standard error of the far log-spaced groups.
    pub(super) far_groups: f64,
    /// Largest `|z|` of a randomization's far-band sum (heavy tails).
    pub(super) tail_z: f64,
    /// Relative standard errors of `alpha`, `beta`, `sigma`.
    pub(super) shape: [f64; 3],
    /// Chi-square per degree of freedom of the mean shape fit.
    pub(super) chi2_per_dof: f64,
}

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

pub(super) fn plan_for(
    variant: &Variant,
    seed: u64,
    randomizations: u32,
    points: u32,
) -> SamplingPlan {
    let mut plan = SamplingPlan {
        seed,
        randomizations,
        opposite_points: 0,
        same_side_points: 0,
        proposal: variant.proposal,
        quasi_random: variant.quasi_random,
        launch: LaunchProposal {
            slow_share: variant.slow_share,
            slow_speed: if variant.slow_share > 0.0 {
                SLOW_SPEED
            } else {
                0.0
            },
            ..LaunchProposal::THERMAL
        },
        offsets: variant.offsets,
    };
    plan.allocate(points, variant.same_side_fraction);
    plan
}

/// Median relative standard error of the kernel over bins with `low <= |du| <= high`.
fn median_relative_error(replicates: &[Histogram], bins: &Bins, low: f64, high: f64) -> f64 {
    let mut errors: Vec<f64> = (0..bins.len())
        .filter(|&k| (low..=high).contains(&bins.centre(k).abs()))
        .map(|k| {
            let values: Vec<f64> = replicates
                .iter()
                .map(|h| h.self_part[k] + h.bath_part[k])
                .collect();
            let estimate = Estimate::from_replicates(&values);
            estimate.stderr / estimate.mean.abs()
        })
        .filter(|e| e.is_finite())
        .collect();
    errors.sort_by(f64::total_cmp);
    errors.get(errors.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Relative standard errors of the shape parameters `alpha`, `beta`,
/// `sigma` (the `fit` stage's fit over the default range) and the mean fit's
/// chi-square per degree of freedom.
fn shape_errors(replicates: &[Histogram], bins: &Bins, study: &StudySettings) -> ([f64; 3], f64) {
    let fine: Vec<Vec<f64>> = replicates
        .iter()
        .map(|h| h.total().iter().map(|v| v / bins.width).collect())
        .collect();
    let offsets: Vec<f64> = (0..bins.len()).map(|k| bins.centre(k)).collect();
    let [low, high] = study.fit_range;
    let protocol = Protocol {
        range: (low, high),
        weighting: Weighting::Statistical,
    };
    let fit = fit_kernel(&fine, &offsets, protocol);
    let Some(mean) = fit.mean else {
        return ([f64::NAN; 3], f64::NAN);
    };
    let parameters: [fn(&Shape) -> f64; 3] = [|s| s.alpha, |s| s.beta, |s| s.sigma];
    (
        parameters.map(|p| fit.stderr(p) / p(&mean.shape).abs()),
        mean.chi2_per_dof,
    )
}

pub(super) fn run_sampler(
    potential: &Potential,
    plan: &SamplingPlan,
    study: &StudySettings,
) -> KernelRun {
    let started = Instant::now();
    let records = plan.integrate_all(potential, &study.engine, |_| ());
    let events: Vec<Event> = records.iter().map(Event::from_record).collect();
    let scenes = events.len() as u64;
    let draws = Draws::count(&events);
    let target = Target::dilute(0.0);
    let sums = moments(
        &events,
        &target,
        &[f64::INFINITY, study.window / 2.0],
        &draws,
    );
    let a_n_at = |k: usize| {
        Estimate::from_replicates(&sums.iter().map(|r| r[k].self_variance).collect::<Vec<_>>())
    };
    let (a_n, a_n_window) = (a_n_at(0), a_n_at(1));
    let seconds = started.elapsed().as_secs_f64();
    let bins = Bins::for_window(study.window, study.bin_width);
    let replicates = histograms(&events, &target, &bins, &draws);
    let (shape, chi2_per_dof) = shape_errors(&replicates, &bins, study);
    KernelRun {
        seconds,
        scenes,
        a_n,
        a_n_window,
        near_bins: median_relative_error(&replicates, &bins, 1e-4, 2e-3),
        far_bins: median_relative_error(&replicates, &bins, 1e-2, 5e-2),
        far_groups: far_group_error(&replicates, &bins),
        tail_z: largest_tail_z(&replicates, &bins),
        shape,
        chi2_per_dof,
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

/// The leading cells of a work-precision row: points per randomization,
/// scenes, seconds, `a_n` with its absolute and relative error, near-bin error.
pub(super) fn precision_cells(points: u32, run: &KernelRun) -> String {
    format!(
        "| {points} | {} | {:.2} | {:.8e} +- {:.1e} | {:.2e} | {:.2e} |",
        run.scenes,
        run.seconds,
        run.a_n.mean,
        run.a_n.stderr,
        run.a_n.stderr / run.a_n.mean,
        run.near_bins,
    )
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
