//! Detailed balance far from `u' = 0` (the paper's pair `G(-3.00 -> -2.96) /
//! G(-2.96 -> -3.00)`): its precision per wall second for the sweep's scene
//! sets, sampled offsets against the offset quadrature and launch proposals
//! of several reaches, each run in the same process.

use std::fmt::Write as _;
use std::time::Instant;

use ternary::binning::Bins;
use ternary::kernel::{Draws, Event, Target, pilot_same_side_fraction, self_bin};
use ternary::physics::launch::thermal_density;
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{LaunchProposal, OffsetIntegration, SamplingPlan};
use ternary::stats::Estimate;

use super::StudySettings;

/// What `ternary bench balance` measures.
#[derive(Clone, Copy, Debug)]
pub struct BalanceBenchOptions {
    /// The potential.
    pub potential: Potential,
    /// Randomizations (replicates) per run.
    pub randomizations: u32,
    /// Velocity `a` of the pair, `v_th`.
    pub from: f64,
    /// Separation `b - a`, `v_th`.
    pub separation: f64,
    /// Bin width of the two kernels, `v_th`.
    pub bin_width: f64,
    /// Seed.
    pub seed: u64,
    /// The study's engine, offset proposal and rule.
    pub study: StudySettings,
}

/// One scene set of the comparison.
struct Variant {
    name: String,
    launch: LaunchProposal,
    offsets: OffsetIntegration,
    /// Points per randomization: scenes, or launch pairs under the quadrature.
    points: u32,
    /// `u'` whose self variance rate the pilot splits the strata for.
    pilot_at: f64,
}

/// The pair measured by one variant.
struct BalanceRun {
    scenes: usize,
    seconds: f64,
    same_side_fraction: f64,
    forward: Estimate,
    backward: Estimate,
    /// Ratio with the replicates' correlation kept.
    paired: Estimate,
    /// Ratio with the two kernels treated as independent (as the sweep table had it until 2026-11-25).
    independent: Estimate,
}

fn run(variant: &Variant, options: &BalanceBenchOptions) -> BalanceRun {
    let started = Instant::now();
    let mut plan = SamplingPlan {
        seed: options.seed,
        randomizations: options.randomizations,
        opposite_points: 0,
        same_side_points: 0,
        proposal: options.study.proposal,
        quasi_random: true,
        launch: variant.launch,
        offsets: variant.offsets,
    };
    let pilot_points = 1024;
    let fraction = pilot_same_side_fraction(
        &plan,
        &options.potential,
        &options.study.engine,
        &[Target::dilute(variant.pilot_at)],
        pilot_points,
    )
    .unwrap_or(0.15);
    plan.allocate(variant.points, fraction);
    let records = plan.integrate_all(&options.potential, &options.study.engine, |_| ());
    let events: Vec<Event> = records.iter().map(Event::from_record).collect();
    let draws = Draws::count(&events);
    let width = options.bin_width;
    let steps = (options.separation / width).round() as usize;
    let bins = Bins::for_window(2.0 * options.separation + 4.0 * width, width);
    let (a, b) = (options.from, options.from + steps as f64 * width);
    let kernel = |from: f64, k: usize| -> Vec<f64> {
        self_bin(&events, &Target::dilute(from), &bins, k, &draws)
            .iter()
            .map(|v| v / width)
            .collect()
    };
    let there = kernel(a, bins.half_bins + steps);
    let back = kernel(b, bins.half_bins - steps);
    let seconds = started.elapsed().as_secs_f64();
    let (forward, backward) = (
        Estimate::from_replicates(&there),
        Estimate::from_replicates(&back),
    );
    BalanceRun {
        scenes: events.len(),
        seconds,
        same_side_fraction: fraction,
        forward,
        backward,
        paired: Estimate::paired_ratio(&there, &back),
        independent: forward.ratio(backward),
    }
}

/// The comparison table: today's sweep set (sampled offsets, launch mixture
/// at `0, +-2`) against the quadrature with mixtures reaching `a`.
///
/// Fails, naming the scene set, where a ratio or its error is not a finite
/// number (no scene carried the particle between the pair's bins: a wide
/// separation with few randomizations).
pub fn balance(options: &BalanceBenchOptions) -> Result<String, String> {
    let sampled = OffsetIntegration::Sampled;
    let quadrature = OffsetIntegration::Quadrature(options.study.quadrature);
    let mixture = |spread: f64| LaunchProposal {
        spread,
        ..LaunchProposal::THERMAL
    };
    let at_pair = LaunchProposal {
        shift: options.from,
        ..LaunchProposal::THERMAL
    };
    let pairs = |scenes: u32| scenes / options.study.quadrature.nodes();
    let mut variants = vec![Variant {
        name: "sampled offsets, launch mixture 0, +-2 (the sweep set today)".into(),
        launch: mixture(2.0),
        offsets: sampled,
        points: 65536,
        pilot_at: 0.0,
    }];
    for (name, launch, pilot_at) in [
        ("quadrature, launch mixture 0, +-2", mixture(2.0), 0.0),
        (
            "quadrature, launch mixture 0, +-3, strata piloted at a",
            mixture(3.0),
            options.from,
        ),
        ("quadrature, launch density at a", at_pair, options.from),
    ] {
        for points in [1024, 4096] {
            variants.push(Variant {
                name: format!("{name} ({points} pairs)"),
                launch,
                offsets: quadrature,
                points,
                pilot_at,
            });
        }
    }
    let mut out = format!(
        "### Detailed balance at a = {}, b - a = {}, {} (bins {}, {} randomizations, seed {})\n\nExpected ratio f0(b) / f0(a) = {:.4}. FOM = 1 / (variance of the paired ratio x seconds); gains against the first row, all in this run; seconds include the pilot. The sampled row draws {} scenes per randomization (~{} pairs' worth).\n\n",
        options.from,
        options.separation,
        options.potential.id(),
        options.bin_width,
        options.randomizations,
        options.seed,
        thermal_density(options.from + options.separation) / thermal_density(options.from),
        65536,
        pairs(65536),
    );
    out.push_str("| scene set | scenes | seconds | same-side share | G(a -> b) | G(b -> a) | ratio (paired) | ratio (independent) | gain |\n|---|---|---|---|---|---|---|---|---|\n");
    let mut baseline: Option<f64> = None;
    for variant in &variants {
        let result = run(variant, options);
        let merit = 1.0 / (result.paired.stderr.powi(2) * result.seconds);
        if !(merit.is_finite() && result.independent.stderr.is_finite()) {
            return Err(format!(
                "{}: the ratio G(a -> b) / G(b -> a) is {} +- {} (G(a -> b) = {}, G(b -> a) = {}): too few scenes join the bins {} apart; use a smaller --separation or more --randomizations",
                variant.name,
                result.paired.mean,
                result.paired.stderr,
                result.forward.mean,
                result.backward.mean,
                options.separation
            ));
        }
        let base = *baseline.get_or_insert(merit);
        let _ = writeln!(
            out,
            "| {} | {} | {:.1} | {:.3} | {:.4} +- {:.4} | {:.4} +- {:.4} | {:.4} +- {:.4} | {:.4} +- {:.4} | x{:.1} |",
            variant.name,
            result.scenes,
            result.seconds,
            result.same_side_fraction,
            result.forward.mean,
            result.forward.stderr,
            result.backward.mean,
            result.backward.stderr,
            result.paired.mean,
            result.paired.stderr,
            result.independent.mean,
            result.independent.stderr,
            merit / base,
        );
    }
    Ok(out)
}
