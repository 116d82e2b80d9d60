//! Early-time evolution with the translation-invariant kernel (physics.md §4):
//! for `|u'| << 1`, `G(u' -> u' + x) ~= G(0 -> x)`, so `dh/dt = g * h` (a
//! convolution with the binned kernel `g_k = G_k dx`) and
//! `h(t) = exp(t g*) delta` is exact in Fourier space for any `t`:
//! `h^(q, t) = exp(t g^(q))`. Computed with FFTs on a periodic grid of the
//! kernel's bins, wide enough that wrap-around is negligible.
//!
//! The log of `h^` is `t g^`, so the cumulants of `h` are `t` times the
//! kernel's moments `kappa_p = sum_k g_k x_k^p`: mass `exp(t kappa_0)`, mean
//! `t kappa_1`, variance `t kappa_2`, excess kurtosis `kappa_4 / (t kappa_2^2)`
//! — a closed form the FFT result is checked against ([`state_moment`] and
//! its normalized shape against [`closed_form_variance`] and the like).
//! Units: `x` in `v_th`, `g` in `rho^2 l v_th`, `t` in `1 / (rho^2 l v_th)`.

use super::fourier::{Complex, Fourier};

use crate::binning::Bins;
use crate::kernel::{Draws, Event, Target, histograms};
use crate::stats::{Replicated, replicate_means};

/// The binned kernel `g_k = G_k dx` (self plus bath) at `target` on `bins`,
/// per replicate: its mean and its means with each replicate left out, for
/// jackknife errors of anything computed from it.
pub fn replicated_kernel(
    events: &[Event],
    draws: &Draws,
    target: &Target,
    bins: &Bins,
) -> Replicated<Vec<f64>> {
    let per_replicate: Vec<Vec<f64>> = histograms(events, target, bins, draws)
        .iter()
        .map(|h| h.total())
        .collect();
    replicate_means(&per_replicate)
}

/// Moments `kappa_p = sum_k g_k x_k^p`, `p = 0..=4`, of a kernel on bins of
/// `width` centred on `x_k = (k - half) width`.
pub fn kernel_moments(rates: &[f64], width: f64) -> [f64; 5] {
    let half = (rates.len() / 2) as f64;
    let mut moments = [0.0; 5];
    for (k, &g) in rates.iter().enumerate() {
        let x = (k as f64 - half) * width;
        let mut power = g;
        for moment in &mut moments {
            *moment += power;
            power *= x;
        }
    }
    moments
}

/// Number `exp(t kappa_0)` of `h` at time `t` from the kernel's moments
/// ([`kernel_moments`]).
pub fn closed_form_number(kappa: &[f64; 5], t: f64) -> f64 {
    libm::exp(t * kappa[0])
}

/// Variance `t kappa_2` of the normalized `h` at time `t`, `v_th^2`.
pub fn closed_form_variance(kappa: &[f64; 5], t: f64) -> f64 {
    t * kappa[2]
}

/// Excess kurtosis `kappa_4 / (t kappa_2^2)` of `h` at time `t`: the fourth
/// cumulant `t kappa_4` over the squared variance, decaying as `1/t`.
pub fn closed_form_excess_kurtosis(kappa: &[f64; 5], t: f64) -> f64 {
    kappa[4] / (t * kappa[2] * kappa[2])
}

/// Moment `sum_i h_i x_i^p` of a state on periodic bins of `width`, index
/// `len / 2` at `x = 0` (as [`evolve`] returns them).
pub fn state_moment(h: &[f64], width: f64, p: i32) -> f64 {
    let half = (h.len() / 2) as f64;
    h.iter()
        .enumerate()
        .map(|(i, m)| m * ((i as f64 - half) * width).powi(p))
        .sum()
}

/// Mean `<x>_h = m_1 / m_0` of a periodic state (normalized), `v_th`.
pub fn state_mean(h: &[f64], width: f64) -> f64 {
    state_moment(h, width, 1) / state_moment(h, width, 0)
}

