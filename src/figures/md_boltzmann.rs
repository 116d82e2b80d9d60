//! `md_boltzmann_<ring>`: MD against Boltzmann on one ring.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, rows_where, series, stack};
use super::planning::compared;
use super::{Axis, DU_AXIS, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// MD against Boltzmann on one ring: `h(u, t_f)` by both estimators.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "md_boltzmann")]
pub struct MdBoltzmann {
    /// The ring (a row label of the comparison table).
    pub ring: String,
}

impl MdBoltzmann {
    /// The first ring against Boltzmann, when `compare` is planned.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let Some(first) = compared(study, present) else {
            return Vec::new();
        };
        let figure = MdBoltzmann { ring: first.name };
        vec![Drawn::new(figure, vec![instances::compare()])]
    }
}

impl FigureKind for MdBoltzmann {
    fn topic(&self) -> Topic {
        Topic::MolecularDynamics
    }

    fn name(&self) -> String {
        format!("md_boltzmann_{}", self.ring)
    }

    fn description(&self) -> String {
        "h(u, t_f) of a ring: the Boltzmann master equation against MD, tagged particles (a) and the published estimator (b)".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: ["tagged", "published"]
                .into_iter()
                .map(|name| {
                    Panel::new(
                        name,
                        Axis::linear(DU_AXIS),
                        Axis::linear("h(u, t_f) [1 / v_th]"),
                        vec![("Boltzmann", Style::Band)],
                    )
                })
                .collect(),
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::compare::comparison::{DU, H_BOLTZMANN, H_PUBLISHED, H_TAGGED, RING, TABLE};
        let (input, ring) = (&inputs[0], &self.ring);
        let rows = rows_where(&frame(TABLE.of(input)?)?, RING.name, ring)?;
        let pair = |pair: &contract::Pair| (DU.name, pair.value.name, Some(pair.stderr.name));
        stack(vec![
            series(&rows, "tagged", "Boltzmann", pair(&H_BOLTZMANN))?,
            series(&rows, "tagged", "MD, tagged particles", pair(&H_TAGGED))?,
            series(&rows, "published", "Boltzmann", pair(&H_BOLTZMANN))?,
            series(
                &rows,
                "published",
                "MD, published estimator",
                pair(&H_PUBLISHED),
            )?,
        ])
    }
}
