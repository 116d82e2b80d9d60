//! The integrator benchmark: error of the final velocities against CPU
//! time for each method at a ladder of tolerances.

use std::fmt::Write as _;
use std::time::Instant;

use ternary::figures::{Layout, Style};
use ternary::physics::potential::Potential;
use ternary::physics::scan::{TIGHTEST_TOLERANCE, thermal_scenes};
use ternary::physics::scene::{Collision, EngineSettings, FreeLine, Method, collide, collide_all};

use super::*;

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
pub(super) const MAX_STEPS: u32 = 1_000_000;

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

/// The scenes' collisions, and the best of `repeats` wall times of `integrate`.
pub(super) fn timed(
    repeats: usize,
    integrate: impl Fn() -> Vec<Collision>,
) -> (Vec<Collision>, f64) {
    let mut best = f64::INFINITY;
    let mut collisions = Vec::new();
    for _ in 0..repeats {
        let started = Instant::now();
        collisions = integrate();
        best = best.min(started.elapsed().as_secs_f64());
    }
    (collisions, best)
}

/// All scenes as the pipeline integrates them: interleaved ([`collide_all`]).
fn integrate_all(
    potential: &Potential,
    settings: &EngineSettings,
    scenes: &[[FreeLine; 3]],
) -> (Vec<Collision>, f64) {
    timed(REPEATS, || collide_all(potential, settings, scenes))
}

/// The scenes integrated one by one ([`collide`]), in order.
pub(super) fn one_by_one(
    potential: &Potential,
    settings: &EngineSettings,
    scenes: &[[FreeLine; 3]],
) -> Vec<Collision> {
    scenes
        .iter()
        .map(|&lines| collide(potential, settings, lines))
        .collect()
}

/// Tolerances at which the interleaved scenes are timed against the same scenes one by one.
const INTERLEAVING_TOLERANCES: [f64; 3] = [1e-6, 1e-10, 1e-12];

/// DPRKN12's scenes interleaved ([`collide_all`]) against one by one ([`collide`]), in one
/// run: the time ratio, and whether every outgoing velocity agrees to the bit.
fn interleaving(potential: &Potential, scenes: &[[FreeLine; 3]]) -> String {
    let mut out = String::from(
        "\nDPRKN12 scenes interleaved (as the pipeline integrates them) against one by one:\n\n\
         | tolerance | one by one us/scene | interleaved us/scene | ratio | same bits |\n\
         |---|---|---|---|---|\n",
    );
    for tolerance in INTERLEAVING_TOLERANCES {
        let settings = EngineSettings::new(Method::Dprkn12, tolerance, MAX_STEPS);
        let (alone, alone_seconds) = timed(REPEATS, || one_by_one(potential, &settings, scenes));
        let (together, together_seconds) = integrate_all(potential, &settings, scenes);
        let same = alone.iter().zip(&together).all(|(a, b)| {
            let bits = |c: &Collision| c.outgoing.map(f64::to_bits);
            bits(a) == bits(b) && a.evaluations == b.evaluations
        });
        let per_scene = |seconds: f64| 1e6 * seconds / scenes.len() as f64;
        let _ = writeln!(
            out,
            "| {tolerance:.0e} | {:.2} | {:.2} | {:.2} | {} |",
            per_scene(alone_seconds),
            per_scene(together_seconds),
            together_seconds / alone_seconds,
            if same { "yes" } else { "no" }
        );
    }
    out
}

/// Largest outgoing-velocity difference between two results of one scene.
pub(super) fn velocity_error(a: &Collision, b: &Collision) -> f64 {
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
    out.push_str(&interleaving(&potential, &scenes));
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
