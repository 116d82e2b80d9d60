//! One run of the kernel benchmarks' sampler and the precision figures it
//! reports (`a_n`, near and far bins, the far log groups, the heavy tails,
//! the shape): shared by the kernel, quadrature and far-kernel benchmarks,
//! which import it and not each other.

use std::time::Instant;

use ternary::binning::Bins;
use ternary::config::{KernelConfig, Study};
use ternary::kernel::fit::{Protocol, Shape, Weighting, fit_kernel};
use ternary::kernel::tail::{group_mean, sided_log_groups};
use ternary::kernel::{Draws, Event, Histogram, Target, histograms, moments};
use ternary::physics::offset_quadrature::OffsetRule;
use ternary::physics::potential::Potential;
use ternary::physics::sampling::{LaunchProposal, OffsetIntegration, OffsetProposal, SamplingPlan};
use ternary::physics::scene::{EngineSettings, Method};
use ternary::stats::Estimate;

use super::integrators::MAX_STEPS;

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
            |s| s.config.engine.study_settings(),
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

/// The sampling plan of `variant`: `points` launch pairs per randomization.
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

/// The far band of `|du|`, `v_th`.
const FAR: (f64, f64) = (0.01, 0.05);

/// Bands of `|du|` whose per-randomization sums show heavy tails.
const TAIL_BANDS: [(f64, f64); 3] = [(0.01, 0.02), (0.02, 0.03), (0.03, 0.05)];

/// Median relative error of the log-spaced groups (`kernel::tail`, as
/// `kernel_log.parquet` has them) lying within [`FAR`], both sides of `u'`.
pub(super) fn far_group_error(replicates: &[Histogram], bins: &Bins) -> f64 {
    let totals: Vec<Vec<f64>> = replicates.iter().map(Histogram::total).collect();
    let centres: Vec<f64> = (0..bins.len()).map(|k| bins.centre(k)).collect();
    let in_band = |k: usize| (FAR.0..=FAR.1).contains(&centres[k].abs());
    let mut errors: Vec<f64> = sided_log_groups(&centres)
        .into_iter()
        .filter(|(_, members)| members.iter().all(|&k| in_band(k)))
        .map(|(_, members)| {
            let group = group_mean(&totals, &members);
            group.stderr / group.mean.abs()
        })
        .collect();
    errors.sort_by(f64::total_cmp);
    errors.get(errors.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The largest `|z|` of a randomization's sum over a band of
/// [`TAIL_BANDS`] (both sides) against the randomizations' mean and spread.
/// Gaussian sums give ~2.5 for 16 randomizations and 3 bands; `R`
/// randomizations cannot exceed `(R - 1) / sqrt(R)` (3.75 for 16), which one
/// outlier carrying the whole spread reaches.
pub(super) fn largest_tail_z(replicates: &[Histogram], bins: &Bins) -> f64 {
    let mut largest: f64 = 0.0;
    for (low, high) in TAIL_BANDS {
        let sums: Vec<f64> = replicates
            .iter()
            .map(|h| {
                let total = h.total();
                (0..bins.len())
                    .filter(|&k| (low..high).contains(&bins.centre(k).abs()))
                    .map(|k| total[k])
                    .sum()
            })
            .collect();
        let estimate = Estimate::from_replicates(&sums);
        let spread = estimate.stderr * (sums.len() as f64).sqrt();
        for sum in sums {
            largest = largest.max((sum - estimate.mean).abs() / spread);
        }
    }
    largest
}
