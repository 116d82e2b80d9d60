//! The early-time evolution of `h` from `delta(u - u')` under the
//! translation-invariant kernel (physics.md §4), with jackknife errors: the
//! exact Fourier-space evolution of [`convolution`] on the kernel's fine bins,
//! rebinned to output bins, and the moments of `h` against the closed-form
//! cumulants `t kappa_p`. Not the kernel's estimate (`kernel`) nor the tables
//! (`stages::evolve`). Units: `x` in `v_th`, `h` per `v_th`, rates in
//! `rho^2 l v_th`, `t` in `1 / (rho^2 l v_th)`.

use super::convolution::{
    self, closed_form_excess_kurtosis, closed_form_number, closed_form_variance, excess_kurtosis,
    kernel_moments, state_mean, state_moment, state_variance,
};
use crate::stats::{Estimate, Replicated};

/// `h(x, t)` at every time of a schedule, for the mean kernel and with each
/// randomization left out, on a periodic grid of the kernel's bins.
pub struct EarlyEvolution {
    /// Bin masses on the periodic grid per time, index `centre` at `x = 0`.
    states: Replicated<Vec<Vec<f64>>>,
    /// The kernel's moments `kappa_0..=kappa_4` ([`kernel_moments`]).
    cumulants: Replicated<[f64; 5]>,
    /// Width of the kernel's (fine) bins, `v_th`.
    width: f64,
    /// The periodic grid's bin at `x = 0`.
    centre: usize,
    /// Fine bins per output bin (odd).
    rebin: usize,
    /// Output bins on each side of `x = 0`.
    half_out: usize,
}

/// The moments of the early-time `h` at one time (jackknife estimates) and
/// their closed forms from the kernel's cumulants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarlyMoments {
    /// Number `sum_i h_i`.
    pub number: Estimate,
    /// Closed-form number `exp(t kappa_0)` (mean only in the tables).
    pub number_closed: Estimate,
    /// Mean `<x>`, `v_th`.
    pub mean: Estimate,
    /// Variance of `x`, `v_th^2`.
    pub variance: Estimate,
    /// Closed-form variance `t kappa_2`.
    pub variance_closed: Estimate,
    /// Excess kurtosis `mu_4 / mu_2^2 - 3`.
    pub kurtosis: Estimate,
    /// Closed-form excess kurtosis `kappa_4 / (t kappa_2^2)`.
    pub kurtosis_closed: Estimate,
}

impl EarlyEvolution {
    /// Evolves `delta(x)` under the binned kernel `rates` (bins of `width`,
    /// see [`convolution::replicated_kernel`]) to every time of `times`
    /// (ascending), on a periodic grid wide enough for the last time
    /// ([`convolution::periodic_size`]) and for the output bins of `rebin`
    /// fine bins covering `[-range, range]`.
    pub fn new(
        rates: &Replicated<Vec<f64>>,
        width: f64,
        times: &[f64],
        rebin: usize,
        range: f64,
    ) -> EarlyEvolution {
        let t_max = times.last().copied().unwrap_or(0.0);
        let out_width = rebin as f64 * width;
        let half_out = (range / out_width).round() as usize;
        let size = convolution::periodic_size(&rates.full, width, t_max)
            .max((2 * (half_out + 1) * rebin).next_power_of_two());
        EarlyEvolution {
            states: rates.map(|g| convolution::evolve(g, size, times)),
            cumulants: rates.map(|g| kernel_moments(g, width)),
            width,
            centre: size / 2,
            rebin,
            half_out,
        }
    }

    /// Width of an output bin, `v_th`.
    pub fn out_width(&self) -> f64 {
        self.rebin as f64 * self.width
    }

    /// The output bins' centres `x`, ascending, `v_th`.
    pub fn offsets(&self) -> Vec<f64> {
        (0..=2 * self.half_out)
            .map(|m| (m as f64 - self.half_out as f64) * self.out_width())
            .collect()
    }

    /// `h` per `v_th` on the output bins ([`EarlyEvolution::offsets`]) at time
    /// index `k`: each bin's mass over its width.
    pub fn density(&self, k: usize) -> Vec<Estimate> {
        let (centre, rebin, half_out) = (self.centre, self.rebin, self.half_out);
        let binned = self
            .states
            .map(|s| convolution::rebin(&s[k], centre, rebin, half_out));
        let out_width = self.out_width();
        binned
            .values()
            .iter()
            .map(|estimate| Estimate {
                mean: estimate.mean / out_width,
                stderr: estimate.stderr / out_width,
            })
            .collect()
    }

