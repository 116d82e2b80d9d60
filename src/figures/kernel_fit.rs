//! `kernel_fit_<id>`: a kernel with its fitted shape, its model and the
//! model's normalized residuals.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, frame, series_of, stack};
use super::kernel_groups::{GROUPS_PER_DECADE, positive_kernel};
use super::planning::{dilute, main_potential};
use super::{Axis, DU_AXIS, Drawn, FigureKind, G_AXIS, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::kernel::model::Part;
use crate::pipeline::{Input, InstanceId, StageError};

/// `G(0 -> u)` of one potential with its fitted shape `alpha x^-beta
/// exp(-x^2/2 sigma^2)` and its model (`kernel::model`), and the model's
/// normalized residuals.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "kernel_fit")]
pub struct KernelFit {
    /// The potential's id (the figure's name).
    pub id: String,
    /// Its legend label.
    pub label: String,
}

impl KernelFit {
    /// The main potential's kernel with its fit.
    pub fn planned(study: &Study, _present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let Some(p) = main_potential(study) else {
            return Vec::new();
        };
        let figure = KernelFit {
            id: p.id(),
            label: p.family().label(),
        };
        let inputs = vec![
            dilute(study, contract::kernel::STAGE, &p),
            dilute(study, contract::fit::STAGE, &p),
        ];
        vec![Drawn::new(figure, inputs)]
    }
}

impl FigureKind for KernelFit {
    fn topic(&self) -> Topic {
        Topic::MainKernel
    }

    fn name(&self) -> String {
        format!("kernel_fit_{}", self.id)
    }

    fn description(&self) -> String {
        "(a) G(0 -> u) against u - u' > 0, +- standard error, with the fitted shape alpha x^-beta exp(-x^2 / 2 sigma^2) and the kernel model's mean over each group it was fitted to (docs/kernel-model.md); bars whose lower end is at or below zero are drawn open downward (an arrow to the frame's bottom). (b) The model's normalized residuals (G - model) / error per group, the error the fit weighs with (pooled with the neighbouring groups')".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel::new(
                    "kernel",
                    Axis::log(DU_AXIS),
                    Axis::log(G_AXIS),
                    vec![
                        ("fit", Style::Line),
                        ("model", Style::Line),
                        ("Monte Carlo", Style::Markers),
                    ],
                ),
                Panel::new(
                    "residuals",
                    Axis::log(DU_AXIS),
                    Axis::linear(RESIDUAL_AXIS),
                    vec![("model", Style::Markers)],
                ),
            ],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        let measured = positive_kernel(&inputs[0], "kernel", "Monte Carlo", GROUPS_PER_DECADE)?;
        let fitted = fitted_shape(&measured, &inputs[1])?;
        let [model, residuals] = model_series(&inputs[1])?;
        stack(vec![measured, fitted, model, residuals])
    }
}

/// The residual panel's axis.
const RESIDUAL_AXIS: &str = "(G - model) / error";

/// The model's group means (panel `kernel`) and normalized residuals (panel
/// `residuals`) above `u'` from `kernel_model_groups` (empty without a
/// model).
fn model_series(fit: &Input) -> Result<[DataFrame; 2], StageError> {
    use contract::fit::model_groups::{DU, G_MODEL, RESIDUAL, TABLE};
    let table = TABLE.of(fit)?;
    let (du, model, residual) = (DU.read(table)?, G_MODEL.read(table)?, RESIDUAL.read(table)?);
    let above: Vec<usize> = contract::fit::part_rows(table, Part::Total)?
        .into_iter()
        .filter(|&k| du[k] > 0.0)
        .collect();
    let pick = |values: &[f64]| -> Vec<f64> { above.iter().map(|&k| values[k]).collect() };
    Ok([
        series_of("kernel", "model", pick(&du), pick(&model), None)?,
        series_of("residuals", "model", pick(&du), pick(&residual), None)?,
    ])
}

/// The fit's mean shape `alpha x^-beta exp(-x^2 / 2 sigma^2)` on the kernel's
/// `x` within the fit range.
fn fitted_shape(kernel: &DataFrame, fit: &Input) -> Result<DataFrame, StageError> {
    use contract::figures::points::X;
    use contract::fit::{ALPHA, BETA, RANGE_MAX, RANGE_MIN, SIGMA, TABLE};
    let table = frame(TABLE.of(fit)?)?;
    let first = |name: &str| -> Result<f64, StageError> {
        let column = table.column(name).map_err(failed)?.f64().map_err(failed)?;
        column.get(0).ok_or_else(|| failed("empty fit table"))
    };
    let (alpha, beta, sigma) = (
        first(ALPHA.value.name)?,
        first(BETA.value.name)?,
        first(SIGMA.value.name)?,
    );
    let (low, high) = (first(RANGE_MIN.name)?, first(RANGE_MAX.name)?);
    let xs: Vec<f64> = kernel
        .column(X.name)
        .map_err(failed)?
        .f64()
        .map_err(failed)?
        .iter()
        .flatten()
        .filter(|x| (low..=high).contains(x))
        .collect();
    let ys: Vec<f64> = xs
        .iter()
        .map(|x| alpha * libm::pow(*x, -beta) * libm::exp(-x * x / (2.0 * sigma * sigma)))
        .collect();
    series_of("kernel", "fit", xs, ys, None)
}
