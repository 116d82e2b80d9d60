//! Molecular dynamics against the Boltzmann evolution (physics.md §7, §8):
//! the Boltzmann `h(u, t_f)` of the translation-invariant kernel on a ring's
//! bins, window variances of `h`, the self kernel's window variance rate
//! averaged over thermal starts (the thermal estimator's counterpart), and
//! the finite-size ratios of MD to Boltzmann, and the goodness of fit of
//! both MD estimators of `h` against a reference ([`goodness`], [`collapse`]):
//! the chi-square with the covariance MD would have if it followed the
//! reference (`physics::md::tagged_model`, `published_model`), and with the
//! runs' own errors (`stats::chi_square`).
//!
//! Owns the arithmetic of the comparison; not the MD runs (`physics::md`),
//! the kernel (`kernel`), the evolution (`evolve`) nor the tables (`stages::compare`).
//! Pure math: no IO. Units: velocities in `v_th`, `h` per `v_th`, rates in
//! `rho^2 l v_th`, times in `1 / (rho^2 l v_th)`.

use crate::binning::Bins;
use crate::evolve::convolution::{self, overlap_rebin};
use crate::kernel::{Draws, Event, Target, moments};
use crate::linalg::simpson_weight;
use crate::physics::launch::thermal_density;
use crate::physics::md::{THERMAL_BAND, published_model, tagged_model};
use crate::stats::{
    ChiSquare, CountModel, Estimate, MIN_TEST_DOF, MINIMUM_EXPECTED_COUNT, Replicated, chi_square,
};
use crate::thresholds::{REJECTED_P, REJECTED_Z};

/// Simpson intervals of the average over thermal starts in
/// `[-THERMAL_BAND, THERMAL_BAND]` (step 0.25).
pub const THERMAL_INTERVALS: usize = 24;

/// A ring's estimator bins: centres relative to `u'` and their width, `v_th`.
#[derive(Clone, Copy, Debug)]
pub struct RingBins<'a> {
    /// Bin centres `u - u'`.
    pub du: &'a [f64],
    /// Bin width.
    pub width: f64,
    /// Total width of the ring's estimator window.
    pub window: f64,
}

/// Boltzmann `h(u, t)` from `delta(u - u')` under the translation-invariant
/// kernel `rates` (binned on `width`, see `evolve::convolution`) at scaled
/// time `time`, exact in Fourier space, on the ring's bins (bin masses over
/// the bin width: `1/v_th`), for the mean kernel and every leave-one-out set.
pub fn boltzmann_on_bins(
    rates: &Replicated<Vec<f64>>,
    width: f64,
    time: f64,
    bins: RingBins,
) -> Replicated<Vec<f64>> {
    let size = convolution::periodic_size(&rates.full, width, time)
        .max((4.0 * bins.window / width) as usize)
        .next_power_of_two();
    rates.map(|g| {
        let h = &convolution::evolve(g, size, &[time])[0];
        overlap_rebin(h, width, size / 2, bins.du, bins.width)
            .iter()
            .map(|m| m / bins.width)
            .collect::<Vec<f64>>()
    })
}

/// Window variance `sum_k h_k du_k^2 width` of a binned `h` (per `v_th`), `v_th^2`.
pub fn window_variance(h: &[f64], du: &[f64], width: f64) -> f64 {
    h.iter().zip(du).map(|(h, du)| h * du * du * width).sum()
}

/// The thermal average over starts `u0` in `[-THERMAL_BAND, THERMAL_BAND]`
/// of every component of `value(u0)` with weight `f0(u0)`, normalized on the
/// band: `sum_j s_j f0(u_j) v(u_j) / sum_j s_j f0(u_j)`, `s_j` the composite
/// Simpson weights of [`THERMAL_INTERVALS`] intervals.
pub fn thermal_average(value: impl Fn(f64) -> Vec<f64>) -> Vec<f64> {
    let step = 2.0 * THERMAL_BAND / THERMAL_INTERVALS as f64;
    let mut average: Vec<f64> = Vec::new();
    let mut norm = 0.0;
    for j in 0..=THERMAL_INTERVALS {
        let u = -THERMAL_BAND + step * j as f64;
        let weight = simpson_weight(j, THERMAL_INTERVALS) * thermal_density(u);
        norm += weight;
        let values = value(u);
        average.resize(values.len(), 0.0);
        average
            .iter_mut()
            .zip(values)
            .for_each(|(a, v)| *a += weight * v);
    }
    average.iter_mut().for_each(|a| *a /= norm);
    average
}

