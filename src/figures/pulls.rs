//! `pulls`: the study's cross-checks' pulls against the standard normal.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, numbers, series_of, stack, standard_normal};
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// The pulls of the study's cross-checks (the `pulls` stage) against
/// the standard normal they follow when the errors are right.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "pulls")]
pub struct Pulls {}

impl Pulls {
    /// The pulls of the study's cross-checks, when the study computes them.
    pub fn planned(_study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        Drawn::if_present(Pulls {}, instances::pulls(), present)
    }
}

impl FigureKind for Pulls {
    fn topic(&self) -> Topic {
        Topic::Checks
    }

    fn name(&self) -> String {
        "pulls".into()
    }

    fn description(&self) -> String {
        "the pulls (a - b) / combined error of every cross-check of the study (pulls stage): their histogram as a density in bins of 0.5 on [-4, 4] (pulls beyond counted in the outer bins), +- Poisson error, against the standard normal density they follow when the errors are right".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![Panel::new(
                "pulls",
                Axis::linear("pull = (a - b) / combined error"),
                Axis::linear("density"),
                vec![(NORMAL, Style::Line)],
            )],
        }
    }

    /// The pulls figure: the histogram of the pulls with a value as a density
    /// (count / (pulls x bin width), +- its Poisson error), those beyond the
    /// range in the outer bins, and the standard normal density.
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::pulls::checks::{PULL, TABLE};
        let table = frame(TABLE.of(&inputs[0])?)?;
        let values: Vec<f64> = numbers(&table, PULL.name)?
            .into_iter()
            .filter(|v| v.is_finite())
            .collect();
        let bins = (2.0 * PULL_RANGE / PULL_BIN) as usize;
        let mut counts = vec![0.0; bins];
        for value in &values {
            let k = ((value + PULL_RANGE) / PULL_BIN)
                .floor()
                .clamp(0.0, (bins - 1) as f64);
            counts[k as usize] += 1.0;
        }
        let per_pull = 1.0 / (values.len() as f64 * PULL_BIN);
        let centres = (0..bins)
            .map(|k| -PULL_RANGE + (k as f64 + 0.5) * PULL_BIN)
            .collect();
        let normal_x: Vec<f64> = (0..=160)
            .map(|k| -PULL_RANGE + 0.05 * f64::from(k))
            .collect();
        stack(vec![
            series_of(
                "pulls",
                &format!("{} pulls", values.len()),
                centres,
                counts.iter().map(|c| c * per_pull).collect(),
                Some(counts.iter().map(|c| c.sqrt() * per_pull).collect()),
            )?,
            standard_normal("pulls", NORMAL, normal_x)?,
        ])
    }
}

/// Legend label of the standard normal density in [`Pulls`].
const NORMAL: &str = "N(0, 1)";
/// Width of [`Pulls`]' bins.
const PULL_BIN: f64 = 0.5;
/// Its bins cover `[-PULL_RANGE, PULL_RANGE]`.
const PULL_RANGE: f64 = 4.0;
