//! `ternary kernel`: a computed kernel's model (`kernel::model`, the `fit`
//! stage's `kernel_model` tables) evaluated at given `u - u'`, each value
//! with its standard error.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use arrow::array::RecordBatch;

use super::numbers::{fixed, significant, with_error};
use super::rates::{intact, table_of};
use super::show::current_artifact;
use crate::contract;
use crate::kernel::model::{Knots, Warp, interpolate};
use crate::pipeline::store::Store;
use crate::pipeline::{InstanceId, Stage};

/// One side's stored model: its knots, the knot values and their covariance.
struct StoredSide {
    knots: Knots,
    values: Vec<f64>,
    covariance: Vec<f64>,
}

/// A kernel's model evaluated at the `du` asked for.
struct Evaluated {
    /// `<instance> <key>` of the `fit` artifact.
    source: String,
    /// The model's test, as a line.
    goodness: String,
    /// Per `du`: `ln G`, its standard error, and where it lies beyond the knots.
    values: Vec<(f64, f64, String)>,
}

/// The model of the `fit` instance `id` at each of `du`; `Ok(Err(status))`
/// when the kernel has no model.
fn evaluate(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
    du: &[f64],
) -> Result<std::result::Result<Evaluated, String>> {
    let (stage, key) = current_artifact(store, plan, id)?;
    let manifest = intact(store, &stage, &key)?;
    let fit = table_of(store, &manifest, contract::fit::model_fit::TABLE.name)?;
    let status = &contract::fit::model_fit::STATUS.read(&fit)?[0];
    if status != "fitted" {
        return Ok(Err(format!("{id} {key}: no model: {status}")));
    }
    let knots = table_of(store, &manifest, contract::fit::model::TABLE.name)?;
    let covariance = table_of(
        store,
        &manifest,
        contract::fit::model_covariance::TABLE.name,
    )?;
    let sides = [
        stored_side(&knots, &covariance, "below")?,
        stored_side(&knots, &covariance, "above")?,
    ];
    let values = du
        .iter()
        .map(|&x| {
            let side = &sides[usize::from(x > 0.0)];
            (
                side.knots.ln_g(&side.values, x.abs()),
                side.knots.ln_g_stderr(&side.covariance, x.abs()),
                extrapolation(side, x.abs()),
            )
        })
        .collect();
    Ok(Ok(Evaluated {
        source: format!("{id} {key}"),
        goodness: goodness_line(&fit)?,
        values,
    }))
}

/// The header of the value table and one row: `du`, `G` with its error
/// from `ln G` and its error, the relative error, a note.
fn value_rows(out: &mut String, du: &[f64], values: &[(f64, f64, String)]) {
    let _ = writeln!(
        out,
        "{:>12}  {:<28}  {:>9}  note",
        "u - u' [v_th]", "G [rho^2 l v_th / v_th]", "rel. err"
    );
    for (&x, (ln_g, error, note)) in du.iter().zip(values) {
        let g = libm::exp(*ln_g);
        let _ = writeln!(
            out,
            "{:>12}  {:<28}  {:>8}%  {note}",
            significant(x),
            with_error(g, g * error, "-"),
            fixed(100.0 * error, 3),
        );
    }
}

/// The text of `ternary kernel`: `G(u' -> u' + du)` of the model of the
/// `fit` instance `id` (`title` names the kernel) at each of `du`
/// (`v_th`, non-zero), with its standard error, and where the model
/// continues straight beyond its knots.
pub fn kernel_model_text(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
    title: &str,
    du: &[f64],
) -> Result<String> {
    let mut out = String::new();
    match evaluate(store, plan, id, du)? {
        Err(status) => {
            let _ = writeln!(out, "{title}\n{status}");
        }
        Ok(evaluated) => {
            let _ = writeln!(
                out,
                "{title} ({})\n{}",
                evaluated.source, evaluated.goodness
            );
            value_rows(&mut out, du, &evaluated.values);
        }
    }
    Ok(out)
}

/// How `ternary kernel` interpolates between computed potentials: the
/// coordinate (`1/n`, `ln theta`) and each node's value of it with the
/// `fit` instance of its kernel, the target's coordinate, and a line saying
/// what was done.
pub struct Interpolation {
    /// `(coordinate, fit instance)` of each computed kernel used.
    pub nodes: Vec<(f64, InstanceId)>,
    /// The coordinate of the kernel asked for.
    pub at: f64,
    /// What the interpolation is, printed under the title.
    pub method: String,
}

