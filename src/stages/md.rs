//! `md`: molecular dynamics of one ring (physics.md §7): independent runs in
//! parallel, each from its own seeded initial state, advanced by cluster
//! stepping; `h(u, t_f)` by the published estimator and by the tagged-velocity
//! estimator, averaged over a short window around `t_f`, with standard errors
//! from the spread of runs; conservation diagnostics per run. The `n = 2`
//! (Sutherland) ring runs as a whole with all pairs, its lineages being its
//! conserved rapidities. Lennard-Jones rings also report their bound pairs,
//! sampled and after the dynamics, against the dilute limit.

use std::ops::Range;

use rayon::prelude::*;
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::binning::Bins;
use crate::config::MdParams;
use crate::contract::instances;
use crate::contract::{self, Col, Rows, TableSpec};
use crate::physics::md::{CLUSTER_STEP_BUDGET, RunResult, RunSettings, ThermalLineages, run};
use crate::physics::potential::{PairPotential, PotentialVisitor};
use crate::physics::ring::{Reach, RingForces};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `md` stage for one ring.
pub struct MdStage {
    params: MdParams,
}

impl MdStage {
    /// An md stage with resolved parameters.
    pub fn new(params: MdParams) -> MdStage {
        MdStage { params }
    }

    fn settings(&self) -> RunSettings {
        let p = &self.params;
        RunSettings {
            particles: p.particles as usize,
            u_prime: p.u_prime,
            tolerance: p.tolerance,
            sample_times: p.sample_times.clone(),
            bins: Bins::for_window(p.window, p.bin_width),
            start_band: p.start_band,
            max_steps: CLUSTER_STEP_BUDGET,
        }
    }

    /// Seed of run `k`: the study's seed mixed with the ring's name and the
    /// run index, so that rings of a study draw independent initial states
    /// (correlated rings would correlate the errors of a finite-size trend).
    fn seed(&self, run: u32) -> u64 {
        let digest = Sha256::digest(self.params.name.as_bytes());
        let name = u64::from_le_bytes(digest[..8].try_into().unwrap_or([0; 8]));
        self.params.seed ^ name ^ u64::from(run + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    }
}

/// Runs the seeds of `runs` with the concrete potential.
struct Runs<'a> {
    stage: &'a MdStage,
    runs: Range<u32>,
    progress: &'a Progress,
}

impl PotentialVisitor for Runs<'_> {
    type Output = Result<Vec<RunResult>, StageError>;

    fn visit<P: PairPotential>(self, potential: P) -> Self::Output {
        let p = &self.stage.params;
        let reach = if p.potential.family().is_integrable() {
            Reach::All
        } else {
            Reach::Neighbours(p.neighbours as usize)
        };
        let forces = RingForces {
            potential,
            circumference: p.circumference,
            reach,
        };
        let settings = self.stage.settings();
        self.runs
            .clone()
            .into_par_iter()
            .map(|k| {
                let result = run(&forces, &settings, self.stage.seed(k))
                    .map_err(|e| StageError::Input(format!("md[{}] run {k}: {e}", p.name)));
                self.progress.advance(1);
                result
            })
            .collect()
    }
}

/// Mean and standard error over runs of bin `k` of `part`. A bin where every
/// run has the same value (no run counted anything there, say) has no spread
/// to estimate an error from: exactly 0, not the rounding residue of the
/// mean, so that chi-square tests can leave it out.
fn per_bin(results: &[RunResult], k: usize, part: fn(&RunResult) -> &Vec<f64>) -> Estimate {
    let values: Vec<f64> = results.iter().map(|r| part(r)[k]).collect();
    let estimate = Estimate::from_replicates(&values);
    if values.iter().all(|v| *v == values[0]) {
        Estimate {
            stderr: 0.0,
            ..estimate
        }
    } else {
        estimate
    }
}

/// One bin of `h` by both estimators.
struct HBin {
    x: f64,
    published: Estimate,
    tagged: Estimate,
}

