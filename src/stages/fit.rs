//! `fit`: the shape `g(x) = alpha |x|^-beta exp(-x^2 / 2 sigma^2)` of the kernel
//! near `u'` (physics.md §5) at one `u'` and density, fitted to the mean kernel
//! under several protocols, one row each: the study's (weights
//! `1 / G_stderr^2` over the configured range of `|u - u'|`), the paper's as far
//! as it states it (the same up to its truncation `|x| <= 0.04`), and the
//! variations of range and weights whose half-spread is every row's systematic
//! error. Standard errors and covariance from refitting every randomization
//! alone (the `kernel` stage's `kernel_replicates` table).
//!
//! And the kernel model (`kernel::model`): `ln G` a natural cubic spline in
//! `ln|du| + |du| / x_c` on each side of `u'`, fitted to the log-spaced
//! groups, written as its knots, their covariance and its jackknife
//! replicates, its goodness of fit and the fitted groups with their
//! residuals; for the whole kernel and for its self part (`part`), whose
//! difference is the bath part.

use rayon::prelude::*;
use serde_json::Value;

use crate::config::FitParams;
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::kernel::fit::{
    KernelFit, Protocol, Shape, Weighting, fit_kernel, systematic, varied_protocols,
};
use crate::kernel::model::{
    GroupFit, KernelModel, NoModel, Part, Side, SideModel, fit_kernel_model, side_groups,
};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `fit` stage for one potential, `u'` and density.
pub struct FitStage {
    params: FitParams,
}

