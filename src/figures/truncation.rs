//! `truncation_<id>`: the self variance rate against the truncation.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, frame, series};
use super::planning::{dilute, main_potential};
use super::{Axis, Drawn, FigureKind, Layout, Mark, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::pipeline::{Input, InstanceId, StageError};

/// `a_n(X)`: the self variance rate against the truncation `X`, with the
/// paper's `X = 0.04` marked.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "truncation")]
pub struct Truncation {
    /// The potential's id.
    pub id: String,
    /// Its legend label.
    pub label: String,
}

impl Truncation {
    /// The main potential's `a_n(X)`.
    pub fn planned(study: &Study, _present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let Some(p) = main_potential(study) else {
            return Vec::new();
        };
        let figure = Truncation {
            id: p.id(),
            label: p.family().label(),
        };
        vec![Drawn::new(
            figure,
            vec![dilute(study, contract::moments::STAGE, &p)],
        )]
    }
}

impl FigureKind for Truncation {
    fn topic(&self) -> Topic {
        Topic::MainKernel
    }

    fn name(&self) -> String {
        format!("truncation_{}", self.id)
    }

    fn description(&self) -> String {
        "self variance rate a_n(X) of the kernel truncated at |u - u'| <= X, with the paper's X = 0.04".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel {
                marks: vec![Mark {
                    x: 0.04,
                    label: "X = 0.04 (paper)",
                }],
                ..Panel::new(
                    "a_n",
                    Axis::log("X [v_th]"),
                    Axis::linear("a_n(X) [ρ² l v_th]"),
                    vec![("", Style::Band)],
                )
            }],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::moments::{SELF_VARIANCE, TABLE, TRUNCATION};
        let (input, label) = (&inputs[0], &self.label);
        let all = frame(TABLE.of(input)?)?;
        let mask = all.column(TRUNCATION.name).map_err(failed)?.is_not_null();
        let finite = all.filter(&mask).map_err(failed)?;
        series(
            &finite,
            "a_n",
            label,
            (
                TRUNCATION.name,
                SELF_VARIANCE.value.name,
                Some(SELF_VARIANCE.stderr.name),
            ),
        )
    }
}
