//! `fit`: the shape `g(x) = alpha |x|^-beta exp(-x^2 / 2 sigma^2)` of the kernel
//! near `u'` (physics.md §5) at one `u'` and density, fitted to the mean kernel
//! with weights `1 / G_stderr^2` over a configurable range of `|u - u'|`;
//! standard errors and covariance from refitting every randomization alone
//! (the `kernel` stage's `kernel_replicates` table).

use serde_json::Value;

use super::kernel::target_instance;
use crate::config::{FitParams, KernelParams};
use crate::contract::{self, Rows};
use crate::kernel::fit::{FIT_GROUPS, KernelFit, Shape, fit_kernel};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

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
        InstanceId::new(contract::fit::STAGE, &target_instance(params))
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for FitStage {
    fn id(&self) -> InstanceId {
        FitStage::instance(&self.params.kernel)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::fit::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![InstanceId::new(
            contract::kernel::STAGE,
            &target_instance(&self.params.kernel),
        )]
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let input = inputs
            .first()
            .ok_or_else(|| StageError::Input("no kernel input".into()))?;
        let (fine, offsets) = contract::kernel::replicates::read(input)?;
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
    use contract::fit::*;
    let [alpha, beta, sigma]: [fn(&Shape) -> f64; 3] = [|s| s.alpha, |s| s.beta, |s| s.sigma];
    let parameter = |f: fn(&Shape) -> f64| {
        move |_: &()| Estimate {
            mean: fit.mean.map_or(f64::NAN, |m| f(&m.shape)),
            stderr: fit.stderr(f),
        }
    };
    let bins = fit.mean.map_or(fit.measured, |m| m.bins);
    Ok(Rows::new(&[()])
        .estimate(ALPHA, parameter(alpha))
        .estimate(BETA, parameter(beta))
        .estimate(SIGMA, parameter(sigma))
        .with(COV_ALPHA_BETA, |_| fit.covariance(alpha, beta))
        .with(COV_ALPHA_SIGMA, |_| fit.covariance(alpha, sigma))
        .with(COV_BETA_SIGMA, |_| fit.covariance(beta, sigma))
        .with(SCALE_FACTOR, |_| fit.scale().sqrt())
        .with(CHI2_PER_DOF, |_| {
            fit.mean.map_or(f64::NAN, |f| f.chi2_per_dof)
        })
        .with(BINS, |_| bins as u32)
        .with(REPLICATES_FITTED, |_| fit.replicates.len() as u32)
        .with(RANGE_MIN, |_| low)
        .with(RANGE_MAX, |_| high)
        .with(STATUS, |_| status.to_string())
        .table(&TABLE)?)
}