impl FitStage {
    /// A fit stage with resolved parameters.
    pub fn new(params: FitParams) -> FitStage {
        FitStage { params }
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for FitStage {
    fn id(&self) -> InstanceId {
        instances::fit(&self.params.kernel)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[
            contract::fit::TABLE.name,
            contract::fit::model::TABLE.name,
            contract::fit::model_covariance::TABLE.name,
            contract::fit::model_jackknife::TABLE.name,
            contract::fit::model_fit::TABLE.name,
            contract::fit::model_groups::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![InstanceId::new(
            contract::kernel::STAGE,
            &instances::target(&self.params.kernel),
        )]
    }

    fn work_units(&self) -> u64 {
        1
    }

    /// Every kernel row read, 4.6 us each: the shape's protocols and the
    /// models' cross-validation and sign patterns, for the whole and its
    /// self part (the default study's 114 instances, 36 CPU s measured,
    /// 2026-12-02; 25 s with the whole's model alone).
    fn cost(&self, inputs: &[Cost]) -> Cost {
        Cost::reading(inputs, 4.6e-6, 1e3, 100.0)
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let input = inputs
            .first()
            .ok_or_else(|| StageError::Input("no kernel input".into()))?;
        use contract::kernel::replicates::{G, G_SELF, read};
        let (fine, offsets) = read(input, G)?;
        let fits: Vec<ProtocolFit> = self
            .protocols()
            .into_par_iter()
            .map(|(role, protocol)| ProtocolFit {
                role,
                protocol,
                fit: fit_kernel(&fine, &offsets, protocol),
            })
            .collect();
        let self_part = read(input, G_SELF)?.0;
        let models: Vec<PartModel> = Part::MODELLED
            .into_par_iter()
            .zip([&fine, &self_part])
            .map(|(part, replicates)| {
                let [below, above] =
                    side_groups(replicates, &offsets, self.params.kernel.bin_width);
                (part, fit_kernel_model(below, above))
            })
            .collect();
        progress.advance(1);
        Ok(vec![
            fit_table(&fits)?,
            knots_table(&models)?,
            covariance_table(&models)?,
            jackknife_table(&models)?,
            model_fit_table(&models)?,
            groups_table(&models)?,
        ])
    }
}

impl FitStage {
    /// The study's protocol, the paper's, then the systematic variations.
    fn protocols(&self) -> Vec<(&'static str, Protocol)> {
        use contract::fit::{PAPER_PROTOCOL, STUDY_PROTOCOL, VARIED_PROTOCOL};
        let statistical = |range| Protocol {
            range,
            weighting: Weighting::Statistical,
        };
        let low = self.params.range_min;
        let mut protocols = vec![
            (STUDY_PROTOCOL, statistical((low, self.params.range_max))),
            (
                PAPER_PROTOCOL,
                statistical((low, self.params.paper_range_max)),
            ),
        ];
        // The variations not already fitted above.
        let varied: Vec<Protocol> = varied_protocols()
            .into_iter()
            .filter(|v| protocols.iter().all(|(_, p)| p != v))
            .collect();
        protocols.extend(varied.into_iter().map(|p| (VARIED_PROTOCOL, p)));
        protocols
    }
}

/// One protocol's fit.
struct ProtocolFit {
    role: &'static str,
    protocol: Protocol,
    fit: KernelFit,
}

impl ProtocolFit {
    /// Fitted, or why not.
    fn status(&self) -> &'static str {
        match (&self.fit.mean, self.fit.replicates.len()) {
            // Nothing to fit (e.g. the integrable n = 2 kernel vanishes): say so.
            (None, _) if self.fit.measured == 0 => "kernel vanishes in the fit range",
            (None, _) => "too few measured groups",
            (Some(_), fitted) if fitted < 2 => "replicates could not be fitted: no standard errors",
            (Some(mean), _) if !mean.converged => "fitted, but the mean fit did not converge",
            (Some(_), _) => "fitted",
        }
    }
}

/// The fit table, one row per protocol; NaN where nothing could be fitted.
fn fit_table(fits: &[ProtocolFit]) -> Result<Table, StageError> {
    use contract::fit::*;
    let [alpha, beta, sigma]: [fn(&Shape) -> f64; 3] = [|s| s.alpha, |s| s.beta, |s| s.sigma];
    let parameter = |f: fn(&Shape) -> f64| {
        move |row: &ProtocolFit| Estimate {
            mean: row.fit.mean.map_or(f64::NAN, |m| f(&m.shape)),
            stderr: row.fit.stderr(f),
        }
    };
    let spread = |f: fn(&Shape) -> f64| {
        let value = systematic(fits.iter().map(|row| &row.fit), f);
        move |_: &ProtocolFit| value
    };
    Ok(Rows::new(fits)
        .with(PROTOCOL, |row| row.role.to_string())
        .with(WEIGHTS, |row| row.protocol.weighting.name().to_string())
        .with(RANGE_MIN, |row| row.protocol.range.0)
        .with(RANGE_MAX, |row| row.protocol.range.1)
        .estimate(ALPHA, parameter(alpha))
        .estimate(BETA, parameter(beta))
        .estimate(SIGMA, parameter(sigma))
        .with(ALPHA_SYSTEMATIC, spread(alpha))
        .with(BETA_SYSTEMATIC, spread(beta))
        .with(SIGMA_SYSTEMATIC, spread(sigma))
        .with(COV_ALPHA_BETA, |row| row.fit.covariance(alpha, beta))
        .with(COV_ALPHA_SIGMA, |row| row.fit.covariance(alpha, sigma))
        .with(COV_BETA_SIGMA, |row| row.fit.covariance(beta, sigma))
        .with(SCALE_FACTOR, |row| row.fit.scale().sqrt())
        .with(CHI2_PER_DOF, |row| {
            row.fit.mean.map_or(f64::NAN, |f| f.chi2_per_dof)
        })
        .with(BINS, |row| {
            row.fit.mean.map_or(row.fit.measured, |m| m.bins) as u32
        })
        .with(REPLICATES_FITTED, |row| row.fit.replicates.len() as u32)
        .with(UNCONVERGED_FITS, |row| row.fit.unconverged as u32)
        .with(STATUS, |row| row.status().to_string())
        .table(&TABLE)?)
}

/// A part of the kernel and its model, or why it has none.
type PartModel = (Part, Result<KernelModel, NoModel>);

/// One knot of one side's model of one part.
struct KnotRow<'a> {
    part: Part,
    side: Side,
    knot: usize,
    model: &'a SideModel,
}

/// Every part's knots, each side's below `u'` then above (none of a part
/// without a model).
fn knot_rows(models: &[PartModel]) -> Vec<KnotRow<'_>> {
    models
        .iter()
        .filter_map(|(part, model)| Some((*part, model.as_ref().ok()?)))
        .flat_map(|(part, model)| {
            model
                .both_sides()
                .into_iter()
                .flat_map(move |(side, model)| {
                    (0..model.values.len()).map(move |knot| KnotRow {
                        part,
                        side,
                        knot,
                        model,
                    })
                })
        })
        .collect()
}

/// `kernel_model`: one row per part, side and knot.
fn knots_table(models: &[PartModel]) -> Result<Table, StageError> {
    use contract::fit::model::*;
    let rows = knot_rows(models);
    let size = |row: &KnotRow| row.model.values.len();
    Ok(Rows::new(&rows)
        .with(PART, |row| row.part.name().to_string())
        .with(SIDE, |row| row.side.name().to_string())
        .with(KNOT, |row| row.knot as u32)
        .with(DU, |row| {
            row.side.sign() * row.model.knots.warp.x(row.model.knots.t[row.knot])
        })
        .with(T, |row| row.model.knots.t[row.knot])
        .with(CUTOFF_SCALE, |row| row.model.knots.warp.cutoff_scale)
        .estimate(LN_G, |row| Estimate {
            mean: row.model.values[row.knot],
            stderr: row.model.covariance[row.knot * (size(row) + 1)].sqrt(),
        })
        .table(&TABLE)?)
}

/// Every knot paired with each of `count(model)` indices of its side's
/// model (the other knot, the left-out randomization).
fn knot_pairs(models: &[PartModel], count: fn(&SideModel) -> usize) -> Vec<(KnotRow<'_>, usize)> {
    knot_rows(models)
        .into_iter()
        .flat_map(|row| (0..count(row.model)).map(move |j| (KnotRow { ..row }, j)))
        .collect()
}

