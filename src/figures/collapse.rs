//! `collapse`: the scaling collapse of rings at one `rho^2 l v_th t_f`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, frame, rows_where, series, stack};
use super::planning::{compared, ring_label};
use super::{Axis, DU_AXIS, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// The scaling collapse: tagged `h(u, t_f)` of rings with one `N` at
/// different `rho` and `T` (the same `rho^2 l v_th t_f`), with Boltzmann.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "collapse")]
pub struct Collapse {
    /// The rings (rows of the comparison table), the first also gives Boltzmann.
    pub rings: Vec<String>,
    /// The legend label of each ring (`N = 161, R = 51.2 mm, 100 meV`).
    pub labels: Vec<String>,
}

impl Collapse {
    /// The collapse of the rings that make it (more than one), when
    /// `compare` is planned.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let collapsing = study.collapse_rings();
        if compared(study, present).is_none() || collapsing.len() < 2 {
            return Vec::new();
        }
        let figure = Collapse {
            rings: collapsing.iter().map(|r| r.name.clone()).collect(),
            labels: collapsing.iter().map(ring_label).collect(),
        };
        vec![Drawn::new(figure, vec![instances::compare()])]
    }
}

impl FigureKind for Collapse {
    fn topic(&self) -> Topic {
        Topic::MolecularDynamics
    }

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