/// Per truncation edge (a ring's half window), per replicate: the self
/// kernel's window variance rate `int_{|x| <= edge} G_self x^2 dx` averaged
/// over thermal starts ([`thermal_average`]), `rho^2 l v_th`. `target` gives
/// everything but `u'`.
pub fn thermal_window_variance_rates(
    events: &[Event],
    draws: &Draws,
    target: &Target,
    edges: &[f64],
) -> Vec<Vec<f64>> {
    let replicates = draws.replicates();
    let averaged = thermal_average(|u_prime| {
        let target = Target { u_prime, ..*target };
        let sums = moments(events, &target, edges, draws);
        (0..edges.len())
            .flat_map(|ring| {
                sums.iter()
                    .map(move |replicate| replicate[ring].self_variance)
            })
            .collect()
    });
    averaged.chunks(replicates).map(<[f64]>::to_vec).collect()
}

/// An MD window variance against Boltzmann's, `v_th^2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VarianceRatio {
    /// Molecular dynamics (standard error over runs).
    pub md: Estimate,
    /// Boltzmann (error over the kernel's randomizations).
    pub boltzmann: Estimate,
    /// `md / boltzmann`: 1 at large `N` and small `rho l`.
    pub ratio: Estimate,
}

impl VarianceRatio {
    /// The two variances and their ratio.
    pub fn new(md: Estimate, boltzmann: Estimate) -> VarianceRatio {
        VarianceRatio {
            md,
            boltzmann,
            ratio: md.ratio(boltzmann),
        }
    }
}

/// A ring's window variances `sum (u - u')^2 h du` by each MD estimator,
/// `v_th^2`, with standard errors over runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowVariances {
    /// The published estimator (background subtracted).
    pub published: Estimate,
    /// The tagged estimator (lineages starting near `u'`).
    pub tagged: Estimate,
    /// The thermal estimator (every lineage).
    pub thermal: Estimate,
}

/// The finite-size and density comparison of one ring at scaled time `time`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FiniteSize {
    /// The published estimator against the window variance of the Boltzmann
    /// `h` on the ring's bins (jackknife): the same `h` as the tagged one's,
    /// with the background's noise.
    pub published: VarianceRatio,
    /// The tagged estimator (starts near `u'`) against the window variance
    /// of the Boltzmann `h` on the ring's bins (jackknife).
    pub tagged: VarianceRatio,
    /// The thermal estimator (every start) against `time` times the
    /// thermally averaged rate per kernel replicate (first order in `Gamma t`).
    pub thermal: VarianceRatio,
}

/// [`FiniteSize`] from the ring's window variances (`md`), its Boltzmann
/// `h` ([`boltzmann_on_bins`]) and its thermal rate per kernel replicate
/// ([`thermal_window_variance_rates`]).
pub fn finite_size(
    md: WindowVariances,
    boltzmann: &Replicated<Vec<f64>>,
    bins: RingBins,
    thermal_rates: &[f64],
    time: f64,
) -> FiniteSize {
    let tagged_boltzmann = boltzmann.scalar(|h| window_variance(h, bins.du, bins.width));
    let thermal_boltzmann =
        Estimate::from_replicates(&thermal_rates.iter().map(|r| r * time).collect::<Vec<f64>>());
    FiniteSize {
        published: VarianceRatio::new(md.published, tagged_boltzmann),
        tagged: VarianceRatio::new(md.tagged, tagged_boltzmann),
        thermal: VarianceRatio::new(md.thermal, thermal_boltzmann),
    }
}

/// A ring's two MD estimates of `h` (per `v_th`) on its estimator bins,
/// and what their models under a reference need.
#[derive(Clone, Copy, Debug)]
pub struct RingH<'a> {
    /// The estimator bins (`u - u'`).
    pub bins: Bins,
    /// `u'`.
    pub u_prime: f64,
    /// Particles `N`.
    pub particles: usize,
    /// The published estimator, mean and standard error over runs.
    pub published: &'a [Estimate],
    /// The tagged estimator, mean and standard error over runs.
    pub tagged: &'a [Estimate],
    /// Tagged lineages of each run.
    pub lineages: &'a [f64],
}

