//! `kicks_<id>`: the mono-energetic collisions' final velocities.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, series_by, stack};
use super::planning::main_potential;
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::physics::potential::Potential;
use crate::pipeline::{Input, InstanceId, StageError};

/// The special particle's final velocity against the launch delay, one
/// curve per scanned launch pair (mono-energetic collisions).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "kicks")]
pub struct Kicks {
    /// The potential's id.
    pub id: String,
}

impl Kicks {
    /// The main potential's kicks, with a scan.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let kicks =
            |p: Potential| Drawn::if_present(Kicks { id: p.id() }, instances::scan(&p), present);
        main_potential(study).into_iter().flat_map(kicks).collect()
    }
}

impl FigureKind for Kicks {
    fn topic(&self) -> Topic {
        Topic::MainKernel
    }

    fn name(&self) -> String {
        format!("kicks_{}", self.id)
    }

    fn description(&self) -> String {
        "final velocity u1f of the special particle (u1 = 0) against the launch delay, per scanned launch pair, +- error bound".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel::new(
                "kick",
                Axis::linear("launch delay Δt [l / v_th]"),
                Axis::linear("u1f [v_th]"),
                vec![("", Style::Line)],
            )],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::scan::LAUNCH;
        use contract::scan::curve::{LAUNCH_DELAY, TABLE, U1_FINAL, U1_FINAL_ERROR};
        let curve = frame(TABLE.of(&inputs[0])?)?;
        let columns = (LAUNCH_DELAY.name, U1_FINAL.name, Some(U1_FINAL_ERROR.name));
        stack(series_by(
            &curve,
            "kick",
            LAUNCH.name,
            |launch| launch.to_string(),
            columns,
        )?)
    }
}