/// The rows of a table of knot pairs, labelled with their part and side.
fn labelled<'r, 'm>(rows: &'r [(KnotRow<'m>, usize)]) -> Rows<'r, (KnotRow<'m>, usize)> {
    Rows::new(rows)
        .with(contract::fit::model::PART, |(row, _)| {
            row.part.name().to_string()
        })
        .with(contract::fit::model::SIDE, |(row, _)| {
            row.side.name().to_string()
        })
}

/// `kernel_model_covariance`: one row per part, side and pair of knots.
fn covariance_table(models: &[PartModel]) -> Result<Table, StageError> {
    use contract::fit::model_covariance::*;
    let rows = knot_pairs(models, |model| model.values.len());
    Ok(labelled(&rows)
        .with(KNOT_I, |(row, _)| row.knot as u32)
        .with(KNOT_J, |(_, j)| *j as u32)
        .with(COVARIANCE, |(row, j)| {
            row.model.covariance[row.knot * row.model.values.len() + j]
        })
        .table(&TABLE)?)
}

/// `kernel_model_jackknife`: one row per part, side, left-out
/// randomization and knot.
fn jackknife_table(models: &[PartModel]) -> Result<Table, StageError> {
    use contract::fit::model_jackknife::*;
    let rows = knot_pairs(models, |model| model.left_out.len());
    Ok(labelled(&rows)
        .with(RANDOMIZATION, |(_, r)| *r as u32)
        .with(KNOT, |(row, _)| row.knot as u32)
        .with(LN_G, |(row, r)| row.model.left_out[*r][row.knot])
        .table(&TABLE)?)
}

/// `kernel_model_fit`: the goodness of fit, one row per part.
fn model_fit_table(models: &[PartModel]) -> Result<Table, StageError> {
    use contract::fit::model_fit::*;
    let rows: Vec<(Part, Option<&KernelModel>, &'static str)> = models
        .iter()
        .map(|(part, model)| {
            let status = model.as_ref().map_or_else(|why| why.reason(), |_| "fitted");
            (*part, model.as_ref().ok(), status)
        })
        .collect();
    type Row<'a> = (Part, Option<&'a KernelModel>, &'static str);
    let value = |row: &Row, f: fn(&KernelModel) -> f64| row.1.map_or(f64::NAN, f);
    let count = |row: &Row, f: fn(&KernelModel) -> usize| row.1.map_or(0, f) as u32;
    Ok(Rows::new(&rows)
        .with(contract::fit::model::PART, |row| row.0.name().to_string())
        .with(STATUS, |row| row.2.to_string())
        .with(MIRRORED, |row| count(row, |m| usize::from(m.mirrored)))
        .with(GROUPS, |row| {
            count(row, |m| m.sides.iter().map(|(_, s)| s.groups.len()).sum())
        })
        .with(KNOTS, |row| {
            count(row, |m| m.sides.iter().map(|(_, s)| s.values.len()).sum())
        })
        .with(DOF, |row| count(row, |m| m.goodness.dof))
        .with(CHI2, |row| value(row, |m| m.goodness.chi2))
        .with(CHI2_EXPECTED, |row| value(row, |m| m.goodness.expected))
        .with(CHI2_SPREAD, |row| value(row, |m| m.goodness.spread))
        .with(P_VALUE, |row| value(row, |m| m.goodness.p_value))
        .with(SIGN_PATTERNS, |row| count(row, |m| m.goodness.patterns))
        .with(CONVERGED, |row| {
            count(row, |m| {
                usize::from(m.sides.iter().all(|(_, s)| s.converged))
            })
        })
        .table(&TABLE)?)
}

/// `kernel_model_groups`: every part's fitted groups with the model's
/// value there.
fn groups_table(models: &[PartModel]) -> Result<Table, StageError> {
    use contract::fit::model_groups::*;
    let rows: Vec<(Part, f64, GroupFit)> = models
        .iter()
        .filter_map(|(part, model)| Some((*part, model.as_ref().ok()?)))
        .flat_map(|(part, model)| {
            model.sides.iter().flat_map(move |(side, fit)| {
                fit.groups
                    .iter()
                    .map(move |group| (part, side.sign(), *group))
            })
        })
        .collect();
    Ok(Rows::new(&rows)
        .with(contract::fit::model::PART, |(part, _, _)| {
            part.name().to_string()
        })
        .with(DU, |(_, sign, g)| sign * 0.5 * (g.lower + g.upper))
        .with(DU_INNER, |(_, sign, g)| sign * g.lower)
        .with(DU_OUTER, |(_, sign, g)| sign * g.upper)
        .with(G, |(_, _, g)| g.mean)
        .with(G_STDERR, |(_, _, g)| g.stderr)
        .with(G_MODEL, |(_, _, g)| g.model)
        .with(RESIDUAL, |(_, _, g)| g.residual())
        .table(&TABLE)?)
}
