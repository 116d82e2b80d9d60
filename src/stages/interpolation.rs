//! `interpolation`: how well the kernel models interpolate between the
//! computed kernels, measured by holding out each computed kernel in turn
//! and predicting it from the models of its neighbours, chosen as `ternary
//! kernel` chooses them (`kernel::model::nearest_nodes`): in `1/n` among
//! the inverse power laws and in `ln theta` among the Lennard-Jones
//! potentials (at the same `u'` and density; the nearest five, or four
//! where only four remain), and in `u'` among one potential's kernels and
//! their mirror images (the nearest four; the held-out kernel's own mirror
//! image left out with it). At each of the held-out kernel's log-spaced
//! groups measured to better than a third, `ln` of every node's model mean
//! over the group is interpolated by the Lagrange polynomial and held
//! against the held-out kernel's own model: `ln(model / prediction)`, the
//! interpolation's error, with its noise (the whole difference recomputed
//! without each randomization, `kernel_model_jackknife`, which the kernels
//! share), and `z`, that error in the one `ternary kernel` states: the
//! interpolation's own estimate (`without_farthest`) and the prediction's
//! statistical error in quadrature.

use serde_json::Value;

use crate::config::KernelParams;
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::kernel::model::{
    FEWEST_NODES, Family, POTENTIAL_NODES, Part, Replicated, SideCurve, U_PRIME_NODES, combine,
    lagrange_weights, nearest_nodes, u_prime_nodes, without_farthest,
};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::{Estimate, median};

/// The `interpolation` stage.
pub struct InterpolationStage {
    /// Every kernel of a potential an interpolation reaches.
    kernels: Vec<KernelParams>,
}

impl InterpolationStage {
    /// The interpolation between `kernels` (each with a planned `fit`),
    /// when at least one of them can be held out: a family of more than
    /// [`FEWEST_NODES`] potentials at one `u'`, or a potential with more
    /// than [`U_PRIME_NODES`] `u'` nodes (mirror images included).
    pub fn planned(kernels: Vec<KernelParams>) -> Option<InterpolationStage> {
        let kernels: Vec<KernelParams> = kernels
            .into_iter()
            .filter(|k| Family::of(&k.potential).is_some())
            .collect();
        let all: Vec<usize> = (0..kernels.len()).collect();
        let along_potentials = all.iter().any(|&k| {
            let family = Family::of(&kernels[k].potential).map(|(f, _)| f);
            let peers = all.iter().filter(|&&j| {
                same_target(&kernels[j], &kernels[k])
                    && Family::of(&kernels[j].potential).map(|(f, _)| f) == family
            });
            peers.count() > FEWEST_NODES
        });
        let along_u_prime = all
            .iter()
            .any(|&k| potential_u_primes(&kernels, &all, k).len() > U_PRIME_NODES);
        (along_potentials || along_u_prime).then_some(InterpolationStage { kernels })
    }
}

/// Both kernels are at one `u'` and density.
fn same_target(a: &KernelParams, b: &KernelParams) -> bool {
    a.u_prime == b.u_prime && a.density == b.density
}

/// A kernel's stored model and the groups it was fitted to.
struct Modelled {
    /// Below `u'`, above `u'`.
    sides: [SideCurve; 2],
    /// `(du, |inner edge|, |outer edge|, G)` of every group.
    groups: Vec<(f64, f64, f64, Estimate)>,
}

/// One kernel an interpolation goes through.
#[derive(Clone, Copy)]
struct Node {
    /// The kernel (index into the stage's kernels).
    kernel: usize,
    /// Its coordinate: `1/n`, `ln theta` or `u'`.
    coordinate: f64,
    /// A mirror image: its `u'` the stored kernel's negated, its sides
    /// swapped.
    mirrored: bool,
}

/// One held-out kernel and the nodes that predict it.
struct Case {
    /// What it is interpolated in.
    coordinate: &'static str,
    /// The held-out kernel (index).
    held_out: usize,
    /// Its coordinate.
    at: f64,
    /// The nodes, in ascending coordinate.
    nodes: Vec<Node>,
}