/// The text of `ternary kernel` for a potential the study did not compute:
/// the models of those it did (`interpolation.nodes`, at the same `u'` and
/// density), each evaluated at `du`, `ln G` interpolated through all of
/// them ([`interpolate`]).
pub fn interpolated_kernel_text(
    store: &Store,
    plan: &[Box<dyn Stage>],
    interpolation: &Interpolation,
    title: &str,
    du: &[f64],
) -> Result<String> {
    let mut evaluated = Vec::new();
    for (coordinate, id) in &interpolation.nodes {
        match evaluate(store, plan, id, du)? {
            Ok(model) => evaluated.push((*coordinate, model)),
            Err(status) => anyhow::bail!("cannot interpolate: {status}"),
        }
    }
    let mut out = String::new();
    let _ = writeln!(out, "{title}: {}", interpolation.method);
    for (_, model) in &evaluated {
        let _ = writeln!(out, "  {}", model.source);
    }
    let values: Vec<(f64, f64, String)> = (0..du.len())
        .map(|k| {
            let points: Vec<(f64, f64, f64)> = evaluated
                .iter()
                .map(|(c, model)| (*c, model.values[k].0, model.values[k].1))
                .collect();
            let (ln_g, error) = interpolate(&points, interpolation.at);
            let beyond = evaluated
                .iter()
                .any(|(_, model)| !model.values[k].2.is_empty());
            let note = if beyond {
                "beyond some model's knots: extrapolated"
            } else {
                ""
            };
            (ln_g, error, note.to_string())
        })
        .collect();
    value_rows(&mut out, du, &values);
    Ok(out)
}

/// The model's test, as `kernel_model_fit` states it.
fn goodness_line(fit: &RecordBatch) -> Result<String> {
    use contract::fit::model_fit::*;
    let first = |col: contract::Col<f64>| -> Result<f64> { Ok(col.read(fit)?[0]) };
    Ok(format!(
        "model: ln G a natural cubic spline in ln|du| + |du| / x_c on each side of u' ({} knots); chi2 {} against {} +- {} for a model that follows the kernel, p = {} (docs/kernel-model.md)",
        KNOTS.read(fit)?[0],
        fixed(first(CHI2)?, 1),
        fixed(first(CHI2_EXPECTED)?, 1),
        fixed(first(CHI2_SPREAD)?, 1),
        fixed(first(P_VALUE)?, 3)
    ))
}

/// The knots of `side` (`below` or `above`) and their covariance.
fn stored_side(knots: &RecordBatch, covariance: &RecordBatch, side: &str) -> Result<StoredSide> {
    use contract::fit::model::{CUTOFF_SCALE, LN_G, SIDE, T};
    use contract::fit::model_covariance::{COVARIANCE, KNOT_I, KNOT_J};
    let sides = SIDE.read(knots)?;
    let rows: Vec<usize> = (0..sides.len()).filter(|&k| sides[k] == side).collect();
    let first = *rows
        .first()
        .with_context(|| format!("kernel_model has no knots {side} u'"))?;
    let (t, values) = (T.read(knots)?, LN_G.read(knots)?);
    let size = rows.len();
    let mut matrix = vec![0.0; size * size];
    let (covariance_sides, i, j) = (
        SIDE.read(covariance)?,
        KNOT_I.read(covariance)?,
        KNOT_J.read(covariance)?,
    );
    let entries = COVARIANCE.read(covariance)?;
    for k in (0..entries.len()).filter(|&k| covariance_sides[k] == side) {
        matrix[i[k] as usize * size + j[k] as usize] = entries[k];
    }
    Ok(StoredSide {
        knots: Knots {
            warp: Warp {
                cutoff_scale: CUTOFF_SCALE.read(knots)?[first],
            },
            t: rows.iter().map(|&k| t[k]).collect(),
        },
        values: rows.iter().map(|&k| values[k].mean).collect(),
        covariance: matrix,
    })
}

/// Where `x` lies outside the knots: the model continues straight in `t`
/// there, past what was fitted (empty inside).
fn extrapolation(side: &StoredSide, x: f64) -> String {
    let t = side.knots.warp.t(x);
    let (first, last) = (side.knots.t[0], side.knots.t[side.knots.t.len() - 1]);
    let edge = |t: f64| significant(side.knots.warp.x(t));
    if t < first {
        format!(
            "inside the innermost knot (|du| = {}): extrapolated",
            edge(first)
        )
    } else if t > last {
        format!(
            "beyond the last knot (|du| = {}, the outermost resolved group): extrapolated",
            edge(last)
        )
    } else {
        String::new()
    }
}
