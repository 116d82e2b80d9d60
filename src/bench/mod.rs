//! Work-precision benchmarks (not tests): error against CPU time, measured in
//! one process so that ratios between methods are meaningful. Results are
//! recorded in docs/benchmarks.md with the command that produced them. Part of
//! the command line, not of the library; the kernel benchmark takes the
//! study's engine, offset proposal, bins and fit range from `--config`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::SeedableRng;
use rand::rngs::StdRng;
use rayon::prelude::*;

use ternary::binning::Bins;
use ternary::config::{KernelConfig, Study};
use ternary::figures::{Axis, Layout, Panel, Point, Style, render};
use ternary::kernel::fit::{Protocol, Shape, Weighting, fit_kernel};
use ternary::kernel::{Draws, Event, Histogram, Target, histograms, moments};
use ternary::physics::offset_quadrature::{OffsetIntegral, OffsetRule};
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{
    LaunchProposal, OffsetIntegration, OffsetProposal, SamplingPlan, SceneRecord,
};
use ternary::physics::scan::{LaunchPair, TIGHTEST_TOLERANCE, thermal_scenes};
use ternary::physics::scene::{Collision, EngineSettings, FreeLine, Method, collide};
use ternary::stats::Estimate;

mod balance;
pub use balance::{BalanceBenchOptions, balance};

/// A benchmark's work-precision figure: error against cost, drawn like the
/// study's figures (SVG and PNG, one column and screen size).
pub struct BenchFigure {
    /// File stem, e.g. `work_precision_kernel`.
    pub name: &'static str,
    /// Axes and styles.
    pub layout: Layout,
    /// The measured points.
    pub points: Vec<Point>,
}

impl BenchFigure {
    /// Writes the figure's files into `dir` (created if missing); their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        render(self.name, &self.layout, &self.points)?
            .into_iter()
            .map(|(file, bytes)| {
                let path = dir.join(file);
                std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
                Ok(path)
            })
            .collect()
    }
}

/// A log-log work-precision panel: `y` against seconds.
fn work_precision_panel(
    name: &'static str,
    x: &'static str,
    y: &'static str,
    style: Style,
) -> Panel {
    // Errors span up to ten decades (integrator tolerances 1e-5..1e-14).
    let y = Axis {
        decades: 12,
        ..Axis::log(y)
    };
    Panel::new(name, Axis::log(x), y, vec![("", style)])
}

/// A point of `series` in `panel`; only positive errors can be drawn on log axes.
fn work_precision_point(panel: &str, series: &str, x: f64, y: f64, y_error: f64) -> Option<Point> {
    (x > 0.0 && y > 0.0).then(|| Point {
        panel: panel.to_string(),
        series: series.to_string(),
        x,
        y,
        y_error,
    })
}

/// What `ternary bench integrators` measures.
#[derive(Clone, Copy, Debug)]
pub struct WorkPrecisionOptions {
    /// Exponent of the inverse power law.
    pub n: f64,
    /// Number of thermal scenes.
    pub scenes: usize,
    /// Seed of the scene sample.
    pub seed: u64,
}

/// Tolerances swept for every method.
const TOLERANCES: [f64; 10] = [
    1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14,
];
/// Timing repeats; the fastest counts (least disturbed by other load).
const REPEATS: usize = 3;
/// Step budget generous enough that no benchmark scene fails for lack of steps.
const MAX_STEPS: u32 = 1_000_000;

/// One method at one tolerance over the whole sample.
struct Measurement {
    method: Method,
    tolerance: f64,
    micros_per_scene: f64,
    evaluations_per_scene: f64,
    max_error: f64,
    median_error: f64,
    failures: usize,
}

fn integrate_all(
    potential: &Potential,
    settings: &EngineSettings,
    scenes: &[[FreeLine; 3]],
) -> (Vec<Collision>, f64) {
    let mut best = f64::INFINITY;
    let mut collisions = Vec::new();
    for _ in 0..REPEATS {
        let started = Instant::now();
        collisions = scenes
            .iter()
            .map(|&lines| collide(potential, settings, lines))
            .collect();
        best = best.min(started.elapsed().as_secs_f64());
    }
    (collisions, best)
}

/// Largest outgoing-velocity difference between two results of one scene.
fn velocity_error(a: &Collision, b: &Collision) -> f64 {
    (0..3)
        .map(|k| (a.outgoing[k] - b.outgoing[k]).abs())
        .fold(0.0, f64::max)
}

