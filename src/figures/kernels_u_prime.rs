//! `kernels_u_prime_<id>`: the kernels of one potential at each `u'`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{log_groups, stack};
use super::kernel_groups::{GROUPS_PER_DECADE, resolved};
use super::{Axis, FigureKind, G_AXIS, Layout, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// `G(u' -> u)` of one potential at each configured `u'` (dilute), above
/// and below `u'` in two panels, on log axes of `|u - u'|` (paper: `u' = 0,
/// -0.25, -3`).
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
