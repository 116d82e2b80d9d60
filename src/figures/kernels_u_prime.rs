//! `kernels_u_prime_<id>`: the kernels of one potential at each `u'`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{log_groups, stack};
use super::kernel_groups::{GROUPS_PER_DECADE, resolved};
use super::{Axis, FigureKind, G_AXIS, Layout, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// `G(u' -> u)` of one potential at each configured `u'` (dilute), both
/// sides of `u'` on log axes of `|u - u'|` (paper: `u' = 0, -0.25, -3`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KernelsAtUPrime {
    /// The potential's id.
    pub id: String,
    /// The `u'` of each kernel input.
    pub u_primes: Vec<f64>,
}

impl FigureKind for KernelsAtUPrime {
    fn name(&self) -> String {
        format!("kernels_u_prime_{}", self.id)
    }

    fn description(&self) -> String {
        "G(u' -> u) at each u' (dilute) against |u - u'| on both sides of u', log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel {
                dashed: true,
                ..Panel::new(
                    "kernels",
                    Axis::log("|u − u'| [v_th]"),
                    Axis::log(G_AXIS),
                    vec![("", Style::Band)],
                )
            }],
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
    let (replicates, du) = contract::kernel::replicates::read(input)?;
    let below: Vec<f64> = du.iter().map(|d| -d).collect();
    [("u > u'", du), ("u < u'", below)]
        .iter()
        .map(|(side, x)| {
            // The legend's minus sign is U+2212, as on the axes.
            let name = format!("u' = {}, {side}", u_prime.to_string().replace('-', "−"));
            resolved(&log_groups(
                ("kernels", &name),
                x,
                &replicates,
                GROUPS_PER_DECADE,
            )?)
        })
        .collect()
}
