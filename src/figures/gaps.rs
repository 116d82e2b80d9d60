//! `gaps`: the relaxation gaps of the inverse power laws against `n`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{frame, numbers, series_of, stack};
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// The relaxation gaps of every inverse power law with a spectrum against
/// `n`: over `Gamma` (a) and in rate units beside `Gamma` (b).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "gaps")]
pub struct Gaps {}

impl Gaps {
    /// The gaps against `n`, when at least two inverse power laws (without
    /// a `theta`) have a spectrum; from the `table` stage's rows.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let with_spectrum = study
            .potentials()
            .iter()
            .filter(|p| p.family().theta().is_none() && present(&instances::spectrum(p)))
            .count();
        let table = instances::table();
        if with_spectrum < 2 || !present(&table) {
            return Vec::new();
        }
        vec![Drawn::new(Gaps {}, vec![table])]
    }
}

impl FigureKind for Gaps {
    fn topic(&self) -> Topic {
        Topic::Rates
    }

    fn name(&self) -> String {
        "gaps".into()
    }

    fn description(&self) -> String {
        "relaxation gaps of the inverse power laws against n (the table's rows with a spectrum): the slowest relaxation rate of the gas (linearized three-body operator) and of one particle (tagged generator) over Gamma, the tagged variance rate at u' = 0 (a), and in rate units with Gamma (b, log axis: rates that vanish, n = 2, are left out), +- jackknife standard error".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel::new(
                    "ratio",
                    Axis::linear("n"),
                    Axis::from_zero("gap / Γ"),
                    vec![("", Style::Markers)],
                ),
                Panel::new(
                    "rates",
                    Axis::linear("n"),
                    Axis::log("rate [ρ² l v_th]"),
                    vec![("", Style::Markers)],
                ),
            ],
        }
    }

    /// The gaps figure's panels from the `table` stage's rows of inverse power
    /// laws (no `theta`) with a gap; panel (b) only its positive rates.
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::spectrum::study::{
            GAP, GAP_OVER_VARIANCE_RATE, PARTICLE_GAP, PARTICLE_GAP_OVER_VARIANCE_RATE,
        };
        use contract::table::{A_N, N, TABLE, THETA};
        let table = frame(TABLE.of(&inputs[0])?)?;
        let (n, theta) = (numbers(&table, N.name)?, numbers(&table, THETA.name)?);
        let power_law = |i: usize| n[i].is_finite() && theta[i].is_nan();
        let panel = |panel: &str, title: &str, pair: contract::Pair, positive: bool| {
            let (values, errors) = (
                numbers(&table, pair.value.name)?,
                numbers(&table, pair.stderr.name)?,
            );
            let rows: Vec<usize> = (0..n.len())
                .filter(|&i| {
                    power_law(i) && values[i].is_finite() && (!positive || values[i] > 0.0)
                })
                .collect();
            series_of(
                panel,
                title,
                rows.iter().map(|&i| n[i]).collect(),
                rows.iter().map(|&i| values[i]).collect(),
                Some(rows.iter().map(|&i| errors[i]).collect()),
            )
        };
        stack(vec![
            panel("ratio", GAS, GAP_OVER_VARIANCE_RATE, false)?,
            panel(
                "ratio",
                ONE_PARTICLE,
                PARTICLE_GAP_OVER_VARIANCE_RATE,
                false,
            )?,
            panel("rates", GAS, GAP, true)?,
            panel("rates", ONE_PARTICLE, PARTICLE_GAP, true)?,
            panel("rates", "a_n (Γ)", A_N, true)?,
        ])
    }
}

/// Series title of the linearized operator's rates.
pub(super) const GAS: &str = "gas (linearized operator)";

/// Series title of the tagged generator's rates.
pub(super) const ONE_PARTICLE: &str = "one particle";