/// The `u'` nodes of the potential and density of kernel `k` among the
/// modelled kernels `modelled`: each kernel, and the mirror image of each
/// at `u' != 0` whose `-u'` is not computed.
fn potential_u_primes(kernels: &[KernelParams], modelled: &[usize], k: usize) -> Vec<Node> {
    let same: Vec<usize> = modelled
        .iter()
        .copied()
        .filter(|&j| {
            kernels[j].potential == kernels[k].potential && kernels[j].density == kernels[k].density
        })
        .collect();
    let computed: Vec<f64> = same.iter().map(|&j| kernels[j].u_prime).collect();
    u_prime_nodes(&computed)
        .into_iter()
        .map(|(coordinate, index, mirrored)| Node {
            kernel: same[index],
            coordinate,
            mirrored,
        })
        .collect()
}

/// The nodes among `candidates` that predict the value at `at`: the
/// `count` nearest around it for the largest `count` from `most` down to
/// [`FEWEST_NODES`] that has them.
fn choose(candidates: &[Node], at: f64, most: usize, separation: f64) -> Option<Vec<Node>> {
    let coordinates: Vec<f64> = candidates.iter().map(|n| n.coordinate).collect();
    (FEWEST_NODES..=most)
        .rev()
        .find_map(|count| nearest_nodes(&coordinates, at, count, separation))
        .map(|taken| taken.iter().map(|&k| candidates[k]).collect())
}

impl InterpolationStage {
    /// Every held-out kernel with its nodes, among the kernels `modelled`
    /// (those with a model): along the potentials, then along `u'`.
    fn cases(&self, modelled: &[usize]) -> Vec<Case> {
        let mut cases = Vec::new();
        for &k in modelled {
            let Some((family, at)) = Family::of(&self.kernels[k].potential) else {
                continue;
            };
            let candidates: Vec<Node> = modelled
                .iter()
                .filter(|&&j| same_target(&self.kernels[j], &self.kernels[k]))
                .filter_map(|&j| {
                    let (f, c) = Family::of(&self.kernels[j].potential)?;
                    let apart = (c - at).abs() >= family.separation().max(f64::MIN_POSITIVE);
                    (f == family && apart).then_some(Node {
                        kernel: j,
                        coordinate: c,
                        mirrored: false,
                    })
                })
                .collect();
            if let Some(nodes) = choose(&candidates, at, POTENTIAL_NODES, family.separation()) {
                cases.push(Case {
                    coordinate: family.coordinate(),
                    held_out: k,
                    at,
                    nodes,
                });
            }
        }
        for &k in modelled {
            let at = self.kernels[k].u_prime;
            let candidates: Vec<Node> = potential_u_primes(&self.kernels, modelled, k)
                .into_iter()
                .filter(|n| n.coordinate.abs() != at.abs())
                .collect();
            if let Some(nodes) = choose(&candidates, at, U_PRIME_NODES, 0.0) {
                cases.push(Case {
                    coordinate: "u'",
                    held_out: k,
                    at,
                    nodes,
                });
            }
        }
        cases
    }
}

/// The stored model of the `fit` instance `id`, `None` without one.
fn modelled(inputs: &[Input], id: &InstanceId) -> Result<Option<Modelled>, StageError> {
    use contract::fit::{model, model_covariance, model_fit, model_groups, model_jackknife};
    let goodness = model_fit::TABLE.find(inputs, id)?;
    let status =
        &model_fit::STATUS.read(goodness)?[contract::fit::goodness_row(goodness, Part::Total)?];
    if status != "fitted" {
        return Ok(None);
    }
    let tables = contract::fit::ModelTables {
        knots: model::TABLE.find(inputs, id)?,
        covariance: model_covariance::TABLE.find(inputs, id)?,
        jackknife: model_jackknife::TABLE.find(inputs, id)?,
    };
    let side = |name| contract::fit::side_curve(&tables, Part::Total, name);
    let table = model_groups::TABLE.find(inputs, id)?;
    let (du, inner, outer) = (
        model_groups::DU.read(table)?,
        model_groups::DU_INNER.read(table)?,
        model_groups::DU_OUTER.read(table)?,
    );
    let (g, stderr) = (
        model_groups::G.read(table)?,
        model_groups::G_STDERR.read(table)?,
    );
    let groups = contract::fit::part_rows(table, Part::Total)?
        .into_iter()
        .map(|k| {
            let value = Estimate {
                mean: g[k],
                stderr: stderr[k],
            };
            (du[k], inner[k].abs(), outer[k].abs(), value)
        })
        .collect();
    Ok(Some(Modelled {
        sides: [side("below")?, side("above")?],
        groups,
    }))
}

