//! `kernels`: the kernel of every inverse power law.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::stack;
use super::kernel_groups::{GROUPS_PER_DECADE, positive_kernel, resolved};
use super::planning::{dilute, kicked};
use super::{Axis, DU_AXIS, Drawn, FigureKind, G_AXIS, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::pipeline::{Input, InstanceId, StageError};

/// `G(0 -> u)` of every inverse power law on log axes (paper: the kernel for every n).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "kernels_every_n")]
pub struct KernelsEveryN {
    /// Legend label of each kernel input.
    pub labels: Vec<String>,
}

impl KernelsEveryN {
    /// The kernels of every scale-free potential with kicks (the inverse
    /// power laws) in one figure.
    pub fn planned(study: &Study, _present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let scale_free: Vec<_> = kicked(study)
            .into_iter()
            .filter(|p| p.family().theta().is_none())
            .collect();
        if scale_free.is_empty() {
            return Vec::new();
        }
        let labels = scale_free.iter().map(|p| p.family().label()).collect();
        let inputs = scale_free
            .iter()
            .map(|p| dilute(study, contract::kernel::STAGE, p))
            .collect();
        vec![Drawn::new(KernelsEveryN { labels }, inputs)]
    }
}

impl FigureKind for KernelsEveryN {
    fn topic(&self) -> Topic {
        Topic::Kernels
    }

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
