//! `spectrum`: the relaxation spectrum of one potential's collision
//! generators on a velocity grid (issue 35), with jackknife errors over the
//! randomizations of its wide scenes. The generators are the `evolve`
//! stage's (`evolve::operator`, the same events and deposition): `full`, the
//! linearized three-body collision operator, and `tagged`, the special
//! particle alone. What relaxes last, and how fast, is
//! `evolve::spectrum`'s; this stage reads the events, calls it on every
//! replicate and on disjoint groups of randomizations, and writes the tables.
//! Rates in `rho^2 l v_th`.

use serde_json::Value;

use crate::config::{SpectrumEstimator, SpectrumParams};
use crate::contract::instances;
use crate::contract::readers::collision_events;
use crate::contract::{self, Rows};
use crate::evolve::grid::VelocityGrid;
use crate::evolve::operator::{Generators, balanced_generators, kernel_generators};
use crate::evolve::processes::collision_invariants;
use crate::evolve::propagate::Generator;
use crate::evolve::spectrum::{Spectrum, spectrum};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::{Entries, Estimate, Replicated, jackknife, replicate_means};

/// The `spectrum` stage of one potential.
pub struct SpectrumStage {
    params: SpectrumParams,
    /// The collisions instance whose scenes fill the grid.
    wide_collisions: String,
}

/// Slowest rates per group in `spectrum_scenes`.
const GROUP_MODES: usize = 10;

/// The names of the two generators, and their invariants' names.
const GENERATORS: [(&str, &[&str]); 2] = [
    ("full", &["number", "momentum", "energy"]),
    ("tagged", &["number"]),
];

/// One generator's spectrum on every replicate set, and the variance rate
/// (shared by both generators).
struct Analysed<'a> {
    name: &'static str,
    invariants: &'static [&'static str],
    spectra: Replicated<Spectrum>,
    gamma: &'a Replicated<f64>,
    /// Per group size: the slowest rates of each group.
    groups: Vec<GroupRates>,
}

/// The slowest rates of every disjoint group of `size` randomizations.
struct GroupRates {
    size: usize,
    rates: Vec<Vec<f64>>,
}

impl SpectrumStage {
    /// The spectrum with resolved parameters, from the collisions named
    /// `wide_collisions` (a launch mixture reaching the whole grid).
    pub fn new(params: SpectrumParams, wide_collisions: String) -> SpectrumStage {
        SpectrumStage {
            params,
            wide_collisions,
        }
    }

    fn grid(&self) -> VelocityGrid {
        VelocityGrid::covering(self.params.velocity_range, self.params.grid_step)
    }

    /// The spectra of generator `which` of every replicate set and group.
    fn analyse<'a>(
        &self,
        generators: &[Generators],
        which: usize,
        gamma: &'a Replicated<f64>,
    ) -> Result<Analysed<'a>, StageError> {
        let grid = self.grid();
        let (name, invariant_names) = GENERATORS[which];
        let invariants: Vec<Vec<f64>> = collision_invariants(&grid)
            .into_iter()
            .take(invariant_names.len())
            .collect();
        let pick = |g: &Generators| {
            if which == 0 {
                g.full.clone()
            } else {
                g.tagged.clone()
            }
        };
        let replicates: Vec<Generator> = generators.iter().map(pick).collect();
        let equilibrium = grid.maxwellian();
        let modes = self.params.modes as usize;
        let solve = |m: &Generator| spectrum(m, &equilibrium, &invariants, modes);
        let means = replicate_means(&replicates);
        let raw = means.map(solve).transpose().map_err(eigen_error)?;
        let spectra = Replicated {
            leave_one_out: raw
                .leave_one_out
                .into_iter()
                .map(|s| s.aligned(&raw.full, &equilibrium))
                .collect(),
            full: raw.full,
        };
        Ok(Analysed {
            name,
            invariants: invariant_names,
            spectra,
            gamma,
            groups: group_rates(&replicates, |m| solve(m).map(|s| s.rates))?,
        })
    }

    /// The tagged variance rate at `u' = 0` of every replicate set, from
    /// each replicate's tagged column there.
    fn gamma(&self, columns: &[Vec<f64>]) -> Replicated<f64> {
        replicate_means(columns).map(|column| self.grid().moments(column, 0.0, f64::INFINITY)[2])
    }
}

