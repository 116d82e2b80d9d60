//! `ternary kernel`: a computed kernel's model (`kernel::model`, the `fit`
//! stage's `kernel_model` tables) evaluated at given `u - u'`, each value
//! with its standard error.

use std::fmt::Write as _;

use anyhow::Result;
use arrow_array::RecordBatch;

use super::numbers::{fixed, significant, with_error};
use super::rates::{intact, table_of};
use super::show::current_artifact;
use crate::contract;
use crate::kernel::model::{
    Part, Replicated, SideCurve, combine, combine_replicated, lagrange_weights, without_farthest,
};
use crate::pipeline::store::Store;
use crate::pipeline::{InstanceId, Stage};

/// What `ternary kernel` evaluates: a modelled part of the kernel, or the
/// bath part, the whole less the self part (physics.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Asked {
    /// `G` or `G_self`: its model.
    Modelled(Part),
    /// `G_bath = G - G_self`: the difference of the two models, jackknifed
    /// over the randomizations they share.
    Bath,
}

impl Asked {
    /// The modelled parts it needs.
    fn parts(self) -> Vec<Part> {
        match self {
            Asked::Modelled(part) => vec![part],
            Asked::Bath => Part::MODELLED.to_vec(),
        }
    }

    /// Its value from the parts' `ln G` (in the order of [`Asked::parts`]).
    fn value(self, ln_g: &[f64]) -> f64 {
        match self {
            Asked::Modelled(_) => libm::exp(ln_g[0]),
            Asked::Bath => libm::exp(ln_g[0]) - libm::exp(ln_g[1]),
        }
    }

    /// Its value and standard error from the parts' `ln G` with their
    /// jackknife replicates (the parts of one kernel, or combined over the
    /// same randomizations): a modelled part's error is `G` times that of
    /// `ln G`; the bath part's, the difference jackknifed as a whole (the
    /// two parts share every randomization, and nearly cancel).
    fn estimate(self, ln_g: &[Replicated]) -> (f64, f64) {
        if let Asked::Modelled(_) = self {
            let g = libm::exp(ln_g[0].value);
            return (g, g * ln_g[0].stderr());
        }
        let at = |r: usize| -> Vec<f64> { ln_g.iter().map(|v| v.left_out[r]).collect() };
        let difference = Replicated {
            value: self.value(&ln_g.iter().map(|v| v.value).collect::<Vec<_>>()),
            left_out: (0..ln_g[0].left_out.len())
                .map(|r| self.value(&at(r)))
                .collect(),
        };
        (difference.value, difference.stderr())
    }
}

/// A kernel's model of one part evaluated at the `du` asked for.
struct Evaluated {
    /// `<instance> <key>` of the `fit` artifact.
    source: String,
    /// The model's test, as a line.
    goodness: String,
    /// Per `du`: `ln G` with its jackknife replicates, and where it lies
    /// beyond the knots.
    values: Vec<(Replicated, String)>,
}

/// The model of `part` of the `fit` instance `id` at each of `du`;
/// `Ok(Err(status))` when it has none.
fn evaluate(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
    du: &[f64],
    part: Part,
) -> Result<std::result::Result<Evaluated, String>> {
    let (stage, key) = current_artifact(store, plan, id)?;
    let manifest = intact(store, &stage, &key)?;
    let fit = table_of(store, &manifest, contract::fit::model_fit::TABLE.name)?;
    let row = contract::fit::goodness_row(&fit, part)?;
    let status = &contract::fit::model_fit::STATUS.read(&fit)?[row];
    if status != "fitted" {
        return Ok(Err(format!(
            "{id} {key}: no model of part {}: {status}",
            part.name()
        )));
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
        contract::fit::side_curve(&tables, part, "below")?,
        contract::fit::side_curve(&tables, part, "above")?,
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
        goodness: goodness_line(&fit, row, part)?,
        values,
    }))
}

/// Every part `asked` needs of the `fit` instance `id`, evaluated at `du`.
fn evaluate_parts(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
    du: &[f64],
    asked: Asked,
) -> Result<std::result::Result<Vec<Evaluated>, String>> {
    let mut parts = Vec::new();
    for part in asked.parts() {
        match evaluate(store, plan, id, du, part)? {
            Ok(evaluated) => parts.push(evaluated),
            Err(status) => return Ok(Err(status)),
        }
    }
    Ok(Ok(parts))
}

/// One printed value: `G` (of the part asked), its standard error, the
/// interpolation's own estimate of its relative error (NaN for a computed
/// kernel) and a note.
struct Printed {
    g: f64,
    stderr: f64,
    interpolation: f64,
    note: String,
}