fn measure(
    potential: &Potential,
    method: Method,
    tolerance: f64,
    scenes: &[[FreeLine; 3]],
    reference: &[Collision],
) -> Measurement {
    let settings = EngineSettings::new(method, tolerance, MAX_STEPS);
    let (collisions, seconds) = integrate_all(potential, &settings, scenes);
    let failures = collisions.iter().filter(|c| c.outcome.is_failure()).count();
    let mut errors: Vec<f64> = collisions
        .iter()
        .zip(reference)
        .filter(|(c, _)| !c.outcome.is_failure())
        .map(|(c, r)| velocity_error(c, r))
        .collect();
    errors.sort_by(f64::total_cmp);
    let evaluations: f64 = collisions.iter().map(|c| f64::from(c.evaluations)).sum();
    Measurement {
        method,
        tolerance,
        micros_per_scene: 1e6 * seconds / scenes.len() as f64,
        evaluations_per_scene: evaluations / scenes.len() as f64,
        max_error: errors.last().copied().unwrap_or(f64::NAN),
        median_error: errors.get(errors.len() / 2).copied().unwrap_or(f64::NAN),
        failures,
    }
}

/// Runs the sweep and returns a Markdown report with the equal-error speedups
/// of the default method over the baseline.
pub fn integrators(options: &WorkPrecisionOptions) -> (String, BenchFigure) {
    let potential = Potential::inverse_power(options.n);
    let scenes = thermal_scenes(options.scenes, options.seed);
    let reference_of = |method| {
        let settings = EngineSettings::new(method, TIGHTEST_TOLERANCE, MAX_STEPS);
        scenes
            .iter()
            .map(|&lines| collide(&potential, &settings, lines))
            .collect::<Vec<_>>()
    };
    let reference = reference_of(Method::Dprkn12);
    let check = reference_of(Method::Dop853);
    let reference_spread = reference
        .iter()
        .zip(&check)
        .map(|(a, b)| velocity_error(a, b))
        .fold(0.0, f64::max);
    let mut measurements = Vec::new();
    for method in Method::ALL {
        for tolerance in TOLERANCES {
            measurements.push(measure(&potential, method, tolerance, &scenes, &reference));
        }
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "### Integrators: n = {}, {} thermal scenes (seed {})\n",
        options.n, options.scenes, options.seed
    );
    let _ = writeln!(
        out,
        "Reference: dprkn12 at tolerance {TIGHTEST_TOLERANCE:e}; dop853 at the same tolerance differs from it by at most {reference_spread:.1e} v_th (the reference's own error).\n"
    );
    let _ = writeln!(
        out,
        "| method | tolerance | us/scene | force evaluations/scene | max error [v_th] | median error [v_th] | failed |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    for m in &measurements {
        let _ = writeln!(
            out,
            "| {} | {:.0e} | {:.2} | {:.0} | {:.1e} | {:.1e} | {} |",
            m.method.name(),
            m.tolerance,
            m.micros_per_scene,
            m.evaluations_per_scene,
            m.max_error,
            m.median_error,
            m.failures
        );
    }
    for challenger in [Method::Dprkn12, Method::Dop853] {
        out.push_str(&speedups(&measurements, challenger, Method::Dopri5));
    }
    let figure = BenchFigure {
        name: "work_precision_integrators",
        layout: Layout {
            panels: vec![work_precision_panel(
                "median error",
                "wall time per scene [us]",
                "median velocity error [v_th]",
                Style::Line,
            )],
        },
        points: measurements
            .iter()
            .filter(|m| m.failures == 0)
            .filter_map(|m| {
                work_precision_point(
                    "median error",
                    m.method.name(),
                    m.micros_per_scene,
                    m.median_error,
                    0.0,
                )
            })
            .collect(),
    };
    (out, figure)
}

/// For each baseline tolerance: the cheapest challenger run whose max error is
/// no larger, and the ratio of times per scene (a lower bound on the speedup
/// at equal error, since the challenger's error is at most the baseline's).
fn speedups(measurements: &[Measurement], challenger: Method, baseline: Method) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\nSpeed at equal or better max error, {} against {}:\n",
        challenger.name(),
        baseline.name()
    );
    let _ = writeln!(
        out,
        "| {b} tolerance | {b} max error | {b} us/scene | {c} tolerance | {c} max error | {c} us/scene | speedup |",
        b = baseline.name(),
        c = challenger.name()
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    for base in measurements
        .iter()
        .filter(|m| m.method == baseline && m.failures == 0)
    {
        let best = measurements
            .iter()
            .filter(|m| m.method == challenger && m.failures == 0 && m.max_error <= base.max_error)
            .min_by(|a, b| a.micros_per_scene.total_cmp(&b.micros_per_scene));
        if let Some(best) = best {
            let _ = writeln!(
                out,
                "| {:.0e} | {:.1e} | {:.2} | {:.0e} | {:.1e} | {:.2} | {:.1}x |",
                base.tolerance,
                base.max_error,
                base.micros_per_scene,
                best.tolerance,
                best.max_error,
                best.micros_per_scene,
                base.micros_per_scene / best.micros_per_scene
            );
        }
    }
    out
}

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
struct Variant {
    name: &'static str,
    proposal: OffsetProposal,
    same_side_fraction: f64,
    quasi_random: bool,
    offsets: OffsetIntegration,
}