/// Variance `m_2 / m_0 - (m_1 / m_0)^2` of a periodic state (normalized), `v_th^2`.
pub fn state_variance(h: &[f64], width: f64) -> f64 {
    let mass = state_moment(h, width, 0);
    state_moment(h, width, 2) / mass - (state_moment(h, width, 1) / mass).powi(2)
}

/// Excess kurtosis `mu_4 / mu_2^2 - 3` of a periodic state (normalized;
/// `mu_p` the central moments).
pub fn excess_kurtosis(h: &[f64], width: f64) -> f64 {
    let half = (h.len() / 2) as f64;
    let x = |i: usize| (i as f64 - half) * width;
    let mass: f64 = h.iter().sum();
    let mean = h.iter().enumerate().map(|(i, m)| m * x(i)).sum::<f64>() / mass;
    let central = |p: i32| {
        h.iter()
            .enumerate()
            .map(|(i, m)| m * (x(i) - mean).powi(p))
            .sum::<f64>()
            / mass
    };
    central(4) / central(2).powi(2) - 3.0
}

/// Periodic grid size (a power of two) holding `h` up to time `t_max`: the
/// kernel's span plus 16 standard deviations and the mean on each side.
pub fn periodic_size(rates: &[f64], width: f64, t_max: f64) -> usize {
    let [_, k1, k2, ..] = kernel_moments(rates, width);
    let reach = (t_max * k1).abs() + 16.0 * (t_max * k2.max(0.0)).sqrt();
    let bins = 2 * ((reach / width).ceil() as usize + rates.len()) + 1;
    bins.next_power_of_two()
}

/// `h(x, t)` for each of `times` from `delta(x)` on `size` periodic bins of the
/// kernel's width: bin masses, index `size / 2` is `x = 0`.
pub fn evolve(rates: &[f64], size: usize, times: &[f64]) -> Vec<Vec<f64>> {
    let half = rates.len() / 2;
    let mut spectrum = vec![Complex::new(0.0, 0.0); size];
    for (k, &g) in rates.iter().enumerate() {
        let index = (k + size - half) % size;
        spectrum[index].re += g;
    }
    let fourier = Fourier::new(size);
    fourier.forward(&mut spectrum);
    times
        .iter()
        .map(|&t| {
            let mut h: Vec<Complex> = spectrum.iter().map(|&g| (g * t).exp()).collect();
            fourier.inverse(&mut h);
            (0..size)
                .map(|i| h[(i + size / 2) % size].re / size as f64)
                .collect()
        })
        .collect()
}

/// Sums `factor` neighbouring bins (odd `factor`) around the centre bin
/// `centre`, keeping `half_out` output bins on each side of it.
pub fn rebin(h: &[f64], centre: usize, factor: usize, half_out: usize) -> Vec<f64> {
    let reach = factor / 2;
    (0..=2 * half_out)
        .map(|m| {
            let middle = centre as isize + (m as isize - half_out as isize) * factor as isize;
            (middle - reach as isize..=middle + reach as isize)
                .filter_map(|i| usize::try_from(i).ok().and_then(|i| h.get(i)))
                .sum()
        })
        .collect()
}

