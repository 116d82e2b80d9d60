//! `fit`: the shape `g(x) = alpha |x|^-beta exp(-x^2 / 2 sigma^2)` of the kernel
//! near `u'` (physics.md §5) at one `u'` and density, fitted to the mean kernel
//! with weights `1 / G_stderr^2` over a configurable range of `|u - u'|`;
//! standard errors and covariance from refitting every randomization alone.

use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::{input_events, target_instance, target_of};
use crate::binning::Bins;
use crate::config::{FitParams, KernelParams};
use crate::kernel::fit::{FIT_GROUPS, KernelFit, Shape, fit_kernel};
use crate::kernel::{Histogram, histograms};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

/// The `fit` stage for one potential, `u'` and density.
pub struct FitStage {
    params: FitParams,
}

impl FitStage {
    /// A fit stage with resolved parameters.
    pub fn new(params: FitParams) -> FitStage {
        FitStage { params }
    }

    /// Instance id for kernel parameters.
    pub fn instance(params: &KernelParams) -> InstanceId {
        InstanceId::new("fit", &target_instance(params))
    }
}

/// `G` per bin: self plus bath over the bin width.
fn kernel_of(histogram: &Histogram, bins: &Bins) -> Vec<f64> {
    histogram.total().iter().map(|v| v / bins.width).collect()
}

impl Stage for FitStage {
    fn id(&self) -> InstanceId {
        FitStage::instance(&self.params.kernel)
    }

    fn version(&self) -> u32 {
        3
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["fit"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![CollisionsStage::instance(
            &self.params.kernel.potential.id(),
        )]
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let kernel = &self.params.kernel;
        let (events, draws, _) = input_events(inputs)?;
        let bins = Bins::for_window(kernel.window, kernel.bin_width);
        let fine: Vec<Vec<f64>> = histograms(&events, &target_of(kernel), &bins, &draws)
            .iter()
            .map(|h| kernel_of(h, &bins))
            .collect();
        let offsets: Vec<f64> = (0..bins.len()).map(|k| bins.centre(k)).collect();
        let (low, high) = (self.params.range_min, self.params.range_max);
        let fit = fit_kernel(&fine, &offsets, (low, high), FIT_GROUPS);
        progress.advance(1);
        let status = match (&fit.mean, fit.replicates.len()) {
            // Nothing to fit (e.g. the integrable n = 2 kernel vanishes): say so.
            (None, _) if fit.measured == 0 => "kernel vanishes in the fit range",
            (None, _) => "too few measured groups",
            (Some(_), fitted) if fitted < 2 => "replicates could not be fitted: no standard errors",
            (Some(_), _) => "fitted",
        };
        Ok(vec![fit_table(&fit, status, (low, high))?])
    }
}

/// The one-row fit table; NaN where nothing could be fitted.
fn fit_table(fit: &KernelFit, status: &str, (low, high): (f64, f64)) -> Result<Table, StageError> {
    let [alpha, beta, sigma]: [fn(&Shape) -> f64; 3] = [|s| s.alpha, |s| s.beta, |s| s.sigma];
    let mean = |f: fn(&Shape) -> f64| vec![fit.mean.map_or(f64::NAN, |m| f(&m.shape))];
    let one = |value: f64| vec![value];
    let bins = fit.mean.map_or(fit.measured, |m| m.bins);
    let columns = vec![
        Column::f64(
            "alpha",
            "rho^2 l v_th (v_th)^(beta-1)",
            "amplitude of g(x) = alpha |x|^-beta exp(-x^2/2 sigma^2), fit to the mean kernel",
            mean(|s| s.alpha),
        ),
        Column::f64(
            "alpha_stderr",
            "as alpha",
            "standard error: spread of per-randomization refits times the scale factor",
            one(fit.stderr(alpha)),
        ),
        Column::f64("beta", "1", "power-law exponent near u'", mean(|s| s.beta)),
        Column::f64(
            "beta_stderr",
            "1",
            "standard error: spread of per-randomization refits times the scale factor",
            one(fit.stderr(beta)),
        ),
        Column::f64(
            "sigma",
            "v_th",
            "Gaussian cut-off: largest momentum transfer of a collision",
            mean(|s| s.sigma),
        ),
        Column::f64(
            "sigma_stderr",
            "v_th",
            "standard error: spread of per-randomization refits times the scale factor",
            one(fit.stderr(sigma)),
        ),
        Column::f64(
            "cov_alpha_beta",
            "mixed",
            "covariance of the means of alpha and beta over replicates",
            one(fit.covariance(alpha, beta)),
        ),
        Column::f64(
            "cov_alpha_sigma",
            "mixed",
            "covariance of the means of alpha and sigma",
            one(fit.covariance(alpha, sigma)),
        ),
        Column::f64(
            "cov_beta_sigma",
            "mixed",
            "covariance of the means of beta and sigma",
            one(fit.covariance(beta, sigma)),
        ),
        Column::f64(
            "scale_factor",
            "1",
            "sqrt(max(1, chi2/dof)) applied to the errors and covariances",
            one(fit.scale().sqrt()),
        ),
        Column::f64(
            "chi2_per_dof",
            "1",
            "chi-square per degree of freedom of the mean fit (bins treated as independent)",
            one(fit.mean.map_or(f64::NAN, |f| f.chi2_per_dof)),
        ),
        Column::u32(
            "bins",
            "1",
            "log-spaced groups of bins fitted (with a non-zero error)",
            vec![bins as u32],
        ),
        Column::u32(
            "replicates_fitted",
            "1",
            "randomizations whose own fit converged",
            vec![fit.replicates.len() as u32],
        ),
        Column::f64("range_min", "v_th", "smallest |u - u'| fitted", one(low)),
        Column::f64("range_max", "v_th", "largest |u - u'| fitted", one(high)),
        Column::text("status", "fitted, or why not", vec![status.to_string()]),
    ];
    Ok(Table::new("fit", columns)?
        .with_metadata("ternary.description", "kernel shape fit near u'".into()))
}
