//! `fit`: the shape `g(x) = alpha |x|^-beta exp(-x^2 / 2 sigma^2)` of the kernel
//! near `u'` (physics.md §5) at one `u'` and density, fitted to the mean kernel
//! with weights `1 / G_stderr^2` over a configurable range of `|u - u'|`;
//! standard errors and covariance from refitting every randomization alone.

use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::{input_events, target_instance, target_of};
use crate::config::{FitParams, KernelParams};
use crate::kernel::fit::{FitData, Shape, ShapeFit, fit_shape, log_groups};
use crate::kernel::{Bins, Estimate, Histogram, histograms};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

/// Log-spaced groups of bins in the fit range (about 14 per decade by default).
const FIT_GROUPS: usize = 36;

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

fn kernel_of(histogram: &Histogram, bins: &Bins) -> Vec<f64> {
    (0..bins.len())
        .map(|k| (histogram.self_part[k] + histogram.bath_part[k]) / bins.width)
        .collect()
}

/// Sample covariance of two parameter lists over replicates, of the mean.
fn covariance_of_mean(a: &[f64], b: &[f64]) -> f64 {
    let count = a.len() as f64;
    let (mean_a, mean_b) = (a.iter().sum::<f64>() / count, b.iter().sum::<f64>() / count);
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - mean_a) * (y - mean_b))
        .sum::<f64>()
        / ((count - 1.0) * count)
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
        let groups = log_groups(&offsets, low, high, FIT_GROUPS);
        let members: Vec<Vec<f64>> = groups
            .iter()
            .map(|g| g.iter().map(|&k| offsets[k]).collect())
            .collect();
        // Mean kernel over each group's bins, per replicate.
        let replicates: Vec<Vec<f64>> = fine
            .iter()
            .map(|kernel| {
                groups
                    .iter()
                    .map(|g| g.iter().map(|&k| kernel[k]).sum::<f64>() / g.len() as f64)
                    .collect()
            })
            .collect();
        let estimates: Vec<Estimate> = (0..groups.len())
            .map(|j| {
                Estimate::from_replicates(&replicates.iter().map(|r| r[j]).collect::<Vec<_>>())
            })
            .collect();
        let values: Vec<f64> = estimates.iter().map(|e| e.mean).collect();
        let errors: Vec<f64> = estimates.iter().map(|e| e.stderr).collect();
        let mean_data = FitData {
            members: &members,
            values: &values,
            errors: &errors,
        };
        progress.advance(1);
        let Some(fit) = fit_shape(&mean_data) else {
            // Nothing to fit (e.g. the integrable n = 2 kernel vanishes): say so.
            let measured = errors.iter().filter(|&&e| e > 0.0).count();
            let status = if measured == 0 {
                "kernel vanishes in the fit range"
            } else {
                "too few measured groups"
            };
            return Ok(vec![fit_table(None, status, measured, &[], (low, high))?]);
        };
        // Each replicate alone, weighted by the replicate-level errors (sqrt(R) x the mean's).
        let scale = (replicates.len() as f64).sqrt();
        let replicate_errors: Vec<f64> = errors.iter().map(|e| e * scale).collect();
        let shapes: Vec<Shape> = replicates
            .iter()
            .filter_map(|values| {
                fit_shape(&FitData {
                    members: &members,
                    values,
                    errors: &replicate_errors,
                })
                .map(|f| f.shape)
            })
            .collect();
        let status = if shapes.len() < 2 {
            "replicates could not be fitted: no standard errors"
        } else {
            "fitted"
        };
        Ok(vec![fit_table(
            Some(fit),
            status,
            fit.bins,
            &shapes,
            (low, high),
        )?])
    }
}

/// The one-row fit table; NaN where nothing could be fitted.
fn fit_table(
    fit: Option<ShapeFit>,
    status: &str,
    bins: usize,
    shapes: &[Shape],
    (low, high): (f64, f64),
) -> Result<Table, StageError> {
    let parameter = |f: fn(&Shape) -> f64| shapes.iter().map(f).collect::<Vec<f64>>();
    let (alpha, beta, sigma) = (
        parameter(|s| s.alpha),
        parameter(|s| s.beta),
        parameter(|s| s.sigma),
    );
    // Scale factor sqrt(chi2/dof) when the shape misfits the kernel (as the
    // Particle Data Group does): the replicate spread alone would ignore that the
    // three parameters then depend on how the bins are weighted.
    let scale = fit.map_or(1.0, |f| f.chi2_per_dof.max(1.0));
    let covariance = |a: &[f64], b: &[f64]| {
        if a.len() < 2 {
            f64::NAN
        } else {
            scale * covariance_of_mean(a, b)
        }
    };
    let spread = |values: &[f64]| covariance(values, values).sqrt();
    let mean = |f: fn(&Shape) -> f64| vec![fit.map_or(f64::NAN, |fit| f(&fit.shape))];
    let one = |value: f64| vec![value];
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
            one(spread(&alpha)),
        ),
        Column::f64("beta", "1", "power-law exponent near u'", mean(|s| s.beta)),
        Column::f64(
            "beta_stderr",
            "1",
            "standard error: spread of per-randomization refits times the scale factor",
            one(spread(&beta)),
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
            one(spread(&sigma)),
        ),
        Column::f64(
            "cov_alpha_beta",
            "mixed",
            "covariance of the means of alpha and beta over replicates",
            one(covariance(&alpha, &beta)),
        ),
        Column::f64(
            "cov_alpha_sigma",
            "mixed",
            "covariance of the means of alpha and sigma",
            one(covariance(&alpha, &sigma)),
        ),
        Column::f64(
            "cov_beta_sigma",
            "mixed",
            "covariance of the means of beta and sigma",
            one(covariance(&beta, &sigma)),
        ),
        Column::f64(
            "scale_factor",
            "1",
            "sqrt(max(1, chi2/dof)) applied to the errors and covariances",
            one(scale.sqrt()),
        ),
        Column::f64(
            "chi2_per_dof",
            "1",
            "chi-square per degree of freedom of the mean fit (bins treated as independent)",
            one(fit.map_or(f64::NAN, |f| f.chi2_per_dof)),
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
            vec![shapes.len() as u32],
        ),
        Column::f64("range_min", "v_th", "smallest |u - u'| fitted", one(low)),
        Column::f64("range_max", "v_th", "largest |u - u'| fitted", one(high)),
        Column::text("status", "fitted, or why not", vec![status.to_string()]),
    ];
    Ok(Table::new("fit", columns)?
        .with_metadata("ternary.description", "kernel shape fit near u'".into()))
}