    /// The moments of `h` at time index `k`, the scaled time `t`, against
    /// the closed forms.
    pub fn moments(&self, k: usize, t: f64) -> EarlyMoments {
        let (states, cumulants, width) = (&self.states, &self.cumulants, self.width);
        EarlyMoments {
            number: states.estimate(k, |h| state_moment(h, width, 0)),
            number_closed: cumulants.scalar(|c| closed_form_number(c, t)),
            mean: states.estimate(k, |h| state_mean(h, width)),
            variance: states.estimate(k, |h| state_variance(h, width)),
            variance_closed: cumulants.scalar(|c| closed_form_variance(c, t)),
            kurtosis: states.estimate(k, |h| excess_kurtosis(h, width)),
            kurtosis_closed: cumulants.scalar(|c| closed_form_excess_kurtosis(c, t)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::replicate_means;

    /// Three replicates of a kernel that conserves number (`kappa_0 = 0`):
    /// a Gaussian gain with a drift, balanced by the loss at `x = 0`, each
    /// replicate with its own drift.
    fn conserving_kernels(width: f64) -> Replicated<Vec<f64>> {
        let replicates: Vec<Vec<f64>> = [0.9, 1.0, 1.1]
            .iter()
            .map(|&drift| {
                let mut rates: Vec<f64> = (0..41)
                    .map(|k| {
                        let x = (k as f64 - 20.0) * width;
                        libm::exp(-x * x / 0.005) * (1.0 + drift * x)
                    })
                    .collect();
                rates[20] -= rates.iter().sum::<f64>();
                rates
            })
            .collect();
        replicate_means(&replicates)
    }

    /// The number is kept (`exp(t kappa_0)`, 1 to the rounding of
    /// `kappa_0`), and the output bins, covering all of `h` but tails below
    /// `1e-20`, carry it: `sum_m h_m out_width` is the number, and the
    /// replicates agree on it. Rounding: `EPSILON` per fine bin of the
    /// periodic grid.
    #[test]
    fn a_conserving_kernel_keeps_the_number_in_the_output_bins() {
        let width = 0.01;
        let rates = conserving_kernels(width);
        let times = [0.5, 5.0, 40.0];
        let evolution = EarlyEvolution::new(&rates, width, &times, 3, 12.0);
        let rounding = f64::EPSILON * evolution.states.full[0].len() as f64;
        assert_eq!(evolution.offsets().len(), evolution.density(0).len());
        for (k, &t) in times.iter().enumerate() {
            let moments = evolution.moments(k, t);
            let number = moments.number.mean;
            assert!((number - moments.number_closed.mean).abs() < rounding);
            assert!((number - 1.0).abs() < rounding, "{moments:?}");
            assert!(moments.number.stderr < rounding, "{moments:?}");
            let density = evolution.density(k);
            let carried: f64 = density.iter().map(|h| h.mean).sum::<f64>() * evolution.out_width();
            assert!((carried - number).abs() < rounding, "t {t}: {carried}");
        }
    }

    /// The drift of every replicate moves the mean as `t kappa_1`: the
    /// jackknife error of the mean is the spread of the replicates' drifts,
    /// and the closed-form variance and its error are those of `t kappa_2`.
    #[test]
    fn the_mean_moves_with_the_kernel_drift_and_carries_its_error() {
        let width = 0.01;
        let rates = conserving_kernels(width);
        let t = 5.0;
        let evolution = EarlyEvolution::new(&rates, width, &[t], 3, 12.0);
        let moments = evolution.moments(0, t);
        let drift = rates.scalar(|g| t * kernel_moments(g, width)[1]);
        let spread = rates.scalar(|g| t * kernel_moments(g, width)[2]);
        // The FFT's rounding floor of the first moment (see
        // `convolution::tests`): EPSILON per bin times its |x|.
        let size = evolution.states.full[0].len() as f64;
        let floor = f64::EPSILON * size * size * width;
        assert!(drift.stderr > 0.0);
        assert!(
            (moments.mean.mean - drift.mean).abs() < floor,
            "{moments:?}"
        );
        assert!(
            (moments.mean.stderr - drift.stderr).abs() < floor,
            "{moments:?}"
        );
        assert_eq!(moments.variance_closed, spread);
    }
}
