//! `kernels_u_prime_<id>`: the kernels of one potential at each `u'`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{log_groups, stack};
use super::kernel_groups::{GROUPS_PER_DECADE, resolved};
use super::planning::main_potential;
use super::{Axis, Drawn, FigureKind, G_AXIS, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// `G(u' -> u)` of one potential at each configured `u'` (dilute), above
/// and below `u'` in two panels, on log axes of `|u - u'|` (paper: `u' = 0,
/// -0.25, -3`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "kernels_at_u_prime")]
pub struct KernelsAtUPrime {
    /// The potential's id.
    pub id: String,
    /// The `u'` of each kernel input.
    pub u_primes: Vec<f64>,
}

impl KernelsAtUPrime {
    /// The main potential's kernels at each dilute `u'`, when there is more
    /// than one.
    pub fn planned(study: &Study, _present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let Some(p) = main_potential(study) else {
            return Vec::new();
        };
        let u_primes: Vec<f64> = study
            .kernel_targets()
            .into_iter()
            .filter(|(_, density)| *density == 0.0)
            .map(|(u_prime, _)| u_prime)
            .collect();
        if u_primes.len() < 2 {
            return Vec::new();
        }
        let inputs = u_primes
            .iter()
            .map(|&u| instances::kernel(&study.kernel_params(p, u, 0.0)))
            .collect();
        let figure = KernelsAtUPrime {
            id: p.id(),
            u_primes,
        };
        vec![Drawn::new(figure, inputs)]
    }
}

impl FigureKind for KernelsAtUPrime {
    fn topic(&self) -> Topic {
        Topic::MainKernel
    }

    fn name(&self) -> String {
        format!("kernels_u_prime_{}", self.id)
    }

    fn description(&self) -> String {
        "G(u' -> u) at each u' (dilute) against |u - u'|, above u' (left) and below (right), log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
    }

    /// One panel per side of `u'`, a colour and dash per `u'`: twelve
    /// series in one panel repeated the palette's seven colours.
    fn layout(&self) -> Layout {
        let side = |name, title| Panel {
            dashed: true,
            title,
            ..Panel::new(
                name,
                Axis::log("|u − u'| [v_th]"),
                Axis::log(G_AXIS),
                vec![("", Style::Band)],
            )
        };
        Layout {
            panels: vec![side(ABOVE, "u > u'"), side(BELOW, "u < u'")],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        let mut parts = Vec::new();
        for (input, u_prime) in inputs.iter().zip(&self.u_primes) {
            parts.extend(kernel_sides(input, *u_prime)?);
        }
        stack(parts)
    }
}

/// `G(u' -> u)` of a kernel artifact above and below `u'`, each averaged
/// over log-spaced groups of `|u - u'|` and left with its resolved groups.
fn kernel_sides(input: &Input, u_prime: f64) -> Result<Vec<DataFrame>, StageError> {
    let (replicates, du) =
        contract::kernel::replicates::read(input, contract::kernel::replicates::G)?;
    let below: Vec<f64> = du.iter().map(|d| -d).collect();
    // The legend's minus sign is U+2212, as on the axes.
    let name = format!("u' = {}", u_prime.to_string().replace('-', "−"));
    [(ABOVE, du), (BELOW, below)]
        .iter()
        .map(|(panel, x)| {
            resolved(&log_groups(
                (panel, &name),
                x,
                &replicates,
                GROUPS_PER_DECADE,
            )?)
        })
        .collect()
}

/// The panel of the kernels above `u'`.
const ABOVE: &str = "above";

/// The panel of the kernels below `u'`.
const BELOW: &str = "below";
