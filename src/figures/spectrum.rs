//! `spectrum_<id>`: the relaxation spectrum of one potential.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, series_of, stack};
use super::planning::main_potential;
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::physics::potential::Potential;
use crate::pipeline::{Input, InstanceId, StageError};
use crate::stats::Estimate;

/// The relaxation spectrum of one potential: the slowest rates over
/// `Gamma` (a), the shapes of the slowest modes (b), the slowest rate
/// against the randomizations it is estimated from (c).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "spectrum")]
pub struct Spectrum {
    /// The potential's id.
    pub id: String,
    /// Its legend label.
    pub label: String,
}

impl Spectrum {
    /// The main potential's relaxation spectrum, with a spectrum.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let spectrum = |p: Potential| {
            let figure = Spectrum {
                id: p.id(),
                label: p.family().label(),
            };
            Drawn::if_present(figure, instances::spectrum(&p), present)
        };
        main_potential(study)
            .into_iter()
            .flat_map(spectrum)
            .collect()
    }
}

impl FigureKind for Spectrum {
    fn topic(&self) -> Topic {
        Topic::Relaxation
    }

    fn name(&self) -> String {
        format!("spectrum_{}", self.id)
    }

    fn description(&self) -> String {
        let label = &self.label;
        format!(
            "relaxation spectrum of {label}: the slowest rates r_k over Gamma (the tagged variance rate at u' = 0) of the linearized three-body operator and of the tagged particle's generator, +- jackknife error (a); the shapes f0 g_k(u) of the two slowest modes of each (b); the slowest rate of each from disjoint groups of randomizations against the group size, +- spread of the groups (c: noise pulls the lowest rate down until the estimate converges)"
        )
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel::new(
                    "rates",
                    Axis::linear("mode k (slowest first)"),
                    Axis::linear("r_k / Γ"),
                    vec![("", Style::Markers)],
                ),
                Panel::new(
                    "modes",
                    Axis::linear("u [v_th]"),
                    Axis::linear("f0 g_k(u) [1 / v_th]"),
                    vec![("", Style::Band)],
                ),
                Panel::new(
                    "scenes",
                    Axis::log("randomizations per estimate"),
                    Axis::linear("r_1 / r_1(all randomizations)"),
                    vec![("", Style::Markers)],
                ),
            ],
        }
    }

    /// The spectrum figure's three panels, per generator (full, tagged).
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::spectrum::{modes, rates, scenes, summary};
        let input = &inputs[0];
        let rates_table = rates::TABLE.of(input)?;
        let modes_table = modes::TABLE.of(input)?;
        let scenes_table = scenes::TABLE.of(input)?;
        let summary_table = summary::TABLE.of(input)?;
        let generators = summary::GENERATOR.read(summary_table).map_err(failed)?;
        let mut parts = Vec::new();
        for (name, title) in [("full", "linearized operator"), ("tagged", "one particle")] {
            if !generators.iter().any(|g| g == name) {
                continue;
            }
            parts.push(generator_rates(rates_table, name, title)?);
            parts.extend(mode_shapes(modes_table, name, title)?);
            // Over the estimate from every randomization (the largest group),
            // so that both generators' convergence reads on one axis.
            let (sizes, rate) = slowest_by_group(scenes_table, name)?;
            let all = rate.last().map_or(f64::NAN, |r| r.mean);
            let ys = rate.iter().map(|r| r.mean / all).collect();
            let errors = rate.iter().map(|r| r.stderr / all).collect();
            parts.push(series_of("scenes", title, sizes, ys, Some(errors))?);
        }
        stack(parts)
    }
}

/// Slowest modes drawn in [`Spectrum`]'s panel (a).
const SPECTRUM_MODES: u32 = 10;
/// Mode shapes drawn per generator in its panel (b).
const SPECTRUM_SHAPES: u32 = 2;

/// The slowest [`SPECTRUM_MODES`] rates of `generator` over `Gamma` against
/// the mode number, as the series `title`.
fn generator_rates(
    table: &arrow_array::RecordBatch,
    generator: &str,
    title: &str,
) -> Result<DataFrame, StageError> {
    use contract::spectrum::rates::{GENERATOR, MODE, RATE_OVER_VARIANCE_RATE};
    let names = GENERATOR.read(table).map_err(failed)?;
    let modes = MODE.read(table).map_err(failed)?;
    let ratios = RATE_OVER_VARIANCE_RATE.read(table).map_err(failed)?;
    let rows: Vec<usize> = (0..names.len())
        .filter(|&i| names[i] == generator && modes[i] <= SPECTRUM_MODES)
        .collect();
    series_of(
        "rates",
        title,
        rows.iter().map(|&i| f64::from(modes[i])).collect(),
        rows.iter().map(|&i| ratios[i].mean).collect(),
        Some(rows.iter().map(|&i| ratios[i].stderr).collect()),
    )
}

/// `f0 g_k(u)` of the slowest [`SPECTRUM_SHAPES`] modes of `generator`.
fn mode_shapes(
    table: &arrow_array::RecordBatch,
    generator: &str,
    title: &str,
) -> Result<Vec<DataFrame>, StageError> {
    use contract::spectrum::modes::{DENSITY, GENERATOR, MODE, U};
    let names = GENERATOR.read(table).map_err(failed)?;
    let modes = MODE.read(table).map_err(failed)?;
    let (u, density) = (
        U.read(table).map_err(failed)?,
        DENSITY.read(table).map_err(failed)?,
    );
    (1..=SPECTRUM_SHAPES)
        .map(|k| {
            let rows: Vec<usize> = (0..names.len())
                .filter(|&i| names[i] == generator && modes[i] == k)
                .collect();
            series_of(
                "modes",
                &format!("{title}, mode {k}"),
                rows.iter().map(|&i| u[i]).collect(),
                rows.iter().map(|&i| density[i].mean).collect(),
                Some(rows.iter().map(|&i| density[i].stderr).collect()),
            )
        })
        .collect()
}

/// The slowest rate of `generator` from groups of each size: sizes and the
/// groups' mean rate (the all-randomization estimate has no spread: error 0).
fn slowest_by_group(
    table: &arrow_array::RecordBatch,
    generator: &str,
) -> Result<(Vec<f64>, Vec<Estimate>), StageError> {
    use contract::spectrum::scenes::{GENERATOR, MODE, RANDOMIZATIONS, RATE};
    let names = GENERATOR.read(table).map_err(failed)?;
    let modes = MODE.read(table).map_err(failed)?;
    let sizes = RANDOMIZATIONS.read(table).map_err(failed)?;
    let rates = RATE.read(table).map_err(failed)?;
    Ok((0..names.len())
        .filter(|&i| names[i] == generator && modes[i] == 1)
        .map(|i| {
            let rate = rates[i];
            let stderr = if rate.stderr.is_finite() {
                rate.stderr
            } else {
                0.0
            };
            (f64::from(sizes[i]), Estimate { stderr, ..rate })
        })
        .unzip())
}
