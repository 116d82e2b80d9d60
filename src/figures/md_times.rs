//! `md_times_<ring>`: `h(u, t)` of one ring at several final times.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, rows_where, series, stack};
use super::{Axis, DU_AXIS, FigureKind, Layout, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// `h(u, t)` of one ring at several final times: MD (tagged) and Boltzmann.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MdTimes {
    /// The ring's name (the figure's).
    pub ring: String,
    /// The rings simulating it to each time (rows of the comparison table).
    pub rings: Vec<String>,
    /// Their final times, ns.
    pub times_ns: Vec<f64>,
}

impl FigureKind for MdTimes {
    fn name(&self) -> String {
        format!("md_times_{}", self.ring)
    }

    fn description(&self) -> String {
        "h(u, t) of one ring at several times: Boltzmann (band) and MD, tagged particles (markers)"
            .into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel {
                paired: true,
                ..Panel::new(
                    "h",
                    Axis::linear(DU_AXIS),
                    Axis::linear("h(u, t) [1 / v_th]"),
                    vec![("Boltzmann", Style::Band)],
                )
            }],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::compare::comparison::{DU, H_BOLTZMANN, H_TAGGED, RING, TABLE};
        let (input, rings, times_ns) = (&inputs[0], &self.rings, &self.times_ns);
        let all = frame(TABLE.of(input)?)?;
        let pair = |pair: &contract::Pair| (DU.name, pair.value.name, Some(pair.stderr.name));
        let mut parts = Vec::new();
        for (ring, time) in rings.iter().zip(times_ns) {
            let rows = rows_where(&all, RING.name, ring)?;
            parts.push(series(
                &rows,
                "h",
                &format!("Boltzmann, {time} ns"),
                pair(&H_BOLTZMANN),
            )?);
            parts.push(series(
                &rows,
                "h",
                &format!("MD, {time} ns"),
                pair(&H_TAGGED),
            )?);
        }
        stack(parts)
    }
}
