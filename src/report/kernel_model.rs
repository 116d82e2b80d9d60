//! `ternary kernel`: a computed kernel's model (`kernel::model`, the `fit`
//! stage's `kernel_model` tables) evaluated at given `u - u'`, each value
//! with its standard error.

use std::fmt::Write as _;

use anyhow::Result;
use arrow::array::RecordBatch;

use super::numbers::{fixed, significant, with_error};
use super::rates::{intact, table_of};
use super::show::current_artifact;
use crate::contract;
use crate::kernel::model::{Replicated, SideCurve, combine, lagrange_weights, without_farthest};
use crate::pipeline::store::Store;
use crate::pipeline::{InstanceId, Stage};

/// A kernel's model evaluated at the `du` asked for.
struct Evaluated {
    /// `<instance> <key>` of the `fit` artifact.
    source: String,
    /// The model's test, as a line.
    goodness: String,
    /// Per `du`: `ln G` with its jackknife replicates, and where it lies
    /// beyond the knots.
    values: Vec<(Replicated, String)>,
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
    let table = |spec: &contract::TableSpec| table_of(store, &manifest, spec.name);
    let (knots, covariance, jackknife) = (
        table(&contract::fit::model::TABLE)?,
        table(&contract::fit::model_covariance::TABLE)?,
        table(&contract::fit::model_jackknife::TABLE)?,
    );
    let tables = contract::fit::ModelTables {
        knots: &knots,
        covariance: &covariance,
        jackknife: &jackknife,
    };
    let sides = [
        contract::fit::side_curve(&tables, "below")?,
        contract::fit::side_curve(&tables, "above")?,
    ];
    let values = du
        .iter()
        .map(|&x| {
            let side = &sides[usize::from(x > 0.0)];
            (side.ln_g(x.abs()), extrapolation(side, x.abs()))
        })
        .collect();
    Ok(Ok(Evaluated {
        source: format!("{id} {key}"),
        goodness: goodness_line(&fit)?,
        values,
    }))
}

/// The header of the value table and one row: `du`, `G` with its error
/// from `ln G` and its error, the relative error, the interpolation's own
/// estimate of its relative error (blank for a computed kernel), a note.
fn value_rows(out: &mut String, du: &[f64], values: &[(f64, f64, f64, String)]) {
    let _ = writeln!(
        out,
        "{:>12}  {:<28}  {:>9}  {:>9}  note",
        "u - u' [v_th]", "G [rho^2 l v_th / v_th]", "rel. err", "interp."
    );
    for (&x, (ln_g, error, interpolation, note)) in du.iter().zip(values) {
        let g = libm::exp(*ln_g);
        let interpolated = if interpolation.is_nan() {
            String::new()
        } else {
            format!("{}%", fixed(100.0 * interpolation.abs(), 3))
        };
        let _ = writeln!(
            out,
            "{:>12}  {:<28}  {:>8}%  {interpolated:>9}  {note}",
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
            let values: Vec<(f64, f64, f64, String)> = evaluated
                .values
                .iter()
                .map(|(ln_g, note)| (ln_g.value, ln_g.stderr(), f64::NAN, note.clone()))
                .collect();
            value_rows(&mut out, du, &values);
        }
    }
    Ok(out)
}

/// One computed kernel an interpolation goes through: its potential's
/// coordinate (`1/n`, `ln theta`; any, when only `u'` is interpolated), its
/// `u'` (a stored kernel's, or its mirror image's) and the `fit` instance
/// of the stored kernel.
pub struct Node {
    /// The potential's coordinate.
    pub coordinate: f64,
    /// The node's `u'`, `v_th`.
    pub u_prime: f64,
    /// The `fit` instance of the stored kernel.
    pub fit: InstanceId,
    /// The node is the stored kernel's mirror image, `G(u' -> u' + du) =
    /// G(-u' -> -u' - du)` (physics.md §3): evaluated at `-du`.
    pub mirrored: bool,
}

/// How `ternary kernel` reaches a kernel the study did not compute: its
/// nodes, grouped by potential in coordinate order, the target's
/// coordinate and `u'`, and a line saying what was done.
pub struct Interpolation {
    /// The computed kernels used.
    pub nodes: Vec<Node>,
    /// The coordinate of the potential asked for.
    pub at: f64,
    /// The `u'` asked for, `v_th`.
    pub u_prime: f64,
    /// What the interpolation is, printed under the title.
    pub method: String,
}