/// One held-out group: the case, the group, the held-out kernel's model
/// there and the prediction.
struct Predicted {
    /// The case (index).
    case: usize,
    /// `(du, |inner edge|, |outer edge|, G)`.
    group: (f64, f64, f64, Estimate),
    /// The held-out kernel's model mean over the group.
    model: Estimate,
    /// The prediction of it from the nodes.
    predicted: Estimate,
    /// `ln(model / predicted)` and its error, jackknifed over the
    /// randomizations they share.
    ln_ratio: (f64, f64),
    /// The interpolation's own estimate of its error in `ln G`: the
    /// prediction less the one through every node but the farthest.
    correction: f64,
}

impl Predicted {
    /// `ln(model / predicted)` in the error `ternary kernel` states for
    /// the prediction: its own estimate and its statistical error in
    /// quadrature.
    fn z(&self) -> f64 {
        let statistical = self.predicted.stderr / self.predicted.mean;
        self.ln_ratio.0 / libm::hypot(self.correction, statistical)
    }
}

/// A held-out group is compared where it is measured to better than a
/// third (as the model's knots reach) and where every model was fitted:
/// the far groups' noise and the models' straight continuation test
/// nothing of the interpolation.
const RESOLVED: f64 = 3.0;

/// The node's model of the side of `u'` a group at `du` lies on (a mirror
/// image's other side).
fn node_side<'m>(node: &Node, du: f64, models: &'m [Option<Modelled>]) -> Option<&'m SideCurve> {
    let side = usize::from((du > 0.0) != node.mirrored);
    Some(&models[node.kernel].as_ref()?.sides[side])
}

/// `exp` of a logarithm with its jackknife error, as a value and its
/// first-order error.
fn exponentiated((ln_value, error): (f64, f64)) -> Estimate {
    let mean = libm::exp(ln_value);
    Estimate {
        mean,
        stderr: mean * error,
    }
}

/// The prediction of every group of `case`'s held-out kernel that is
/// resolved and inside every model's knots: `ln` of the nodes' group means
/// through the Lagrange weights, against the held-out kernel's own model,
/// the difference jackknifed as one combination.
fn predict(case: &Case, index: usize, models: &[Option<Modelled>]) -> Vec<Predicted> {
    let Some(held_out) = &models[case.held_out] else {
        return Vec::new();
    };
    let coordinates: Vec<f64> = case.nodes.iter().map(|n| n.coordinate).collect();
    let weights = lagrange_weights(&coordinates, case.at);
    let lower = without_farthest(&coordinates, case.at);
    let lower_coordinates: Vec<f64> = lower.iter().map(|&k| coordinates[k]).collect();
    let lower_weights = lagrange_weights(&lower_coordinates, case.at);
    let own = Node {
        kernel: case.held_out,
        coordinate: case.at,
        mirrored: false,
    };
    let covered = |du: f64, inner: f64, outer: f64| {
        case.nodes
            .iter()
            .chain([&own])
            .all(|node| node_side(node, du, models).is_some_and(|c| c.covers(inner, outer)))
    };
    held_out
        .groups
        .iter()
        .filter(|(du, inner, outer, g)| {
            g.mean > RESOLVED * g.stderr && covered(*du, *inner, *outer)
        })
        .filter_map(|&group| {
            let (du, inner, outer, _) = group;
            let mean_of =
                |node: &Node| Some(node_side(node, du, models)?.ln_group_mean(inner, outer));
            let nodes: Vec<Replicated> = case.nodes.iter().map(mean_of).collect::<Option<_>>()?;
            let model = mean_of(&own)?;
            let ratio_weights: Vec<f64> = [1.0]
                .into_iter()
                .chain(weights.iter().map(|w| -w))
                .collect();
            let terms: Vec<Replicated> = [model.clone()]
                .into_iter()
                .chain(nodes.iter().cloned())
                .collect();
            let predicted = combine(&weights, &nodes);
            let lower_value: f64 = lower
                .iter()
                .zip(&lower_weights)
                .map(|(&k, w)| w * nodes[k].value)
                .sum();
            Some(Predicted {
                case: index,
                group,
                model: exponentiated((model.value, model.stderr())),
                predicted: exponentiated(predicted),
                ln_ratio: combine(&ratio_weights, &terms),
                correction: predicted.0 - lower_value,
            })
        })
        .collect()
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for InterpolationStage {
    fn id(&self) -> InstanceId {
        instances::interpolation()
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.kernels).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::interpolation::{coordinates, groups, summary};
        &[
            groups::TABLE.name,
            summary::TABLE.name,
            coordinates::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.kernels.iter().map(instances::fit).collect()
    }

    fn work_units(&self) -> u64 {
        self.kernels.len() as u64
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let mut models = Vec::new();
        for kernel in &self.kernels {
            models.push(modelled(inputs, &instances::fit(kernel))?);
            progress.advance(1);
        }
        let with_model: Vec<usize> = (0..models.len()).filter(|&k| models[k].is_some()).collect();
        let cases = self.cases(&with_model);
        let predicted: Vec<Predicted> = cases
            .iter()
            .enumerate()
            .flat_map(|(index, case)| predict(case, index, &models))
            .collect();
        Ok(vec![
            self.groups_table(&cases, &predicted)?,
            self.summary_table(&cases, &predicted)?,
            self.coordinates_table(&cases, &predicted)?,
        ])
    }
}

/// A held-out kernel as the tables name it.
struct HeldOut {
    /// What it is interpolated in.
    coordinate: &'static str,
    /// Its potential's id.
    potential: String,
    /// Its `u'`.
    u_prime: f64,
    /// Its `rho l`.
    density: f64,
    /// The nodes that predict it, as text.
    nodes: String,
}

/// `rows` with the columns that name each row's held-out kernel.
fn with_held_out<'r, R>(rows: Rows<'r, R>, of: impl Fn(&R) -> &HeldOut) -> Rows<'r, R> {
    use contract::interpolation::held_out::*;
    rows.with(COORDINATE, |r| of(r).coordinate.to_string())
        .with(POTENTIAL, |r| of(r).potential.clone())
        .with(U_PRIME, |r| of(r).u_prime)
        .with(RHO_L, |r| of(r).density)
        .with(NODES, |r| of(r).nodes.clone())
}

