//! `kernel_fit_<id>`: a kernel with its fitted shape.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, frame, series_of, stack};
use super::kernel_groups::{GROUPS_PER_DECADE, positive_kernel};
use super::{Axis, DU_AXIS, FigureKind, G_AXIS, Layout, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// `G(0 -> u)` of one potential with its fitted shape `alpha x^-beta exp(-x^2/2 sigma^2)`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KernelFit {
    /// The potential's id (the figure's name).
    pub id: String,
    /// Its legend label.
    pub label: String,
}

impl FigureKind for KernelFit {
    fn name(&self) -> String {
        format!("kernel_fit_{}", self.id)
    }

    fn description(&self) -> String {
        "G(0 -> u) against u - u' > 0, +- standard error, with the fitted shape alpha x^-beta exp(-x^2 / 2 sigma^2); bars whose lower end is at or below zero are drawn open downward (an arrow to the frame's bottom)".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel::new(
                "kernel",
                Axis::log(DU_AXIS),
                Axis::log(G_AXIS),
                vec![("fit", Style::Line), ("Monte Carlo", Style::Markers)],
            )],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        let measured = positive_kernel(&inputs[0], "kernel", "Monte Carlo", GROUPS_PER_DECADE)?;
        let fitted = fitted_shape(&measured, &inputs[1])?;
        stack(vec![measured, fitted])
    }
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
