//! `collapse`: the scaling collapse of rings at one `rho^2 l v_th t_f`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, frame, rows_where, series, stack};
use super::{Axis, DU_AXIS, FigureKind, Layout, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// The scaling collapse: tagged `h(u, t_f)` of rings with one `N` at
/// different `rho` and `T` (the same `rho^2 l v_th t_f`), with Boltzmann.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Collapse {
    /// The rings (rows of the comparison table), the first also gives Boltzmann.
    pub rings: Vec<String>,
    /// The legend label of each ring (`N = 161, R = 51.2 mm, 100 meV`).
    pub labels: Vec<String>,
}

impl FigureKind for Collapse {
    fn name(&self) -> String {
        "collapse".into()
    }

    fn description(&self) -> String {
        "tagged h(u, t_f) of rings with one N at different rho and T and the same rho^2 l v_th t_f (the rho^2 T^(1/2 - 1/n) collapse), with the Boltzmann h".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel::new(
                "collapse",
                Axis::linear(DU_AXIS),
                Axis::linear("h(u, t_f) [1 / v_th]"),
                vec![("Boltzmann", Style::Band)],
            )],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::compare::comparison::{DU, H_BOLTZMANN, H_TAGGED, RING, TABLE};
        let (input, rings, labels) = (&inputs[0], &self.rings, &self.labels);
        let all = frame(TABLE.of(input)?)?;
        let pair = |pair: &contract::Pair| (DU.name, pair.value.name, Some(pair.stderr.name));
        let first = rings.first().ok_or_else(|| failed("no ring to collapse"))?;
        let mut parts = vec![series(
            &rows_where(&all, RING.name, first)?,
            "collapse",
            "Boltzmann",
            pair(&H_BOLTZMANN),
        )?];
        for (ring, label) in rings.iter().zip(labels) {
            let rows = rows_where(&all, RING.name, ring)?;
            parts.push(series(&rows, "collapse", label, pair(&H_TAGGED))?);
        }
        stack(parts)
    }
}