impl RingH<'_> {
    /// The tagged estimator's model if MD followed `predicted`.
    fn tagged_model(&self, predicted: &[Estimate]) -> CountModel {
        tagged_model(&means(predicted), self.bins.width, self.lineages)
    }
}

/// The means of estimates.
fn means(estimates: &[Estimate]) -> Vec<f64> {
    estimates.iter().map(|e| e.mean).collect()
}

/// Chi-square of an MD estimate of `h` against a reference, twice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Goodness {
    /// With the covariance MD would have if it followed the reference, bins
    /// grouped to at least [`MINIMUM_EXPECTED_COUNT`] expected counts
    /// ([`CountModel::chi_square`]).
    pub model: ChiSquare,
    /// With the runs' own standard errors, bin by bin, bins without spread
    /// left out (`stats::chi_square`, the published definition): its per-bin
    /// variances come from a handful of runs of small counts, so it scatters
    /// above chi-square (under the reference its chi2/dof has median 1.0 to
    /// 1.2 and a long upper tail, simulated for the default study's rings).
    pub sample: ChiSquare,
}

/// What the comparison of an MD estimator with its reference concludes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Agreement {
    /// No test rejects at [`REJECTED_P`].
    Agrees,
    /// The shape's chi-square or the window variance's ratio rejects.
    Differs,
    /// Neither test can be made: fewer than [`MIN_TEST_DOF`] groups and no
    /// window variance.
    NoTest,
}

impl Agreement {
    /// The verdict as tables and the report print it.
    pub fn label(self) -> &'static str {
        match self {
            Agreement::Agrees => "agrees",
            Agreement::Differs => "differs",
            Agreement::NoTest => "no test",
        }
    }
}

/// The verdict of the shape's chi-square (`shape`; a test only with at least
/// [`MIN_TEST_DOF`] degrees of freedom) and of the ratio of the window
/// variances, MD over the reference, against 1 (`variance_ratio`): MD
/// differs when either rejects at [`REJECTED_P`] (the ratio at `|z| >`
/// [`REJECTED_Z`]). The variance is the test with power against a
/// broadening: a 20% excess spreads over every group of the shape's
/// chi-square, but is all of the ratio's.
pub fn agreement(shape: Option<ChiSquare>, variance_ratio: Option<Estimate>) -> Agreement {
    let shape = shape.filter(|s| s.dof >= MIN_TEST_DOF);
    let ratio_z = variance_ratio.map(ratio_z).filter(|z| z.is_finite());
    if shape.is_none() && ratio_z.is_none() {
        Agreement::NoTest
    } else if shape.is_some_and(|s| s.p_value() < REJECTED_P)
        || ratio_z.is_some_and(|z| z.abs() > REJECTED_Z)
    {
        Agreement::Differs
    } else {
        Agreement::Agrees
    }
}

/// How many standard errors a ratio that should be 1 lies from it.
pub fn ratio_z(ratio: Estimate) -> f64 {
    (ratio.mean - 1.0) / ratio.stderr
}

/// Both MD estimators of `ring` against the reference `predicted` (its
/// Boltzmann `h` on the ring's bins, with errors): `[published, tagged]`.
pub fn goodness(ring: &RingH, predicted: &[Estimate]) -> [Goodness; 2] {
    let published = published_model(
        &ring.bins,
        ring.u_prime,
        ring.particles,
        &means(predicted),
        ring.lineages.len(),
    );
    let width = ring.bins.width;
    let fit = |model: &CountModel, md: &[Estimate]| Goodness {
        model: model.chi_square(md, predicted, width, MINIMUM_EXPECTED_COUNT),
        sample: chi_square(md, predicted),
    };
    [
        fit(&published, ring.published),
        fit(&ring.tagged_model(predicted), ring.tagged),
    ]
}

/// The scaling collapse: the tagged `h` of `ring` against that of `first`
/// on the same bins at the same `rho^2 l v_th t_f`. The two rings are
/// independent, so the difference's model is both rings' tagged models
/// under their reference `h` (`predicted`, `first_predicted`), and `first`'s
/// `h` enters as the reference without errors of its own (its scatter is in
/// the model).
pub fn collapse(
    ring: &RingH,
    predicted: &[Estimate],
    first: &RingH,
    first_predicted: &[Estimate],
) -> Goodness {
    let both = ring
        .tagged_model(predicted)
        .difference(&first.tagged_model(first_predicted));
    let exact: Vec<Estimate> = first
        .tagged
        .iter()
        .map(|e| Estimate {
            mean: e.mean,
            stderr: 0.0,
        })
        .collect();
    Goodness {
        model: both.chi_square(ring.tagged, &exact, ring.bins.width, MINIMUM_EXPECTED_COUNT),
        sample: chi_square(ring.tagged, first.tagged),
    }
}

