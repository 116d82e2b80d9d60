//! `kernels`: the kernel of every inverse power law.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::stack;
use super::kernel_groups::{GROUPS_PER_DECADE, positive_kernel, resolved};
use super::{Axis, DU_AXIS, FigureKind, G_AXIS, Layout, Panel, Style};
use crate::pipeline::{Input, StageError};

/// `G(0 -> u)` of every inverse power law on log axes (paper: the kernel for every n).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KernelsEveryN {
    /// Legend label of each kernel input.
    pub labels: Vec<String>,
}

impl FigureKind for KernelsEveryN {
    fn name(&self) -> String {
        "kernels".into()
    }

    fn description(&self) -> String {
        "G(0 -> u) of every inverse power law (u' = 0, dilute) against u - u' > 0, log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
    }

    fn layout(&self) -> Layout {
        kernels_layout()
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        every_kernel(&self.labels, inputs)
    }
}

/// The layout of a figure of kernels `G(0 -> u)` on log axes, one band each.
pub(super) fn kernels_layout() -> Layout {
    Layout {
        panels: vec![Panel::new(
            "kernels",
            Axis::log(DU_AXIS),
            Axis::log(G_AXIS),
            vec![("", Style::Band)],
        )],
    }
}

/// The resolved groups of each kernel input, as the series of its label.
pub(super) fn every_kernel(labels: &[String], inputs: &[Input]) -> Result<DataFrame, StageError> {
    let parts = labels
        .iter()
        .zip(inputs)
        .map(|(label, input)| {
            positive_kernel(input, "kernels", label, GROUPS_PER_DECADE)
                .and_then(|groups| resolved(&groups))
        })
        .collect::<Result<Vec<_>, _>>()?;
    stack(parts)
}
