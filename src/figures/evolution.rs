//! `evolution_<instance>`: the tagged particle's `h(u, t)` relaxing to `f0`.

use polars::prelude::{ChunkCompareEq, DataFrame};
use serde::Serialize;

use super::frames::{failed, frame, series, series_of, stack, standard_normal};
use super::planning::spread;
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// The tagged particle's `h(u, t)` approaching `f0` (a), the early
/// variance growing as `t kappa_2` (b), and the early `h` scaled to unit
/// variance against the standard normal (c).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "evolution")]
pub struct Evolution {
    /// The evolved kernel's instance (`ipp-6_u0_rho0`).
    pub instance: String,
    /// Times drawn in panel (a), `1/Gamma`.
    pub times: Vec<f64>,
}

/// Curves of `h(u, t)` in the evolution figure, at most.
const EVOLUTION_CURVES: usize = 5;

impl Evolution {
    /// `h(u, t)` at up to `EVOLUTION_CURVES` of the evolution's times.
    pub fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let Some(evolve) = study.evolve_params() else {
            return Vec::new();
        };
        let instance = instances::target(&evolve.kernel);
        let id = InstanceId::new(contract::evolve::STAGE, &instance);
        if !present(&id) || evolve.times.is_empty() {
            return Vec::new();
        }
        let times = spread(&evolve.times, EVOLUTION_CURVES);
        vec![Drawn::new(Evolution { instance, times }, vec![id])]
    }
}

impl FigureKind for Evolution {
    fn topic(&self) -> Topic {
        Topic::Relaxation
    }

    fn name(&self) -> String {
        format!("evolution_{}", self.instance)
    }

    fn description(&self) -> String {
        "tagged particle's h(u, t) relaxing to f0 (a, log scale), the early variance of h with its closed form t kappa_2 (b), and the early h at each of evolve.early_times scaled to unit variance against the standard normal (c): a cusp from the kernel at first, the central limit's Gaussian by t ~ 1e-2 / Gamma; bars and bands whose lower end is at or below zero are drawn open downward (to the frame's bottom)".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel::new(
                    "h",
                    Axis::linear("u [v_th]"),
                    Axis::log("h(u, t) [1 / v_th]"),
                    vec![("", Style::Line)],
                ),
                Panel::new(
                    "variance",
                    Axis::log("t [1 / Γ]"),
                    Axis::log("variance of h [v_th²]"),
                    vec![("t κ₂", Style::Line)],
                ),
                Panel::new(
                    "early",
                    Axis::linear("(u − u') / s, s² = variance of h"),
                    Axis::log("s h(u, t)"),
                    vec![(STANDARD_NORMAL, Style::Line), ("", Style::Band)],
                ),
            ],
        }
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::evolve::{TIME_GAMMA, early_summary, evolution};
        let (input, times) = (&inputs[0], &self.times);
        let h = frame(evolution::TABLE.of(input)?)?;
        let at = |t: f64| -> Result<DataFrame, StageError> {
            let mask = h
                .column(TIME_GAMMA.name)
                .map_err(failed)?
                .f64()
                .map_err(failed)?
                .equal(t);
            h.filter(&mask).map_err(failed)
        };
        let tagged =
            |pair: &contract::Pair| (evolution::U.name, pair.value.name, Some(pair.stderr.name));
        let mut parts = Vec::new();
        for &t in times {
            let label = format!("t = {t} / Γ");
            parts.push(series(&at(t)?, "h", &label, tagged(&evolution::H_TAGGED))?);
        }
        let first = times.first().ok_or_else(|| failed("no time to draw"))?;
        let equilibrium = (evolution::U.name, evolution::EQUILIBRIUM_TAGGED.name, None);
        parts.push(series(&at(*first)?, "h", "f0", equilibrium)?);
        let early = frame(early_summary::TABLE.of(input)?)?;
        let variance =
            |pair: &contract::Pair| (TIME_GAMMA.name, pair.value.name, Some(pair.stderr.name));
        parts.push(series(
            &early,
            "variance",
            "master equation",
            variance(&early_summary::VARIANCE),
        )?);
        parts.push(series(
            &early,
            "variance",
            "t κ₂",
            variance(&early_summary::VARIANCE_CLOSED_FORM),
        )?);
        parts.extend(early_shapes(input)?);
        stack(parts)
    }
}

/// Reach of the early panel, in standard deviations of `h`.
const EARLY_REACH: f64 = 5.0;

/// Panel (c): the early `h(u, t)` at each of `evolve.early_times`, scaled to
/// unit variance (`x = (u - u') / s`, `y = s h`, `s^2` its variance at `t`),
/// against the standard normal density: a cusp inherited from the kernel at
/// the earliest times, the central limit's Gaussian by `t ~ 1e-2 / Gamma`
/// (physics.md §4).
fn early_shapes(input: &Input) -> Result<Vec<DataFrame>, StageError> {
    use contract::evolve::{TIME_GAMMA, early_evolution, early_summary};
    let summary = early_summary::TABLE.of(input)?;
    let h = early_evolution::TABLE.of(input)?;
    let (times, variances) = (
        TIME_GAMMA.read(summary)?,
        early_summary::VARIANCE.read(summary)?,
    );
    let (at, du, values) = (
        TIME_GAMMA.read(h)?,
        early_evolution::DU.read(h)?,
        early_evolution::H.read(h)?,
    );
    let mut parts = Vec::new();
    for (&t, variance) in times.iter().zip(&variances) {
        let scale = variance.mean.sqrt();
        let (mut xs, mut ys, mut errors) = (Vec::new(), Vec::new(), Vec::new());
        for k in (0..du.len()).filter(|&k| at[k] == t) {
            let x = du[k] / scale;
            if x.abs() <= EARLY_REACH {
                xs.push(x);
                ys.push(values[k].mean * scale);
                errors.push(values[k].stderr * scale);
            }
        }
        // Three significant digits: a ring's time converted to 1/Gamma
        // carries seventeen.
        let t: f64 = format!("{t:.2e}").parse().map_err(failed)?;
        parts.push(series_of(
            "early",
            &format!("t = {t} / Γ"),
            xs,
            ys,
            Some(errors),
        )?);
    }
    let xs: Vec<f64> = (-100..=100)
        .map(|k| EARLY_REACH * f64::from(k) / 100.0)
        .collect();
    parts.push(standard_normal("early", STANDARD_NORMAL, xs)?);
    Ok(parts)
}

/// The reference series of the early panel.
const STANDARD_NORMAL: &str = "standard normal";
