//! `rates_<id>`: the self drift and variance rates against `u'`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, series, stack};
use super::planning::main_potential;
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::physics::potential::Potential;
use crate::pipeline::{Input, InstanceId, StageError};

/// Self drift and variance rates against `u'`, and the Fokker-Planck drift.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "rates")]
pub struct Rates {
    /// The potential's id.
    pub id: String,
    /// Its legend label.
    pub label: String,
}

impl Rates {
    /// The main potential's rates against `u'`, with a sweep.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let rates = |p: Potential| {
            let figure = Rates {
                id: p.id(),
                label: p.family().label(),
            };
            let sweep = InstanceId::new(contract::sweep::STAGE, &p.id());
            Drawn::if_present(figure, sweep, present)
        };
        main_potential(study).into_iter().flat_map(rates).collect()
    }
}

impl FigureKind for Rates {
    fn topic(&self) -> Topic {
        Topic::Rates
    }

    fn name(&self) -> String {
        format!("rates_{}", self.id)
    }

    fn description(&self) -> String {
        "self variance rate D2 (a) and drift D1 with the Fokker-Planck drift (D2' - u D2)/2 (b) against u'".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel::new(
                    "variance",
                    Axis::linear("u' [v_th]"),
                    Axis::linear("D2 [ρ² l v_th]"),
                    vec![("", Style::Band)],
                ),
                Panel::new(
                    "drift",
                    Axis::linear("u' [v_th]"),
                    Axis::linear("D1 [ρ² l v_th]"),
                    vec![("Fokker", Style::Band), ("", Style::Markers)],
                ),
            ],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::sweep::rates::{
            FOKKER_PLANCK_DRIFT, SELF_DRIFT, SELF_VARIANCE, TABLE, U_PRIME,
        };
        let table = frame(TABLE.of(&inputs[0])?)?;
        let pair = |pair: &contract::Pair| (U_PRIME.name, pair.value.name, Some(pair.stderr.name));
        stack(vec![
            series(&table, "variance", "D2 (Monte Carlo)", pair(&SELF_VARIANCE))?,
            series(&table, "drift", "D1 (Monte Carlo)", pair(&SELF_DRIFT))?,
            series(
                &table,
                "drift",
                "Fokker-Planck (D2' − u D2)/2",
                pair(&FOKKER_PLANCK_DRIFT),
            )?,
        ])
    }
}
