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

use rayon::prelude::*;

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

/// A quantity evaluated on the estimate and on every leave-one-out replicate set.
pub struct Replicated<T> {
    /// On all replicates.
    pub full: T,
    /// With each replicate left out.
    pub leave_one_out: Vec<T>,
}

impl<T: Sync> Replicated<T> {
    /// Applies `f` to every member, in parallel.
    pub fn map<U: Send>(&self, f: impl Fn(&T) -> U + Sync) -> Replicated<U> {
        Replicated {
            full: f(&self.full),
            leave_one_out: self.leave_one_out.par_iter().map(&f).collect(),
        }
    }
}

impl Replicated<Vec<Vec<f64>>> {
    /// Jackknife estimate of `f` of the state at time index `k`.
    pub fn estimate(&self, k: usize, f: impl Fn(&[f64]) -> f64) -> Estimate {
        let loo: Vec<Vec<f64>> = self.leave_one_out.iter().map(|s| vec![f(&s[k])]).collect();
        jackknife(&[f(&self.full[k])], &loo)[0]
    }

    /// Jackknife estimates of the state at time index `k`, node by node.
    pub fn states(&self, k: usize) -> Vec<Estimate> {
        let loo: Vec<Vec<f64>> = self.leave_one_out.iter().map(|s| s[k].clone()).collect();
        jackknife(&self.full[k], &loo)
    }
}

impl Replicated<Vec<f64>> {
    /// Jackknife estimates, component by component.
    pub fn values(&self) -> Vec<Estimate> {
        jackknife(&self.full, &self.leave_one_out)
    }

    /// Jackknife estimate of the scalar `f` of the vector.
    pub fn scalar(&self, f: impl Fn(&[f64]) -> f64) -> Estimate {
        let loo: Vec<Vec<f64>> = self.leave_one_out.iter().map(|v| vec![f(v)]).collect();
        jackknife(&[f(&self.full)], &loo)[0]
    }
}

/// The mean of replicate vectors and the means with each one left out.
pub fn replicate_means(replicates: &[Vec<f64>]) -> Replicated<Vec<f64>> {
    let count = replicates.len() as f64;
    let mut total = vec![0.0; replicates[0].len()];
    for replicate in replicates {
        total.iter_mut().zip(replicate).for_each(|(t, v)| *t += v);
    }
    Replicated {
        full: total.iter().map(|t| t / count).collect(),
        leave_one_out: replicates
            .iter()
            .map(|own| {
                total
                    .iter()
                    .zip(own)
                    .map(|(t, v)| (t - v) / (count - 1.0))
                    .collect()
            })
            .collect(),
    }
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