impl MdStage {
    fn h_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        use contract::md::h::*;
        let bins = self.settings().bins;
        let rows: Vec<HBin> = (0..bins.len())
            .map(|k| HBin {
                x: bins.centre(k),
                published: per_bin(results, k, |r| &r.published),
                tagged: per_bin(results, k, |r| &r.tagged),
            })
            .collect();
        let mut ratios: Vec<f64> = rows
            .iter()
            .filter(|r| r.tagged.stderr > 0.0)
            .map(|r| r.published.stderr / r.tagged.stderr)
            .collect();
        ratios.sort_by(f64::total_cmp);
        let median_ratio = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
        Ok(Rows::new(&rows)
            .with(DU, |r| r.x)
            .with(BIN_CENTRE, |r| self.params.u_prime + r.x)
            .estimate(H_PUBLISHED, |r| r.published)
            .estimate(H_TAGGED, |r| r.tagged)
            .table(&TABLE)?
            .with_metadata("ternary.noise_ratio", median_ratio.to_string())
            .with_metadata(
                "ternary.circumference_l",
                self.params.circumference.to_string(),
            ))
    }

    /// Per estimator: the mass `sum h dx` and variance `sum x^2 h dx` within
    /// the window (x = u - u'), per run, averaged with standard errors.
    fn summary_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        use contract::estimator::{PUBLISHED, TAGGED, THERMAL};
        use contract::md::summary::*;
        let bins = self.settings().bins;
        let moment = |h: &[f64], p: i32| -> f64 {
            h.iter()
                .enumerate()
                .map(|(k, v)| v * bins.centre(k).powi(p) * bins.width)
                .sum()
        };
        let per_run = |value: &dyn Fn(&RunResult) -> f64| {
            Estimate::from_replicates(&results.iter().map(value).collect::<Vec<f64>>())
        };
        let binned =
            |part: fn(&RunResult) -> &Vec<f64>| [0, 2].map(|p| per_run(&|r| moment(part(r), p)));
        let rows = [
            (PUBLISHED, binned(|r| &r.published)),
            (TAGGED, binned(|r| &r.tagged)),
            (
                THERMAL,
                [
                    per_run(&|r| r.thermal.number),
                    per_run(&|r| r.thermal.window_variance),
                ],
            ),
        ];
        Ok(Rows::new(&rows)
            .with(ESTIMATOR, |(name, _)| name.to_string())
            .estimate(NUMBER, |(_, [number, _])| *number)
            .estimate(WINDOW_VARIANCE, |(_, [_, variance])| *variance)
            .table(&TABLE)?)
    }

    /// Fraction of neighbour gaps bound (`w^2/4 + U < 0`) in the initial
    /// states (the sampler's equilibrium) and at the last sample time (after
    /// the dynamics), with standard errors over runs, against the dilute
    /// limit `rho K_b` (0 for purely repulsive potentials).
    fn pairs_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        use contract::md::pairs::*;
        let p = &self.params;
        let gaps = f64::from(p.particles);
        let fraction = |k: usize| {
            let values: Vec<f64> = results
                .iter()
                .map(|r| r.bound_pairs[k] as f64 / gaps)
                .collect();
            Estimate::from_replicates(&values)
        };
        let density = f64::from(p.particles - 1) / p.circumference;
        let dilute = Estimate {
            mean: density * p.potential.family().bound_pair_length(),
            stderr: 0.0,
        };
        let rows = [
            (INITIAL, fraction(0)),
            (FINAL, fraction(1)),
            (DILUTE_LIMIT, dilute),
        ];
        Ok(Rows::new(&rows)
            .with(STATE, |(state, _)| state.to_string())
            .estimate(BOUND_FRACTION, |(_, fraction)| *fraction)
            .table(&TABLE)?)
    }

    fn runs_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        use contract::md::runs::*;
        let rows: Vec<(u32, &RunResult)> = (0..self.params.runs).zip(results).collect();
        let rows = Rows::new(&rows)
            .with(RUN, |(k, _)| *k)
            .with(SEED, |(k, _)| self.seed(*k).to_string());
        Ok(with_diagnostics(rows).table(&TABLE)?)
    }
}

