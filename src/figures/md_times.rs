//! `md_times_<ring>`: `h(u, t)` of one ring at several final times.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, rows_where, series, stack};
use super::planning::compared;
use super::{Axis, DU_AXIS, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::MdParams;
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// `h(u, t)` of one ring at several final times: MD (tagged) and Boltzmann.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "md_times")]
pub struct MdTimes {
    /// The ring's name (the figure's).
    pub ring: String,
    /// The rings simulating it to each time (rows of the comparison table).
    pub rings: Vec<String>,
    /// Their final times, ns.
    pub times_ns: Vec<f64>,
}

impl MdTimes {
    /// `h(u, t)` at several times: the first compared ring simulated to more
    /// than one final time (same gas and ring), its rings in order of time,
    /// when `compare` is planned.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        if compared(study, present).is_none() {
            return Vec::new();
        }
        let rings = study.compared_rings();
        let same_ring = |a: &MdParams, b: &MdParams| {
            a.gas == b.gas && a.particles == b.particles && a.radius_um == b.radius_um
        };
        let times = rings.iter().find_map(|ring| {
            let mut group: Vec<&MdParams> = rings
                .iter()
                .filter(|other| same_ring(ring, other))
                .collect();
            if group.len() < 2 {
                return None;
            }
            group.sort_by(|a, b| a.final_time_ns.total_cmp(&b.final_time_ns));
            Some(MdTimes {
                ring: group.last().map(|r| r.name.clone()).unwrap_or_default(),
                rings: group.iter().map(|r| r.name.clone()).collect(),
                times_ns: group.iter().map(|r| r.final_time_ns).collect(),
            })
        });
        times
            .map(|figure| Drawn::new(figure, vec![instances::compare()]))
            .into_iter()
            .collect()
    }
}

impl FigureKind for MdTimes {
    fn topic(&self) -> Topic {
        Topic::MolecularDynamics
    }

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