/// The text of `ternary kernel` for a kernel the study did not compute:
/// the models of those it did (`interpolation.nodes`), each evaluated at
/// `du` (mirror images at `-du`); `ln G` interpolated in `u'` through each
/// potential's nodes, then in the potentials' coordinate, its error
/// jackknifed over the randomizations the kernels share ([`combine`]).
pub fn interpolated_kernel_text(
    store: &Store,
    plan: &[Box<dyn Stage>],
    interpolation: &Interpolation,
    title: &str,
    du: &[f64],
) -> Result<String> {
    let mut evaluated = Vec::new();
    for node in &interpolation.nodes {
        let sign = if node.mirrored { -1.0 } else { 1.0 };
        let at: Vec<f64> = du.iter().map(|x| sign * x).collect();
        match evaluate(store, plan, &node.fit, &at)? {
            Ok(model) => evaluated.push((node, model)),
            Err(status) => anyhow::bail!("cannot interpolate: {status}"),
        }
    }
    let mut out = String::new();
    let _ = writeln!(out, "{title}: {}", interpolation.method);
    for (node, model) in &evaluated {
        let mirror = if node.mirrored {
            format!(" (its mirror image, at u' = {})", node.u_prime)
        } else {
            String::new()
        };
        let _ = writeln!(out, "  {}{mirror}", model.source);
    }
    let weights = node_weights(interpolation, (false, false));
    let values: Vec<(f64, f64, f64, String)> = (0..du.len())
        .map(|k| {
            let at_du: Vec<Replicated> = evaluated
                .iter()
                .map(|(_, model)| model.values[k].0.clone())
                .collect();
            let (ln_g, error) = combine(&weights, &at_du);
            let plain: Vec<f64> = at_du.iter().map(|v| v.value).collect();
            let interpolation_error = correction(interpolation, &plain);
            let beyond = evaluated
                .iter()
                .any(|(_, model)| !model.values[k].1.is_empty());
            let note = if beyond {
                "beyond some model's knots: extrapolated"
            } else {
                ""
            };
            (ln_g, error, interpolation_error, note.to_string())
        })
        .collect();
    value_rows(&mut out, du, &values);
    Ok(out)
}

/// Each node's weight in the interpolated `ln G`: its Lagrange weight in
/// `u'` among its potential's nodes times its potential's in the
/// potentials' coordinate (the two interpolations in turn are one linear
/// combination); with `lower` (across the potentials, within `u'`), that
/// interpolation one degree lower, its farthest node weighing 0.
fn node_weights(interpolation: &Interpolation, lower: (bool, bool)) -> Vec<f64> {
    let nodes = &interpolation.nodes;
    let mut coordinates: Vec<f64> = nodes.iter().map(|n| n.coordinate).collect();
    coordinates.dedup();
    let across = weights_of(&coordinates, interpolation.at, lower.0);
    nodes
        .iter()
        .map(|node| {
            let same: Vec<f64> = nodes
                .iter()
                .filter(|n| n.coordinate == node.coordinate)
                .map(|n| n.u_prime)
                .collect();
            let within = weights_of(&same, interpolation.u_prime, lower.1);
            let k = same.iter().position(|&u| u == node.u_prime).unwrap_or(0);
            let c = coordinates
                .iter()
                .position(|&c| c == node.coordinate)
                .unwrap_or(0);
            within[k] * across[c]
        })
        .collect()
}

/// The Lagrange weights of `nodes` at `at`, or (`lower`, more than one
/// node) those of every node but the farthest, which weighs 0.
fn weights_of(nodes: &[f64], at: f64, lower: bool) -> Vec<f64> {
    let kept = without_farthest(nodes, at);
    if !lower || kept.is_empty() {
        return lagrange_weights(nodes, at);
    }
    let coordinates: Vec<f64> = kept.iter().map(|&k| nodes[k]).collect();
    let mut weights = vec![0.0; nodes.len()];
    for (&k, w) in kept.iter().zip(lagrange_weights(&coordinates, at)) {
        weights[k] = w;
    }
    weights
}

/// The interpolation's own estimate of its error in `ln G` at one `du`:
/// its differences from the interpolations one degree lower across the
/// potentials and within `u'`, combined in quadrature (each the last
/// correction of Neville's algorithm; 0 where there is one node).
fn correction(interpolation: &Interpolation, values: &[f64]) -> f64 {
    let at = |lower| -> f64 {
        let weights = node_weights(interpolation, lower);
        weights.iter().zip(values).map(|(w, v)| w * v).sum()
    };
    let full = at((false, false));
    libm::hypot(full - at((true, false)), full - at((false, true)))
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

/// Where `x` lies outside the knots: the model continues straight in `t`
/// there, past what was fitted (empty inside).
fn extrapolation(side: &SideCurve, x: f64) -> String {
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