impl MdStage {
    /// The results of the runs in `runs`, in run order.
    fn results(&self, runs: Range<u32>, progress: &Progress) -> Result<Vec<RunResult>, StageError> {
        self.params.potential.visit(Runs {
            stage: self,
            runs,
            progress,
        })
    }

    /// The ring's tables from the results of all its runs.
    fn tables_of(&self, results: &[RunResult]) -> Result<Vec<Table>, StageError> {
        Ok(vec![
            self.h_table(results)?,
            self.summary_table(results)?,
            self.runs_table(results)?,
            self.pairs_table(results)?,
        ])
    }
}

/// The per-run diagnostics columns that `runs` and the shards share.
fn with_diagnostics<'r>(rows: Rows<'r, (u32, &'r RunResult)>) -> Rows<'r, (u32, &'r RunResult)> {
    use contract::md::runs::*;
    rows.with(LINEAGES, |(_, r)| r.lineages as f64)
        .with(THERMAL_LINEAGES, |(_, r)| r.thermal.lineages as f64)
        .with(ENERGY_ERROR, |(_, r)| r.energy_error)
        .with(MOMENTUM_ERROR, |(_, r)| r.momentum_error)
        .with(MACRO_STEPS, |(_, r)| r.macro_steps as f64)
        .with(PAIR_FORCES, |(_, r)| r.pair_forces as f64)
        .with(BOUND_PAIRS_START, |(_, r)| r.bound_pairs[0] as u32)
        .with(BOUND_PAIRS_END, |(_, r)| r.bound_pairs[1] as u32)
        .with(INVARIANT_DRIFT, |(_, r)| r.invariant_drift)
}

/// A shard's tables: every field of each run's result, exactly (run indices
/// from `first`).
fn shard_tables(first: u32, results: &[RunResult]) -> Result<Vec<Table>, StageError> {
    use contract::md::shard::*;
    let rows: Vec<(u32, &RunResult)> = (first..).zip(results).collect();
    let per_run = with_diagnostics(Rows::new(&rows).with(RUN, |(k, _)| *k))
        .with(THERMAL_NUMBER, |(_, r)| r.thermal.number)
        .with(THERMAL_WINDOW_VARIANCE, |(_, r)| r.thermal.window_variance)
        .table(&RESULTS)?;
    let bins: Vec<(u32, usize, f64, f64)> = rows
        .iter()
        .flat_map(|(k, r)| {
            (0..r.published.len()).map(move |b| (*k, b, r.published[b], r.tagged[b]))
        })
        .collect();
    let per_bin = Rows::new(&bins)
        .with(RUN, |row| row.0)
        .with(BIN, |row| row.1 as u32)
        .with(PUBLISHED, |row| row.2)
        .with(TAGGED, |row| row.3)
        .table(&BINS)?;
    Ok(vec![per_run, per_bin])
}

/// The runs' results in a shard's tables, in run order (`bins` per run).
fn results_of(tables: &[Table], bins: usize) -> Result<Vec<RunResult>, StageError> {
    use contract::md::shard::*;
    let table = |spec: &TableSpec| {
        tables
            .iter()
            .find(|t| t.name == spec.name)
            .map(|t| &t.batch)
            .ok_or_else(|| StageError::Input(format!("a shard lacks `{}`", spec.name)))
    };
    let (per_run, per_bin) = (table(&RESULTS)?, table(&BINS)?);
    let published = PUBLISHED.read(per_bin)?;
    let tagged = TAGGED.read(per_bin)?;
    let column = |col: Col<f64>| col.read(per_run);
    let (lineages, thermal_lineages) = (column(LINEAGES)?, column(THERMAL_LINEAGES)?);
    let (number, variance) = (column(THERMAL_NUMBER)?, column(THERMAL_WINDOW_VARIANCE)?);
    let (energy, momentum) = (column(ENERGY_ERROR)?, column(MOMENTUM_ERROR)?);
    let (steps, forces) = (column(MACRO_STEPS)?, column(PAIR_FORCES)?);
    let drift = column(INVARIANT_DRIFT)?;
    let (start, end) = (
        BOUND_PAIRS_START.read(per_run)?,
        BOUND_PAIRS_END.read(per_run)?,
    );
    Ok((0..lineages.len())
        .map(|k| RunResult {
            published: published[k * bins..(k + 1) * bins].to_vec(),
            tagged: tagged[k * bins..(k + 1) * bins].to_vec(),
            lineages: lineages[k] as usize,
            thermal: ThermalLineages {
                lineages: thermal_lineages[k] as usize,
                number: number[k],
                window_variance: variance[k],
            },
            energy_error: energy[k],
            momentum_error: momentum[k],
            macro_steps: steps[k] as u64,
            pair_forces: forces[k] as u64,
            bound_pairs: [start[k] as usize, end[k] as usize],
            invariant_drift: drift[k],
        })
        .collect())
}

/// CPU seconds per neighbour encounter of a ring run at the MD tolerance
/// [`ENCOUNTER_TOLERANCE`]: the default study's eleven rings, 168 CPU seconds
/// (2026-12-01, the 2-core VM, `ternary status --costs`); dense rings cost
/// up to 3x, Lennard-Jones 8x (bound pairs).
const CPU_PER_ENCOUNTER: f64 = 1.3e-5;

/// The tolerance [`CPU_PER_ENCOUNTER`] holds at; the cost goes as
/// `tolerance^(-0.12)` (the rings took 0.58x at 1e-8 what they took at 1e-10,
/// 2026-11-29).
const ENCOUNTER_TOLERANCE: f64 = 1e-8;

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for MdStage {
    fn id(&self) -> InstanceId {
        instances::md(&self.params.name)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::md::*;
        &[
            h::TABLE.name,
            summary::TABLE.name,
            runs::TABLE.name,
            pairs::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        u64::from(self.params.runs)
    }

    /// Runs times neighbour encounters per run (`N rho v_th t_f`) at
    /// `CPU_PER_ENCOUNTER`, scaled to the tolerance; small tables.
    fn cost(&self, _inputs: &[Cost]) -> Cost {
        let gas = &self.params.gas;
        let encounters = f64::from(self.params.particles)
            * gas.density_per_um
            * gas.thermal_speed_um_per_ns()
            * self.params.final_time_ns;
        Cost {
            cpu_seconds: f64::from(self.params.runs)
                * encounters
                * CPU_PER_ENCOUNTER
                * libm::pow(self.params.tolerance / ENCOUNTER_TOLERANCE, -0.12),
            bytes: 3e4,
            rows: 100.0,
        }
    }

    fn run(&self, _inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        self.tables_of(&self.results(0..self.params.runs, progress)?)
    }

    /// Runs are independent: a shard computes some of them.
    fn shard_units(&self) -> u32 {
        self.params.runs
    }

    fn run_shard(
        &self,
        _inputs: &[Input],
        runs: Range<u32>,
        progress: &Progress,
    ) -> Result<Vec<Table>, StageError> {
        let first = runs.start;
        let results = self.results(runs, progress)?;
        shard_tables(first, &results)
    }

    fn shard_tables(&self) -> &'static [&'static str] {
        use contract::md::shard::*;
        &[RESULTS.name, BINS.name]
    }

    /// The ring's tables from every run's results, read back from the shards
    /// in run order.
    fn merge(&self, shards: Vec<Vec<Table>>) -> Result<Vec<Table>, StageError> {
        let mut results = Vec::new();
        for tables in &shards {
            results.extend(results_of(tables, self.settings().bins.len())?);
        }
        self.tables_of(&results)
    }
}