/// Masses of periodic fine bins (`width`, index `centre` at `x = 0`) summed
/// into output bins of `out_width` centred on `out_centres`, each fine bin
/// shared by overlap length (output bins need not align with fine ones).
pub fn overlap_rebin(
    h: &[f64],
    width: f64,
    centre: usize,
    out_centres: &[f64],
    out_width: f64,
) -> Vec<f64> {
    out_centres
        .iter()
        .map(|&x| {
            let (low, high) = (x - 0.5 * out_width, x + 0.5 * out_width);
            let first = (low / width - 0.5).floor() as isize;
            let last = (high / width + 0.5).ceil() as isize;
            (first..=last)
                .filter_map(|k| {
                    let index = usize::try_from(centre as isize + k).ok()?;
                    let (a, b) = ((k as f64 - 0.5) * width, (k as f64 + 0.5) * width);
                    let overlap = (b.min(high) - a.max(low)).max(0.0);
                    Some(h.get(index)? * overlap / width)
                })
                .sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kernel with a loss at the centre and asymmetric gains: the FFT
    /// evolution's mass, mean, variance and excess kurtosis equal the
    /// cumulant closed form.
    #[test]
    fn fourier_evolution_matches_the_cumulants() {
        let width = 0.01;
        let mut rates = vec![0.0; 41];
        for (k, rate) in rates.iter_mut().enumerate() {
            let x = (k as f64 - 20.0) * width;
            *rate = libm::exp(-x * x / 0.005) * (1.0 + 3.0 * x);
        }
        rates[20] = -rates.iter().sum::<f64>() + rates[20] - 0.02;
        let kappa = kernel_moments(&rates, width);
        let times = [0.5, 5.0, 40.0];
        let size = periodic_size(&rates, width, 40.0);
        for (h, t) in evolve(&rates, size, &times).iter().zip(times) {
            let half = (size / 2) as f64;
            // FFT rounding leaves ~EPSILON per bin everywhere on the periodic
            // grid; weighted by |x|^p it bounds the p-th moment's error (the
            // mean at t = 40: 1.4e-12 against 3.7e-11).
            let floor = |p: i32| {
                f64::EPSILON
                    * (0..size)
                        .map(|i| ((i as f64 - half) * width).abs().powi(p))
                        .sum::<f64>()
            };
            let mass = state_moment(h, width, 0);
            let mean = state_mean(h, width);
            let variance = state_variance(h, width);
            let kurtosis = excess_kurtosis(h, width);
            let number = closed_form_number(&kappa, t);
            assert!((mass - number).abs() < 1e-12, "t {t}: {mass}");
            assert!((mean - t * kappa[1]).abs() < floor(1), "t {t}: {mean}");
            let closed = closed_form_variance(&kappa, t);
            assert!(
                (variance - closed).abs() < floor(2),
                "t {t}: {variance} vs {closed}"
            );
            // mu_4 / mu_2^2 carries the fourth moment's floor over mu_2^2.
            let closed = closed_form_excess_kurtosis(&kappa, t);
            assert!(
                (kurtosis - closed).abs() < floor(4) / variance.powi(2),
                "t {t}: {kurtosis} vs {closed}"
            );
        }
    }

    /// Half the mass at `-a`, half at `+a`: mean 0, variance `a^2`, excess
    /// kurtosis `1 - 3 = -2`.
    #[test]
    fn a_two_point_state_has_excess_kurtosis_minus_two() {
        let width = 0.5;
        let mut h = vec![0.0; 16];
        (h[5], h[11]) = (0.25, 0.25);
        let a = 3.0 * width;
        assert_eq!(state_mean(&h, width), 0.0);
        assert!((state_variance(&h, width) - a * a).abs() < 1e-15);
        assert!((excess_kurtosis(&h, width) + 2.0).abs() < 1e-15);
    }

    #[test]
    fn overlap_rebinning_shares_split_bins() {
        // Fine bins of width 1 at x = -2..=2 with masses 1..=5; an output bin
        // [-1, 1] takes half of the bins at -1 and 1 and all of the bin at 0.
        let h = [1.0, 2.0, 3.0, 4.0, 5.0];
        let out = overlap_rebin(&h, 1.0, 2, &[0.0, 2.0], 2.0);
        assert_eq!(out, vec![0.5 * 2.0 + 3.0 + 0.5 * 4.0, 0.5 * 4.0 + 5.0]);
    }

    #[test]
    fn rebinning_keeps_mass_near_the_centre() {
        let h: Vec<f64> = (0..21).map(f64::from).collect();
        let out = rebin(&h, 10, 3, 2);
        assert_eq!(out, vec![12.0, 21.0, 30.0, 39.0, 48.0]);
    }
}