/// Precision and cost of one sampler run.
#[derive(Clone, Copy)]
struct KernelRun {
    seconds: f64,
    scenes: u64,
    a_n: Estimate,
    /// Median relative standard error of `G` over bins with `|du|` in a band.
    near_bins: f64,
    far_bins: f64,
    /// Relative standard errors of `alpha`, `beta`, `sigma`.
    shape: [f64; 3],
    /// Chi-square per degree of freedom of the mean shape fit.
    chi2_per_dof: f64,
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

fn plan_for(variant: &Variant, seed: u64, randomizations: u32, points: u32) -> SamplingPlan {
    let mut plan = SamplingPlan {
        seed,
        randomizations,
        opposite_points: 0,
        same_side_points: 0,
        proposal: variant.proposal,
        quasi_random: variant.quasi_random,
        launch: LaunchProposal::THERMAL,
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

fn run_sampler(potential: &Potential, plan: &SamplingPlan, study: &StudySettings) -> KernelRun {
    let started = Instant::now();
    let records = plan.integrate_all(potential, &study.engine, |_| ());
    let events: Vec<Event> = records.iter().map(Event::from_record).collect();
    let scenes = events.len() as u64;
    let draws = Draws::count(&events);
    let target = Target::dilute(0.0);
    let sums = moments(&events, &target, &[f64::INFINITY], &draws);
    let a_n =
        Estimate::from_replicates(&sums.iter().map(|r| r[0].self_variance).collect::<Vec<_>>());
    let seconds = started.elapsed().as_secs_f64();
    let bins = Bins::for_window(study.window, study.bin_width);
    let replicates = histograms(&events, &target, &bins, &draws);
    let (shape, chi2_per_dof) = shape_errors(&replicates, &bins, study);
    KernelRun {
        seconds,
        scenes,
        a_n,
        near_bins: median_relative_error(&replicates, &bins, 1e-4, 2e-3),
        far_bins: median_relative_error(&replicates, &bins, 1e-2, 5e-2),
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
        },
        Variant {
            name: "+ mixture offset proposal",
            proposal: defaults,
            same_side_fraction: 0.5,
            quasi_random: false,
            offsets: OffsetIntegration::Sampled,
        },
        Variant {
            name: "+ strata 85/15 (opposite/same side)",
            proposal: defaults,
            same_side_fraction: 0.15,
            quasi_random: false,
            offsets: OffsetIntegration::Sampled,
        },
        Variant {
            name: "+ scrambled Sobol' points",
            proposal: defaults,
            same_side_fraction: 0.15,
            quasi_random: true,
            offsets: OffsetIntegration::Sampled,
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
        ternary::kernel::pilot_same_side_fraction(&probe, &potential, &engine, &target, 1024)
            .unwrap_or(0.15);
    let pilot_seconds = started.elapsed().as_secs_f64();
    let piloted = Variant {
        name: "+ strata from a pilot (default)",
        proposal: defaults,
        same_side_fraction: fraction,
        quasi_random: true,
        offsets: OffsetIntegration::Sampled,
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

/// The sizes of a work-precision table: `points * num / den` for each
/// `(num, den)`, at least 16, each once (the default 4096 points gives 2^10
/// to 2^16 sampled scenes and 64 to 12288 quadrature pairs).
fn work_precision_sizes(points: u32, ratios: &[(u32, u32)]) -> Vec<u32> {
    let mut sizes: Vec<u32> = ratios
        .iter()
        .map(|&(num, den)| (points * num / den).max(16))
        .collect();
    sizes.dedup();
    sizes
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
fn precision_cells(points: u32, run: &KernelRun) -> String {
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

/// A quadrature run and the time its pilot took (included in `run.seconds`).
struct QuadratureRun {
    run: KernelRun,
    pilot_seconds: f64,
}

/// The quadrature sampler with `pairs` launch pairs per randomization, the
/// strata split by its own pilot (timed with the run).
fn run_quadrature(
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
        &Target::dilute(0.0),
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
fn quadrature_work_precision(
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
fn inner_rule_convergence(potential: &Potential, study: &StudySettings, seed: u64) -> String {
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

/// What `ternary bench md` measures: one ring of the published configuration
/// (physics.md §7), advanced by cluster stepping and by whole-ring stepping.
#[derive(Clone, Copy, Debug)]
pub struct MdBenchOptions {
    /// Particles `N`.
    pub particles: usize,
    /// Ring radius, um.
    pub radius_um: f64,
    /// Temperature, eV.
    pub kt_ev: f64,
    /// Final time, ns.
    pub final_time_ns: f64,
    /// Neighbours on each side that interact.
    pub neighbours: usize,
    /// Seed of the initial state.
    pub seed: u64,
}

/// One way of advancing the ring, timed.
struct MdRun {
    seconds: f64,
    energy_error: f64,
    evaluations: u64,
    particle_forces: u64,
    velocities: Vec<f64>,
}

/// `ternary bench md`: wall time and energy error of one run of `N` electrons
/// (`n = 6`, `l0 = 1 um`, `eps = 1 eV`) to the final time, cluster stepping
/// against whole-ring stepping at the same tolerances, in one process.
pub fn md(options: &MdBenchOptions) -> Result<String, String> {
    use ternary::physics::clusters::ClusterRing;
    use ternary::physics::potential::InverseIntegerPower;
    use ternary::physics::ring::{Reach, RingForces, RingState, evolve, thermal_start};
    use ternary::physics::units::{Mass, PhysicalGas};

    let gas = PhysicalGas {
        l0_um: 1.0,
        eps_ev: 1.0,
        kt_ev: options.kt_ev,
        mass: Mass::ElectronMasses(1.0),
        density_per_um: 0.0,
    };
    let length = gas.length_unit_um(Some(6.0));
    let circumference = 2.0 * std::f64::consts::PI * options.radius_um / length;
    let duration = options.final_time_ns / gas.time_unit_ns(Some(6.0));
    let forces = RingForces {
        potential: InverseIntegerPower::<6>,
        circumference,
        reach: Reach::Neighbours(options.neighbours),
    };
    let mut rng = StdRng::seed_from_u64(options.seed);
    let (positions, velocities) =
        thermal_start(&forces, options.particles, Some(0.0), &mut rng, 1000)
            .map_err(|error| error.to_string())?;
    let start = RingState::new(&positions, &velocities, circumference);
    let energy = start.energy(&forces);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Ring of N = {} (n = 6, R = {} um, kT = {} eV, electrons): C = {circumference:.0} l, rho l = {:.2e}, t_f = {} ns = {duration:.4e} l/v_th, {} neighbours per side.\n",
        options.particles,
        options.radius_um,
        options.kt_ev,
        (options.particles - 1) as f64 / circumference,
        options.final_time_ns,
        options.neighbours
    );
    let _ = writeln!(
        out,
        "| stepping | tolerance | wall s | relative energy error | force sweeps | pair forces |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    for tolerance in [1e-10, 1e-12] {
        let clock = Instant::now();
        let mut ring = ClusterRing::new(forces, &positions, &velocities, tolerance);
        ring.advance(duration, u64::MAX)
            .map_err(|error| format!("cluster stepping: {error}"))?;
        let cluster = MdRun {
            seconds: clock.elapsed().as_secs_f64(),
            energy_error: (ring.energy() - energy).abs() / energy,
            evaluations: ring.work.evaluations,
            particle_forces: ring.pair_forces,
            velocities: ring.velocities.clone(),
        };
        let clock = Instant::now();
        let mut whole = start.clone();
        let work = evolve(&forces, &mut whole, duration, tolerance, u64::MAX)
            .map_err(|error| format!("whole-ring stepping: {error}"))?;
        let global = MdRun {
            seconds: clock.elapsed().as_secs_f64(),
            energy_error: (whole.energy(&forces) - energy).abs() / energy,
            evaluations: work.evaluations,
            particle_forces: work.evaluations * (options.particles * options.neighbours) as u64,
            velocities: whole.velocities(),
        };
        for (name, run) in [("cluster", &cluster), ("whole ring", &global)] {
            let _ = writeln!(
                out,
                "| {name} | {tolerance:.0e} | {:.2} | {:.1e} | {} | {:.2e} |",
                run.seconds, run.energy_error, run.evaluations, run.particle_forces as f64
            );
        }
        rows.push((tolerance, cluster, global));
    }
    let _ = writeln!(out);
    for (tolerance, cluster, global) in &rows {
        let largest = cluster
            .velocities
            .iter()
            .zip(&global.velocities)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "tolerance {tolerance:.0e}: cluster stepping {:.1}x faster than whole-ring stepping; largest final velocity difference {largest:.1e} v_th",
            global.seconds / cluster.seconds
        );
    }
    Ok(out)
}