/// The header of the value table and one row per `du`: `G` with its
/// error, the relative error, the interpolation's estimate (blank for a
/// computed kernel), a note.
fn value_rows(out: &mut String, du: &[f64], values: &[Printed]) {
    let _ = writeln!(
        out,
        "{:>12}  {:<28}  {:>9}  {:>9}  note",
        "u - u' [v_th]", "G [rho^2 l v_th / v_th]", "rel. err", "interp."
    );
    for (&x, value) in du.iter().zip(values) {
        let interpolated = if value.interpolation.is_nan() {
            String::new()
        } else {
            format!("{}%", fixed(100.0 * value.interpolation.abs(), 3))
        };
        let _ = writeln!(
            out,
            "{:>12}  {:<28}  {:>8}%  {interpolated:>9}  {}",
            significant(x),
            with_error(value.g, value.stderr, "-"),
            fixed(100.0 * value.stderr / value.g.abs(), 3),
            value.note,
        );
    }
}

/// The text of `ternary kernel`: `G(u' -> u' + du)` (or the part
/// `asked`) of the model of the `fit` instance `id` (`title` names the
/// kernel) at each of `du` (`v_th`, non-zero), with its standard error,
/// and where the model continues straight beyond its knots.
pub fn kernel_model_text(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
    title: &str,
    du: &[f64],
    asked: Asked,
) -> Result<String> {
    let mut out = String::new();
    match evaluate_parts(store, plan, id, du, asked)? {
        Err(status) => {
            let _ = writeln!(out, "{title}\n{status}");
        }
        Ok(parts) => {
            let _ = writeln!(out, "{title} ({})", parts[0].source);
            for part in &parts {
                let _ = writeln!(out, "{}", part.goodness);
            }
            let values: Vec<Printed> = (0..du.len())
                .map(|k| {
                    let at: Vec<Replicated> = parts.iter().map(|p| p.values[k].0.clone()).collect();
                    let (g, stderr) = asked.estimate(&at);
                    Printed {
                        g,
                        stderr,
                        interpolation: f64::NAN,
                        note: beyond_knots(&parts, k),
                    }
                })
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
/// `du` (mirror images at `-du`); `ln G` of each part `asked` needs
/// interpolated in `u'` through each potential's nodes, then in the
/// potentials' coordinate, its error jackknifed over the randomizations
/// the kernels share ([`combine`]).
pub fn interpolated_kernel_text(
    store: &Store,
    plan: &[Box<dyn Stage>],
    interpolation: &Interpolation,
    title: &str,
    du: &[f64],
    asked: Asked,
) -> Result<String> {
    let mut evaluated = Vec::new();
    for node in &interpolation.nodes {
        let sign = if node.mirrored { -1.0 } else { 1.0 };
        let at: Vec<f64> = du.iter().map(|x| sign * x).collect();
        match evaluate_parts(store, plan, &node.fit, &at, asked)? {
            Ok(parts) => evaluated.push((node, parts)),
            Err(status) => anyhow::bail!("cannot interpolate: {status}"),
        }
    }
    let mut out = String::new();
    let _ = writeln!(out, "{title}: {}", interpolation.method);
    for (node, parts) in &evaluated {
        let mirror = if node.mirrored {
            format!(" (its mirror image, at u' = {})", node.u_prime)
        } else {
            String::new()
        };
        let _ = writeln!(out, "  {}{mirror}", parts[0].source);
    }
    let weights = node_weights(interpolation, (false, false));
    let values: Vec<Printed> = (0..du.len())
        .map(|k| interpolated_row(interpolation, &weights, &evaluated, k, asked))
        .collect();
    value_rows(&mut out, du, &values);
    Ok(out)
}

/// Where the `k`-th `du` lies beyond the knots of any of the `parts`'
/// models (empty inside all).
fn beyond_knots(parts: &[Evaluated], k: usize) -> String {
    parts
        .iter()
        .map(|part| &part.values[k].1)
        .find(|note| !note.is_empty())
        .cloned()
        .unwrap_or_default()
}

/// The printed row of the `k`-th `du`: the part `asked` interpolated
/// through the `evaluated` nodes' models with `weights`, the
/// interpolation's own estimate of its relative error, and a note where
/// some model lies beyond its knots.
fn interpolated_row(
    interpolation: &Interpolation,
    weights: &[f64],
    evaluated: &[(&Node, Vec<Evaluated>)],
    k: usize,
    asked: Asked,
) -> Printed {
    // Per part, its ln G at every node.
    let nodes: Vec<Vec<Replicated>> = (0..asked.parts().len())
        .map(|p| {
            evaluated
                .iter()
                .map(|(_, parts)| parts[p].values[k].0.clone())
                .collect()
        })
        .collect();
    let beyond = evaluated
        .iter()
        .any(|(_, parts)| !beyond_knots(parts, k).is_empty());
    let note = if beyond {
        "beyond some model's knots: extrapolated"
    } else {
        ""
    };
    let printed = interpolated_value(weights, &nodes, asked);
    let plain: Vec<Vec<f64>> = nodes
        .iter()
        .map(|part| part.iter().map(|v| v.value).collect())
        .collect();
    Printed {
        interpolation: correction(interpolation, asked, &plain) / printed.g.abs(),
        note: note.to_string(),
        ..printed
    }
}

/// The part `asked` from each needed part's `ln G` at the nodes
/// (`nodes[part][node]`), interpolated with `weights`: jackknifed as a
/// whole over the randomizations the nodes share, or (nodes of different
/// randomizations) each part's error taken as independent.
fn interpolated_value(weights: &[f64], nodes: &[Vec<Replicated>], asked: Asked) -> Printed {
    let paired: Option<Vec<Replicated>> = nodes
        .iter()
        .map(|part| combine_replicated(weights, part))
        .collect();
    let (g, stderr) = match paired {
        Some(parts) => asked.estimate(&parts),
        None => {
            let parts: Vec<(f64, f64)> = nodes.iter().map(|part| combine(weights, part)).collect();
            let ln_g: Vec<f64> = parts.iter().map(|p| p.0).collect();
            let stderr = parts
                .iter()
                .map(|&(ln_g, error)| libm::exp(ln_g) * error)
                .fold(0.0, libm::hypot);
            (asked.value(&ln_g), stderr)
        }
    };
    Printed {
        g,
        stderr,
        interpolation: f64::NAN,
        note: String::new(),
    }
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

/// The interpolation's own estimate of its error in the part `asked` at
/// one `du` (`values[part][node]`: the needed parts' `ln G` at the nodes):
/// its differences from the interpolations one degree lower across the
/// potentials and within `u'`, combined in quadrature (each the last
/// correction of Neville's algorithm; 0 where there is one node).
fn correction(interpolation: &Interpolation, asked: Asked, values: &[Vec<f64>]) -> f64 {
    let at = |lower| -> f64 {
        let weights = node_weights(interpolation, lower);
        let ln_g: Vec<f64> = values
            .iter()
            .map(|part| weights.iter().zip(part).map(|(w, v)| w * v).sum())
            .collect();
        asked.value(&ln_g)
    };
    let full = at((false, false));
    libm::hypot(full - at((true, false)), full - at((false, true)))
}

/// The test of `part`'s model, as row `row` of `kernel_model_fit` states it.
fn goodness_line(fit: &RecordBatch, row: usize, part: Part) -> Result<String> {
    use contract::fit::model_fit::*;
    let first = |col: contract::Col<f64>| -> Result<f64> { Ok(col.read(fit)?[row]) };
    let modelled = match part {
        Part::Total => "ln G",
        Part::SelfPart => "ln G_self",
    };
    Ok(format!(
        "model: {modelled} a natural cubic spline in ln|du| + |du| / x_c on each side of u' ({} knots); chi2 {} against {} +- {} for a model that follows the kernel, p = {} (docs/kernel-model.md)",
        KNOTS.read(fit)?[row],
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `ln G` of a part with its replicates: `value`, and `value` moved by
    /// each of `moves` (`G` units) in turn.
    fn part(value: f64, moves: &[f64]) -> Replicated {
        Replicated {
            value: libm::log(value),
            left_out: moves.iter().map(|m| libm::log(value + m)).collect(),
        }
    }

    /// The bath part of two parts that move together over the
    /// randomizations has no error of its own, though each part has one; a
    /// modelled part's error is `G` times its `ln G`'s.
    #[test]
    fn a_bath_part_of_co_moving_parts_has_no_error() {
        let moves = [0.3, -0.2, 0.1, -0.4, 0.25, 0.0, -0.1, 0.15];
        let (whole, own) = (part(10.0, &moves), part(9.0, &moves));
        let (bath, error) = Asked::Bath.estimate(&[whole.clone(), own]);
        assert!((bath - 1.0).abs() < 1e-12, "{bath}");
        assert!(error < 1e-12, "{error}");
        let (g, whole_error) = Asked::Modelled(Part::Total).estimate(std::slice::from_ref(&whole));
        assert!((g - 10.0).abs() < 1e-12);
        assert!((whole_error - 10.0 * whole.stderr()).abs() < 1e-12);
        assert!(whole_error > 0.1, "{whole_error}");
    }
}
