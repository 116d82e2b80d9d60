//! `finite_size`: MD over Boltzmann window variances against `rho l`.

use polars::prelude::{ChunkCompareIneq, DataFrame};
use serde::Serialize;

use super::frames::{failed, frame, numbers, series_by, stack};
use super::planning::compared;
use super::{Axis, Drawn, FigureKind, Layout, Panel, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// MD over Boltzmann window variances against `rho l`, one series per `N`:
/// tagged (a) and thermal (b) estimators.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "finite_size")]
pub struct FiniteSize {}

impl FiniteSize {
    /// The finite-size table's rings, when `compare` is planned and compares
    /// rings at `u' = 0`.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        if compared(study, present).is_none() || study.compared_rings().is_empty() {
            return Vec::new();
        }
        vec![Drawn::new(FiniteSize {}, vec![instances::compare()])]
    }
}

impl FigureKind for FiniteSize {
    fn topic(&self) -> Topic {
        Topic::MolecularDynamics
    }

    fn name(&self) -> String {
        "finite_size".into()
    }

    fn description(&self) -> String {
        "MD / Boltzmann window variance at t_f against rho l, one series per N (drawn side by side: N = 41, 81, 161 at one rho l are moved apart by 1.2% of the axis), tagged (a) and thermal (b) estimators; the rings at the study's common rho^2 l v_th t_f (others, such as a ring's earlier time, are in the table, not drawn)".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: [
                ("tagged", "tagged particles"),
                ("thermal", "thermal estimator"),
            ]
            .into_iter()
            .map(|(name, title)| Panel {
                dodge: true,
                title,
                level: Some(1.0),
                ..Panel::new(
                    name,
                    Axis::linear("ρ l"),
                    Axis::linear("MD / Boltzmann"),
                    Vec::new(),
                )
            })
            .collect(),
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::compare::finite_size::{
            DENSITY, PARTICLES, RATIO, SCALED_TIME, TABLE, THERMAL_RATIO,
        };
        let rings = at_common_time(&frame(TABLE.of(&inputs[0])?)?, SCALED_TIME.name)?;
        let named = |n: &str| format!("N = {n}");
        let pair = |pair: &contract::Pair| (DENSITY.name, pair.value.name, Some(pair.stderr.name));
        let mut parts = series_by(&rings, "tagged", PARTICLES.name, named, pair(&RATIO))?;
        parts.extend(series_by(
            &rings,
            "thermal",
            PARTICLES.name,
            named,
            pair(&THERMAL_RATIO),
        )?);
        stack(parts)
    }
}

/// The rows of `rings` at their median scaled time `rho^2 l v_th t_f` (within
/// 1e-6 of it): a figure against `rho l` compares rings at one scaled time.
fn at_common_time(rings: &DataFrame, scaled_time: &str) -> Result<DataFrame, StageError> {
    let mut sorted = numbers(rings, scaled_time)?;
    sorted.sort_by(f64::total_cmp);
    let median = *sorted
        .get(sorted.len() / 2)
        .ok_or_else(|| failed("no ring to draw"))?;
    let times = rings
        .column(scaled_time)
        .map_err(failed)?
        .f64()
        .map_err(failed)?;
    let keep = times.gt_eq(median * (1.0 - 1e-6)) & times.lt_eq(median * (1.0 + 1e-6));
    rings.filter(&keep).map_err(failed)
}