impl InterpolationStage {
    /// The held-out kernel of `case`.
    fn describe(&self, case: &Case) -> HeldOut {
        let kernel = &self.kernels[case.held_out];
        let nodes: Vec<String> = case
            .nodes
            .iter()
            .map(|node| match (case.coordinate, node.mirrored) {
                ("u'", false) => node.coordinate.to_string(),
                ("u'", true) => format!("{} (mirror image)", node.coordinate),
                _ => self.kernels[node.kernel].potential.id(),
            })
            .collect();
        let nodes = match case.coordinate {
            "u'" => format!("u' = {}", nodes.join(", ")),
            _ => nodes.join(", "),
        };
        HeldOut {
            coordinate: case.coordinate,
            potential: kernel.potential.id(),
            u_prime: kernel.u_prime,
            density: kernel.density,
            nodes,
        }
    }

    /// One row per held-out kernel and group.
    fn groups_table(&self, cases: &[Case], predicted: &[Predicted]) -> Result<Table, StageError> {
        use contract::interpolation::groups::*;
        let rows: Vec<(_, &Predicted)> = predicted
            .iter()
            .map(|p| (self.describe(&cases[p.case]), p))
            .collect();
        Ok(with_held_out(Rows::new(&rows), |(d, _)| d)
            .with(DU, |(_, p)| p.group.0)
            .with(DU_INNER, |(_, p)| p.group.0.signum() * p.group.1)
            .with(DU_OUTER, |(_, p)| p.group.0.signum() * p.group.2)
            .estimate(G, |(_, p)| p.group.3)
            .estimate(G_MODEL, |(_, p)| p.model)
            .estimate(G_PREDICTED, |(_, p)| p.predicted)
            .estimate(LN_RATIO, |(_, p)| Estimate {
                mean: p.ln_ratio.0,
                stderr: p.ln_ratio.1,
            })
            .with(CORRECTION, |(_, p)| p.correction)
            .with(Z, |(_, p)| p.z())
            .table(&TABLE)?)
    }

