//! Evolution of the perturbation `h(u, t)` (physics.md §4): the exact
//! translation-invariant convolution semigroup for early times
//! ([`convolution`]), the full `u'`-dependent master equation on a velocity
//! grid ([`operator`], [`grid`]) with its exact exponential ([`propagate`]),
//! and the Fokker-Planck equation of the same drift and variance rates.
//! Uncertainties come from the jackknife over the Monte Carlo randomizations.
//! Pure math: no IO.

pub mod convolution;
pub mod grid;
pub mod operator;
pub mod propagate;
pub mod spectral;

use crate::kernel::Estimate;

/// Jackknife estimates of a vector-valued function of `R` replicates, given
/// its value on all of them (`full`) and with each one left out
/// (`leave_one_out`): mean `full`, standard error
/// `sqrt((R - 1)/R sum_r (f_(-r) - mean_r f_(-r))^2)`. This is how the
/// uncertainty of a nonlinear function of the kernel (such as `exp(t M)`) is
/// carried.
pub fn jackknife(full: &[f64], leave_one_out: &[Vec<f64>]) -> Vec<Estimate> {
    let count = leave_one_out.len() as f64;
    full.iter()
        .enumerate()
        .map(|(i, &value)| {
            let mean = leave_one_out.iter().map(|v| v[i]).sum::<f64>() / count;
            let spread = leave_one_out
                .iter()
                .map(|v| (v[i] - mean).powi(2))
                .sum::<f64>();
            Estimate {
                mean: value,
                stderr: ((count - 1.0) / count * spread).sqrt(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For the mean of replicates the jackknife error is the usual standard error.
    #[test]
    fn jackknife_of_a_mean_is_the_standard_error() {
        let values = [1.0, 4.0, 2.5, 3.0, 7.0];
        let total: f64 = values.iter().sum();
        let full = [total / 5.0];
        let loo: Vec<Vec<f64>> = values.iter().map(|v| vec![(total - v) / 4.0]).collect();
        let jack = jackknife(&full, &loo)[0];
        let usual = Estimate::from_replicates(&values);
        assert!((jack.stderr - usual.stderr).abs() < 1e-14);
        assert_eq!(jack.mean, usual.mean);
    }
}
