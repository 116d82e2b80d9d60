//! `truncation_<id>`: the self variance rate against the truncation.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, frame, series};
use super::{Axis, FigureKind, Layout, Mark, Panel, Style};
use crate::contract;
use crate::pipeline::{Input, StageError};

/// `a_n(X)`: the self variance rate against the truncation `X`, with the
/// paper's `X = 0.04` marked.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Truncation {
    /// The potential's id.
    pub id: String,
    /// Its legend label.
    pub label: String,
}

impl FigureKind for Truncation {
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