    /// One row per held-out kernel.
    fn summary_table(&self, cases: &[Case], predicted: &[Predicted]) -> Result<Table, StageError> {
        use contract::interpolation::summary::*;
        let rows: Vec<(_, Vec<&Predicted>)> = cases
            .iter()
            .enumerate()
            .map(|(index, case)| {
                let own = predicted.iter().filter(|p| p.case == index).collect();
                (self.describe(case), own)
            })
            .collect();
        let abs_z = |own: &[&Predicted]| -> Vec<f64> { own.iter().map(|p| p.z().abs()).collect() };
        let deviation = |p: &&Predicted| (p.predicted.mean / p.model.mean - 1.0).abs();
        Ok(with_held_out(Rows::new(&rows), |(d, _)| d)
            .with(GROUPS, |(_, own)| own.len() as u32)
            .with(MEDIAN_ABS_Z, |(_, own)| median(&abs_z(own)))
            .with(LARGEST_ABS_Z, |(_, own)| {
                abs_z(own).into_iter().fold(0.0, f64::max)
            })
            .with(BEYOND_TWO, |(_, own)| {
                abs_z(own).iter().filter(|&&z| z > 2.0).count() as u32
            })
            .with(MEDIAN_ABS_LN_RATIO, |(_, own)| {
                median(&own.iter().map(|p| p.ln_ratio.0.abs()).collect::<Vec<f64>>())
            })
            .with(MEDIAN_ABS_CORRECTION, |(_, own)| {
                median(&own.iter().map(|p| p.correction.abs()).collect::<Vec<f64>>())
            })
            .with(LARGEST_DEVIATION, |(_, own)| {
                own.iter().map(deviation).fold(0.0, f64::max)
            })
            .table(&TABLE)?)
    }

    /// One row per coordinate: its held-out kernels' groups summed.
    fn coordinates_table(
        &self,
        cases: &[Case],
        predicted: &[Predicted],
    ) -> Result<Table, StageError> {
        use contract::interpolation::coordinates::*;
        let mut rows: Vec<Along> = Vec::new();
        for (index, case) in cases.iter().enumerate() {
            let own: Vec<f64> = predicted
                .iter()
                .filter(|p| p.case == index)
                .map(|p| p.z().abs())
                .collect();
            let deviation = predicted
                .iter()
                .filter(|p| p.case == index)
                .map(|p| (p.predicted.mean / p.model.mean - 1.0).abs())
                .fold(0.0, f64::max);
            let at = rows.iter().position(|r| r.coordinate == case.coordinate);
            let along = match at {
                Some(at) => &mut rows[at],
                None => {
                    rows.push(Along::new(case.coordinate));
                    rows.last_mut().expect("just pushed")
                }
            };
            along.add(self.describe(case), &own, deviation);
        }
        Ok(Rows::new(&rows)
            .with(COORDINATE, |r| r.coordinate.to_string())
            .with(HELD_OUT, |r| r.medians.len() as u32)
            .with(GROUPS, |r| r.groups)
            .with(BEYOND_TWO, |r| r.beyond_two)
            .with(BEYOND_TWO_SHARE, |r| {
                f64::from(r.beyond_two) / f64::from(r.groups.max(1))
            })
            .with(MEDIAN_ABS_Z, |r| median(&r.medians))
            .with(LARGEST_ABS_Z, |r| r.largest)
            .with(LARGEST_POTENTIAL, |r| r.largest_at.0.clone())
            .with(LARGEST_U_PRIME, |r| r.largest_at.1)
            .with(LARGEST_DEVIATION, |r| r.deviation)
            .table(&TABLE)?)
    }
}

/// The held-out kernels along one coordinate, summed.
struct Along {
    /// The coordinate.
    coordinate: &'static str,
    /// Groups compared.
    groups: u32,
    /// Groups with `|z| > 2`.
    beyond_two: u32,
    /// Each held-out kernel's median `|z|`.
    medians: Vec<f64>,
    /// The largest `|z|`.
    largest: f64,
    /// The potential and `u'` of the kernel with the largest `|z|`.
    largest_at: (String, f64),
    /// The largest `|G_predicted / G_model - 1|`.
    deviation: f64,
}

impl Along {
    /// Nothing held out yet along `coordinate`.
    fn new(coordinate: &'static str) -> Along {
        Along {
            coordinate,
            groups: 0,
            beyond_two: 0,
            medians: Vec::new(),
            largest: 0.0,
            largest_at: (String::new(), f64::NAN),
            deviation: 0.0,
        }
    }

    /// The held-out kernel `held_out`, with its groups' `|z|` and its
    /// largest relative deviation.
    fn add(&mut self, held_out: HeldOut, abs_z: &[f64], deviation: f64) {
        self.groups += abs_z.len() as u32;
        self.beyond_two += abs_z.iter().filter(|&&z| z > 2.0).count() as u32;
        self.medians.push(median(abs_z));
        let largest = abs_z.iter().copied().fold(0.0, f64::max);
        if largest > self.largest || self.largest_at.0.is_empty() {
            self.largest = largest;
            self.largest_at = (held_out.potential, held_out.u_prime);
        }
        self.deviation = self.deviation.max(deviation);
    }
}
