//! `near_integrable`: how the rates vanish near the Calogero point `n = 2`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::frames::{failed, series_of, stack};
use super::gaps::{GAS, ONE_PARTICLE};
use super::{Axis, Drawn, FigureKind, Layout, Panel, Style, Topic};
use crate::config::Study;
use crate::contract;
use crate::contract::instances;
use crate::pipeline::{Input, InstanceId, StageError};

/// How the rates of `r^-n` vanish as `n -> 2+`: `Gamma` and the gaps
/// against `n - 2` with their fitted near-integrable laws (a), the gaps
/// over `Gamma` (b).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "near_integrable")]
pub struct NearIntegrable {}

impl NearIntegrable {
    /// The exponents near `n = 2`, when the study computes them.
    pub fn planned(_study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        Drawn::if_present(NearIntegrable {}, instances::near_integrable(), present)
    }
}

impl FigureKind for NearIntegrable {
    fn topic(&self) -> Topic {
        Topic::Rates
    }

    fn name(&self) -> String {
        "near_integrable".into()
    }

    fn description(&self) -> String {
        "the rates of the inverse power laws near the Calogero point n = 2 (near_integrable stage) against n - 2, log axes: Gamma (the tagged variance rate at u' = 0), the gap of the gas (linearized three-body operator) and of one particle (tagged generator), +- jackknife standard error, each with its fitted law A (n - 2)^p exp(q (n - 2)) over the fitted range (a, p with its error in the legend; perturbation theory: p = 2); the gaps over Gamma (b, p = 0 expected). Only resolved rates (positive by three standard errors) are drawn and fitted".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            panels: vec![
                Panel {
                    paired: true,
                    pair_order: NEAR_INTEGRABLE_PAIRS,
                    ..Panel::new(
                        "rates",
                        Axis::log("n - 2"),
                        Axis::log("rate [ρ² l v_th]"),
                        vec![("fit", Style::Line)],
                    )
                },
                Panel {
                    paired: true,
                    pair_order: NEAR_INTEGRABLE_PAIRS,
                    ..Panel::new(
                        "ratio",
                        Axis::log("n - 2"),
                        Axis::linear("gap / Γ"),
                        vec![("fit", Style::Line)],
                    )
                },
            ],
        }
    }

    /// The near-integrable figure: per fitted quantity its resolved rates
    /// against `n - 2` and its law over the fitted range, paired by name.
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        use contract::near_integrable::{fits, rates};
        let input = &inputs[0];
        let rates_table = rates::TABLE.of(input)?;
        let fits_table = fits::TABLE.of(input)?;
        let excess = rates::EXCESS.read(rates_table).map_err(failed)?;
        let quantities = fits::QUANTITY.read(fits_table).map_err(failed)?;
        let exponents = fits::EXPONENT.read(fits_table).map_err(failed)?;
        let amplitudes = fits::AMPLITUDE.read(fits_table).map_err(failed)?;
        let corrections = fits::CORRECTION.read(fits_table).map_err(failed)?;
        let mut parts = Vec::new();
        for (panel, quantity, label, pair) in [
            ("rates", "variance_rate", "Γ", rates::VARIANCE_RATE),
            ("rates", "gap", GAS, rates::GAP),
            ("rates", "particle_gap", ONE_PARTICLE, rates::PARTICLE_GAP),
            (
                "ratio",
                "gap_over_variance_rate",
                GAS,
                rates::GAP_OVER_VARIANCE_RATE,
            ),
            (
                "ratio",
                "particle_gap_over_variance_rate",
                ONE_PARTICLE,
                rates::PARTICLE_GAP_OVER_VARIANCE_RATE,
            ),
        ] {
            let row = quantities
                .iter()
                .position(|q| q == quantity)
                .ok_or_else(|| failed(format!("near_integrable has no fit of {quantity}")))?;
            let values = pair.read(rates_table).map_err(failed)?;
            let used: Vec<usize> = (0..values.len())
                .filter(|&i| contract::near_integrable::resolved(values[i]))
                .collect();
            parts.push(series_of(
                panel,
                &format!("spectrum, {label}"),
                used.iter().map(|&i| excess[i]).collect(),
                used.iter().map(|&i| values[i].mean).collect(),
                Some(used.iter().map(|&i| values[i].stderr).collect()),
            )?);
            let (exponent, amplitude, correction) =
                (exponents[row], amplitudes[row].mean, corrections[row].mean);
            if !exponent.mean.is_finite() {
                continue;
            }
            let fitted = used.iter().map(|&i| excess[i]);
            let (xs, ys) = fitted_law(fitted, amplitude, exponent.mean, correction);
            let name = format!(
                "fit, p = {:.3} ± {:.3}, {label}",
                exponent.mean, exponent.stderr
            );
            parts.push(series_of(panel, &name, xs, ys, None)?);
        }
        stack(parts)
    }
}

/// The fitted law `A x^p exp(q x)` (`x = n - 2`) on [`FIT_CURVE_POINTS`]
/// log-spaced intervals over the range of the `fitted` excesses: its `x`
/// and its rate.
fn fitted_law(
    fitted: impl Iterator<Item = f64>,
    amplitude: f64,
    exponent: f64,
    correction: f64,
) -> (Vec<f64>, Vec<f64>) {
    let (low, high) = fitted.fold((f64::INFINITY, 0.0_f64), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    });
    let xs: Vec<f64> = (0..=FIT_CURVE_POINTS)
        .map(|k| low * libm::pow(high / low, k as f64 / FIT_CURVE_POINTS as f64))
        .collect();
    let ys = xs
        .iter()
        .map(|&x| amplitude * libm::pow(x, exponent) * libm::exp(correction * x))
        .collect();
    (xs, ys)
}

/// Intervals of a fitted law's curve (log-spaced in `n - 2`).
const FIT_CURVE_POINTS: usize = 48;

/// The `near_integrable` figure's pairs, coloured alike in both panels.
const NEAR_INTEGRABLE_PAIRS: &[&str] = &["Γ", GAS, ONE_PARTICLE];