/// Per group size `m` (powers of two up to the randomizations): the slowest
/// [`GROUP_MODES`] rates of every disjoint group of `m` consecutive
/// randomizations, each group's generator the mean of its own.
fn group_rates(
    replicates: &[Generator],
    rates: impl Fn(&Generator) -> Result<Vec<f64>, crate::linalg::EigenError> + Sync,
) -> Result<Vec<GroupRates>, StageError> {
    use rayon::prelude::*;
    let count = replicates.len();
    let sizes = std::iter::successors(Some(1), |m| Some(m * 2)).take_while(|&m| m <= count);
    sizes
        .map(|m| {
            let groups: Vec<&[Generator]> = replicates.chunks_exact(m).collect();
            let slowest = groups
                .par_iter()
                .map(|group| {
                    let mean = Generator::mean(Generator::sum(group), m);
                    rates(&mean).map(|r| r.into_iter().take(GROUP_MODES).collect())
                })
                .collect::<Result<Vec<Vec<f64>>, _>>()
                .map_err(eigen_error)?;
            Ok(GroupRates {
                size: m,
                rates: slowest,
            })
        })
        .collect()
}

fn eigen_error(error: crate::linalg::EigenError) -> StageError {
    StageError::Input(format!("diagonalizing the generator: {error}"))
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for SpectrumStage {
    fn id(&self) -> InstanceId {
        instances::spectrum(&self.params.kernel.potential)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::spectrum::*;
        &[
            rates::TABLE.name,
            summary::TABLE.name,
            conserved::TABLE.name,
            modes::TABLE.name,
            scenes::TABLE.name,
            jackknife::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![instances::collisions(&self.wide_collisions)]
    }

    fn work_units(&self) -> u64 {
        3
    }

    /// Placing every event image on every node dominates: 5e-8 s per event
    /// row and node for the columns (measured 2026-11-27, 2 cores: `n = 6`'s
    /// 2.0e6 wide rows in 12 s on 161 nodes, 19 s on 201, 31 s on 321), 8e-8
    /// s for the Dirichlet form (9.9e5 rows: 12.8 s on 161 nodes, 7.1 s on
    /// 81; the columns 7.8 s on 161); the tables hold a row per mode and
    /// generator, and the shapes a row per node.
    fn cost(&self, inputs: &[Cost]) -> Cost {
        let events: f64 = inputs.iter().map(|input| input.rows).sum();
        let nodes = self.grid().len() as f64;
        let rows = 2.0 * nodes * (1.0 + f64::from(self.params.modes));
        let per_placement = match self.params.estimator {
            SpectrumEstimator::Columns => 5e-8,
            SpectrumEstimator::DetailedBalance => 8e-8,
        };
        Cost {
            cpu_seconds: per_placement * events * nodes,
            bytes: 40.0 * rows,
            rows,
        }
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let (events, draws, _) = collision_events(&inputs[0])?;
        progress.set_total(2 + events.len() as u64);
        let (grid, floor) = (self.grid(), self.params.kernel.kick_floor);
        let centre = grid
            .node_of(0.0)
            .ok_or_else(|| StageError::Input("u = 0 is no grid node".into()))?;
        let (generators, centre_columns) = match self.params.estimator {
            SpectrumEstimator::Columns => {
                let generators = kernel_generators(&events, &draws, &grid, floor, |done| {
                    progress.advance(done as u64)
                });
                let columns = generators.iter().map(|g| g.tagged.column(centre)).collect();
                (generators, columns)
            }
            SpectrumEstimator::DetailedBalance => {
                balanced_generators(&events, &draws, &grid, floor, centre, |done| {
                    progress.advance(done as u64)
                })
            }
        };
        let gamma = self.gamma(&centre_columns);
        let analysed = [
            self.analyse(&generators, 0, &gamma)?,
            self.analyse(&generators, 1, &gamma)?,
        ];
        progress.advance(2);
        Ok(vec![
            rates_table(&analysed)?,
            self.summary_table(&analysed, draws.replicates())?,
            conserved_table(&analysed)?,
            self.modes_table(&analysed)?,
            scenes_table(&analysed)?,
            jackknife_table(&analysed)?,
        ])
    }
}

/// Jackknife estimate of `f` of the spectrum.
fn of(spectra: &Replicated<Spectrum>, f: impl Fn(&Spectrum) -> f64) -> Estimate {
    spectra.scalar(f)
}

/// Jackknife estimate of `f` of the spectrum over `Gamma`, per replicate.
fn over_gamma(a: &Analysed, f: impl Fn(&Spectrum) -> f64 + Sync) -> Estimate {
    a.spectra.zip(a.gamma, |s, g| f(s) / g).scalar(|x| *x)
}

/// Modes of the estimate on all randomizations with a negative rate: noise
/// (the operator has none), ranked below the physical spectrum.
fn growing(a: &Analysed) -> usize {
    a.spectra.full.rates.iter().filter(|&&r| r < 0.0).count()
}

/// `spectrum.parquet`.
fn rates_table(analysed: &[Analysed]) -> Result<Table, StageError> {
    use contract::spectrum::rates::*;
    let mut rows = Vec::new();
    for a in analysed {
        for k in 0..a.spectra.full.rates.len() {
            let parity = if a.spectra.full.parities[k] > 0.0 {
                "even"
            } else {
                "odd"
            };
            rows.push((
                a.name,
                k as u32 + 1,
                parity,
                of(&a.spectra, |s| s.rates[k]),
                over_gamma(a, |s| s.rates[k]),
            ));
        }
    }
    Ok(Rows::new(&rows)
        .with(GENERATOR, |r| r.0.to_string())
        .with(MODE, |r| r.1)
        .with(PARITY, |r| r.2.to_string())
        .estimate(RATE, |r| r.3)
        .estimate(RATE_OVER_VARIANCE_RATE, |r| r.4)
        .table(&TABLE)?)
}

impl SpectrumStage {
    /// `spectrum_summary.parquet`.
    fn summary_table(
        &self,
        analysed: &[Analysed],
        randomizations: usize,
    ) -> Result<Table, StageError> {
        use contract::spectrum::summary::*;
        let p = &self.params;
        Ok(Rows::new(analysed)
            .with(GENERATOR, |a| a.name.to_string())
            .with(VELOCITY_RANGE, |_| p.velocity_range)
            .with(GRID_STEP, |_| p.grid_step)
            .with(RANDOMIZATIONS, |_| randomizations as u32)
            .estimate(VARIANCE_RATE, |a| a.gamma.scalar(|g| *g))
            .estimate(GAP, |a| of(&a.spectra, |s| s.rates[growing(a)]))
            .estimate(GAP_OVER_VARIANCE_RATE, |a| {
                over_gamma(a, |s| s.rates[growing(a)])
            })
            .with(GROWING_MODES, |a| growing(a) as u32)
            .with(FASTEST_GROWTH, |a| (-a.spectra.full.rates[0]).max(0.0))
            .estimate(ASYMMETRY, |a| of(&a.spectra, |s| s.asymmetry))
            .table(&TABLE)?)
    }

    /// `spectrum_modes.parquet`.
    fn modes_table(&self, analysed: &[Analysed]) -> Result<Table, StageError> {
        use contract::spectrum::modes::*;
        let grid = self.grid();
        let f0 = grid.maxwellian();
        let mut rows = Vec::new();
        for a in analysed {
            for k in 0..a.spectra.full.shapes.len() {
                let loo: Vec<&[f64]> = a
                    .spectra
                    .leave_one_out
                    .iter()
                    .map(|s| s.shapes[k].as_slice())
                    .collect();
                let shape = jackknife(&a.spectra.full.shapes[k], &loo);
                for (node, g) in shape.into_iter().enumerate() {
                    let density = g.scaled(f0[node] / grid.step);
                    rows.push((a.name, k as u32 + 1, grid.velocity(node), g, density));
                }
            }
        }
        Ok(Rows::new(&rows)
            .with(GENERATOR, |r| r.0.to_string())
            .with(MODE, |r| r.1)
            .with(U, |r| r.2)
            .estimate(SHAPE, |r| r.3)
            .estimate(DENSITY, |r| r.4)
            .table(&TABLE)?)
    }
}

/// `spectrum_conserved.parquet`.
fn conserved_table(analysed: &[Analysed]) -> Result<Table, StageError> {
    use contract::spectrum::conserved::*;
    let mut rows = Vec::new();
    for a in analysed {
        for (k, invariant) in a.invariants.iter().enumerate() {
            rows.push((
                a.name,
                *invariant,
                of(&a.spectra, |s| s.residuals[k]),
                of(&a.spectra, |s| s.conserved[k].eigenvalue),
                of(&a.spectra, |s| s.conserved[k].overlap),
            ));
        }
    }
    Ok(Rows::new(&rows)
        .with(GENERATOR, |r| r.0.to_string())
        .with(INVARIANT, |r| r.1.to_string())
        .estimate(RESIDUAL, |r| r.2)
        .estimate(EIGENVALUE, |r| r.3)
        .estimate(OVERLAP, |r| r.4)
        .table(&TABLE)?)
}

/// `spectrum_jackknife.parquet`.
fn jackknife_table(analysed: &[Analysed]) -> Result<Table, StageError> {
    use contract::spectrum::jackknife::*;
    let mut rows = Vec::new();
    for a in analysed {
        let gap = growing(a);
        let left_out = a.spectra.leave_one_out.iter().zip(&a.gamma.leave_one_out);
        for (r, (spectrum, gamma)) in left_out.enumerate() {
            rows.push((a.name, r as u32, *gamma, spectrum.rates[gap]));
        }
    }
    Ok(Rows::new(&rows)
        .with(GENERATOR, |r| r.0.to_string())
        .with(RANDOMIZATION, |r| r.1)
        .with(VARIANCE_RATE, |r| r.2)
        .with(GAP, |r| r.3)
        .table(&TABLE)?)
}

/// `spectrum_scenes.parquet`.
fn scenes_table(analysed: &[Analysed]) -> Result<Table, StageError> {
    use contract::spectrum::scenes::*;
    let mut rows = Vec::new();
    for a in analysed {
        for GroupRates {
            size,
            rates: groups,
        } in &a.groups
        {
            for k in 0..GROUP_MODES.min(groups[0].len()) {
                let values: Vec<f64> = groups.iter().map(|g| g[k]).collect();
                let rate = if values.len() > 1 {
                    Estimate::from_replicates(&values)
                } else {
                    Estimate {
                        mean: values[0],
                        stderr: f64::NAN,
                    }
                };
                rows.push((
                    a.name,
                    *size as u32,
                    groups.len() as u32,
                    k as u32 + 1,
                    rate,
                ));
            }
        }
    }
    Ok(Rows::new(&rows)
        .with(GENERATOR, |r| r.0.to_string())
        .with(RANDOMIZATIONS, |r| r.1)
        .with(GROUPS, |r| r.2)
        .with(MODE, |r| r.3)
        .estimate(RATE, |r| r.4)
        .table(&TABLE)?)
}