/// Largest relative difference of two rings' scaled final times
/// `rho^2 l v_th t_f` that counts as the same time: the times come from
/// different `N`, `rho l` and `t_f` through a few roundings each (~1e-16),
/// while a study's distinct times differ by far more than 1e-9.
pub const SAME_SCALED_TIME: f64 = 1e-9;

/// A ring as the scaling collapse takes it: its MD `h`, its estimator bins'
/// centres `u - u'`, its reference `h` on them (with errors) and its scaled
/// final time `rho^2 l v_th t_f`.
#[derive(Clone, Copy, Debug)]
pub struct CollapseRing<'a> {
    /// The MD estimates.
    pub h: RingH<'a>,
    /// Bin centres `u - u'` as the ring's tables give them, `v_th`.
    pub du: &'a [f64],
    /// The reference (Boltzmann) `h` on the ring's bins.
    pub predicted: &'a [Estimate],
    /// `rho^2 l v_th t_f`.
    pub time: f64,
}

/// The scaling collapse of `ring` onto `first` ([`collapse`]) where it
/// applies: the same bins and the same scaled time (to [`SAME_SCALED_TIME`]
/// relative), so that `h` must be the same if MD follows the Boltzmann
/// equation; `None` otherwise.
pub fn scaling_collapse(ring: &CollapseRing, first: &CollapseRing) -> Option<Goodness> {
    (first.du == ring.du && (ring.time / first.time - 1.0).abs() < SAME_SCALED_TIME)
        .then(|| collapse(&ring.h, ring.predicted, &first.h, first.predicted))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::quasi_random::standard_normal_cdf;

    /// The thermal average of a constant is that constant (to rounding of
    /// 25 terms).
    #[test]
    fn thermal_average_of_a_constant_is_the_constant() {
        let average = thermal_average(|_| vec![2.5, -1.0]);
        assert!((average[0] - 2.5).abs() < 1e-14);
        assert!((average[1] + 1.0).abs() < 1e-14);
    }

    /// `<u^2>` of `f0` restricted to `|u| <= a`: `1 - 2 a f0(a) / (2 Phi(a) - 1)`.
    /// Simpson's error `(b - a) h^4 / 180 max|f''''|` with `h = 1/4` and
    /// `|d^4 (u^2 f0) / du^4| <= 12 f0(0)` bounds the numerator's error by
    /// 6.2e-4 and the normalization's by 1.6e-4 of itself: 1e-3 covers both.
    #[test]
    fn thermal_average_of_u_squared_is_the_truncated_second_moment() {
        let a = THERMAL_BAND;
        let exact = 1.0 - 2.0 * a * thermal_density(a) / (2.0 * standard_normal_cdf(a) - 1.0);
        let average = thermal_average(|u| vec![u * u])[0];
        assert!((average - exact).abs() < 1e-3, "{average} vs {exact}");
        assert!((average - 1.0).abs() > 0.02, "truncation resolved");
    }

    /// Without collisions `h` stays `delta(u - u')`: all its mass, `1 /
    /// width` per `v_th`, in the ring's centre bin, and no window variance.
    #[test]
    fn boltzmann_h_without_collisions_is_a_delta() {
        let rates = Replicated {
            full: vec![0.0; 21],
            leave_one_out: vec![vec![0.0; 21]; 3],
        };
        let du = [-0.2, -0.1, 0.0, 0.1, 0.2];
        let bins = RingBins {
            du: &du,
            width: 0.1,
            window: 0.5,
        };
        let h = boltzmann_on_bins(&rates, 0.01, 100.0, bins);
        for h in std::iter::once(&h.full).chain(&h.leave_one_out) {
            for (k, value) in h.iter().enumerate() {
                let expected = if k == 2 { 10.0 } else { 0.0 };
                assert!((value - expected).abs() < 1e-12, "bin {k}: {value}");
            }
        }
        let md = Estimate {
            mean: 1.0,
            stderr: 0.1,
        };
        let md = WindowVariances {
            published: md,
            tagged: md,
            thermal: md,
        };
        let FiniteSize {
            published,
            tagged,
            thermal,
        } = finite_size(md, &h, bins, &[1.0, 2.0, 3.0], 0.5);
        assert_eq!(published.boltzmann, tagged.boltzmann);
        assert!(tagged.boltzmann.mean.abs() < 1e-14);
        assert_eq!(thermal.boltzmann.mean, 1.0);
        assert_eq!(thermal.ratio.mean, 1.0);
    }

    /// The verdict: a ratio 4 errors from 1 rejects, one 3 errors away does
    /// not; a shape with p < 1e-3 rejects unless it has fewer than three
    /// degrees of freedom (no test), and neither test at all is no test.
    #[test]
    fn agreement_rejects_at_the_thresholds_and_only_with_a_test() {
        let ratio = |z: f64| {
            Some(Estimate {
                mean: 1.0 + 0.05 * z,
                stderr: 0.05,
            })
        };
        let shape = |chi2: f64, dof: usize| Some(ChiSquare { chi2, dof });
        assert_eq!(agreement(None, ratio(4.0)), Agreement::Differs);
        assert_eq!(agreement(None, ratio(-4.0)), Agreement::Differs);
        assert_eq!(agreement(None, ratio(3.0)), Agreement::Agrees);
        // chi2 = 30 for 6 dof: p = 3.9e-5; 10 for 6: p = 0.12.
        assert_eq!(agreement(shape(30.0, 6), None), Agreement::Differs);
        assert_eq!(agreement(shape(10.0, 6), ratio(0.0)), Agreement::Agrees);
        assert_eq!(agreement(shape(30.0, 2), None), Agreement::NoTest);
        assert_eq!(agreement(shape(30.0, 2), ratio(0.5)), Agreement::Agrees);
        assert_eq!(agreement(None, None), Agreement::NoTest);
    }

    /// A ring of 9 bins of width 0.1 whose published and tagged `h` (per
    /// `v_th`) are `h`, from runs of `lineages`.
    fn exact_ring<'a>(h: &'a [Estimate], lineages: &'a [f64]) -> RingH<'a> {
        RingH {
            bins: Bins::for_window(0.9, 0.1),
            u_prime: 0.0,
            particles: 1000,
            published: h,
            tagged: h,
            lineages,
        }
    }

    /// Two rings with the same tagged `h` on the same bins at the same
    /// scaled time collapse with chi-square 0 (both statistics, every bin
    /// group counted); at another time or on other bins there is no collapse.
    #[test]
    fn equal_rings_collapse_exactly_and_others_not_at_all() {
        let du: Vec<f64> = (0..9).map(|k| 0.1 * (k as f64 - 4.0)).collect();
        let h: Vec<Estimate> = du
            .iter()
            .map(|x| {
                let mean = 10.0 * thermal_density(10.0 * x);
                Estimate {
                    mean,
                    stderr: 0.05 * mean,
                }
            })
            .collect();
        // Three runs, thousands of lineages in all: no bin group short of
        // MINIMUM_EXPECTED_COUNT but the tails.
        let lineages = [400.0, 500.0, 600.0];
        let ring = CollapseRing {
            h: exact_ring(&h, &lineages),
            du: &du,
            predicted: &h,
            time: 0.3,
        };
        let Goodness { model, sample } = scaling_collapse(&ring, &ring).unwrap();
        assert_eq!((model.chi2, sample.chi2), (0.0, 0.0));
        assert!(
            model.dof > 0 && sample.dof == du.len(),
            "{model:?} {sample:?}"
        );
        let later = CollapseRing {
            time: 0.3 * (1.0 + 1e-6),
            ..ring
        };
        assert!(scaling_collapse(&later, &ring).is_none());
        let shifted: Vec<f64> = du.iter().map(|x| x + 0.05).collect();
        let elsewhere = CollapseRing {
            du: &shifted,
            ..ring
        };
        assert!(scaling_collapse(&elsewhere, &ring).is_none());
    }

    /// Mass `1/2` at `du = +-0.2` per bins of width 0.1: variance `0.04`.
    #[test]
    fn window_variance_weighs_bins_by_their_squared_offset() {
        let du = [-0.2, -0.1, 0.0, 0.1, 0.2];
        let h = [5.0, 0.0, 0.0, 0.0, 5.0];
        assert!((window_variance(&h, &du, 0.1) - 0.04).abs() < 1e-15);
    }
}
