//! `dissociation`: the rate at which thermal atoms break thermal bound pairs
//! (`A2 + A -> 3A`) for one potential with a well, from scrambled Sobol'
//! scenes (`physics::dissociation`), with the recombination rate detailed
//! balance predicts from it, thermally averaged and against `u'`.

use serde_json::Value;

use crate::config::DissociationParams;
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::physics::dissociation::{
    BoundPair, balanced_recombination, dissociation_rate, sobol_dissociation_scenes,
};
use crate::physics::scene::Collision;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `dissociation` stage of one potential.
pub struct DissociationStage {
    params: DissociationParams,
}

impl DissociationStage {
    /// A dissociation run with resolved parameters.
    pub fn new(params: DissociationParams) -> DissociationStage {
        DissociationStage { params }
    }

    /// The scenes of randomization `randomization`, in point order.
    fn scenes(
        &self,
        randomization: u32,
        progress: &Progress,
    ) -> Result<Vec<(BoundPair, Collision)>, StageError> {
        let p = &self.params;
        let net = (p.seed, randomization, p.points);
        sobol_dissociation_scenes(&p.potential, &p.engine, net, || progress.advance(1)).ok_or_else(
            || {
                StageError::Invariant(format!(
                    "{} has no well: no bound pairs to break",
                    self.params.potential.id()
                ))
            },
        )
    }
}

/// The `u'` grid of `recombination.parquet`: `-3 .. 3` in steps of 0.25
/// (the sweep's default grid), `v_th`.
fn u_prime_grid() -> Vec<f64> {
    (-12..=12).map(|k| 0.25 * f64::from(k)).collect()
}

/// Per randomization: `k_d`, then `R(u')` on the grid.
struct Replicate {
    rate: f64,
    recombination: Vec<f64>,
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for DissociationStage {
    fn id(&self) -> InstanceId {
        instances::dissociation(&self.params.potential)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[
            contract::dissociation::TABLE.name,
            contract::dissociation::recombination::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        u64::from(self.params.points) * u64::from(self.params.randomizations)
    }

    /// One scene per point, its CPU time growing with the well depth `D`
    /// (`kT`; a deep well oscillates many times while the atom approaches):
    /// `1.35e-4 s (4D)^0.75` for `4D > 1`, `(4D)^0.4` below at the engine
    /// tolerance 1e-12, within 30% of the default study's Lennard-Jones
    /// scenes (measured 2026-11-27 on 2 cores: 1.84 ms at `D = 5` (`theta =
    /// 0.05`), 0.17 ms at `D = 1/4`, 0.031 ms at `D = 1/400`; 0.79x that
    /// since 2026-12-03, sixteen scenes integrated four at a time per task). A looser
    /// tolerance starts the atom closer (`tolerance^(-1/12)`, the `r^-6` tail
    /// at the level `0.1 sqrt(tolerance)`) and takes as many fewer steps per
    /// unit time: `tolerance^(-1/6)` in all (0.46x at 1e-10, measured 0.48x).
    fn cost(&self, _inputs: &[Cost]) -> Cost {
        let scenes = self.work_units() as f64;
        let depth = 4.0 * self.params.potential.well_depth();
        let exponent = if depth > 1.0 { 0.75 } else { 0.4 };
        let tolerance = libm::pow(self.params.engine.tolerance / 1e-12, -1.0 / 6.0);
        Cost {
            cpu_seconds: scenes * 1.35e-4 * libm::pow(depth, exponent) * tolerance,
            bytes: 200.0,
            rows: 1.0,
        }
    }

    fn run(&self, _inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let bound_length = self.params.potential.family().bound_pair_length();
        let grid = u_prime_grid();
        let mut replicates = Vec::new();
        let (mut failed, mut max_energy_error) = (0_u32, 0.0_f64);
        for randomization in 0..self.params.randomizations {
            let scenes = self.scenes(randomization, progress)?;
            replicates.push(Replicate {
                rate: dissociation_rate(&scenes),
                recombination: balanced_recombination(&scenes, bound_length, &grid),
            });
            for (_, collision) in &scenes {
                if collision.outcome.is_failure() {
                    failed += 1;
                } else {
                    max_energy_error = max_energy_error.max(collision.energy_error.abs());
                }
            }
        }
        let rate =
            Estimate::from_replicates(&replicates.iter().map(|r| r.rate).collect::<Vec<_>>());
        Ok(vec![
            self.rate_table(bound_length, rate, failed, max_energy_error)?,
            recombination_table(&grid, &replicates, 3.0 * bound_length, rate)?,
        ])
    }
}

impl DissociationStage {
    /// `dissociation.parquet`.
    fn rate_table(
        &self,
        bound_length: f64,
        rate: Estimate,
        failed: u32,
        max_energy_error: f64,
    ) -> Result<Table, StageError> {
        use contract::dissociation::*;
        let balanced = rate.scaled(3.0 * bound_length);
        Ok(Rows::new(&[()])
            .optional(THETA, |_| self.params.potential.family().theta())
            .with(BOUND_PAIR_LENGTH, |_| bound_length)
            .estimate(DISSOCIATION_RATE, |_| rate)
            .estimate(BALANCED_RECOMBINATION, |_| balanced)
            .with(SCENES, |_| self.work_units() as u32)
            .with(FAILED_SCENES, |_| failed)
            .with(MAX_ENERGY_ERROR, |_| max_energy_error)
            .table(&TABLE)?)
    }
}

/// `recombination.parquet`: `R(u')` on the grid, then its thermal average
/// `3 K_b k_d` (`balance` is `3 K_b`).
fn recombination_table(
    grid: &[f64],
    replicates: &[Replicate],
    balance: f64,
    rate: Estimate,
) -> Result<Table, StageError> {
    use contract::dissociation::recombination::*;
    let rows: Vec<(Option<f64>, Estimate)> = grid
        .iter()
        .enumerate()
        .map(|(k, &u)| {
            let values: Vec<f64> = replicates.iter().map(|r| r.recombination[k]).collect();
            (Some(u), Estimate::from_replicates(&values))
        })
        .chain([(None, rate.scaled(balance))])
        .collect();
    Ok(Rows::new(&rows)
        .optional(U_PRIME, |r| r.0)
        .estimate(RATE_COLUMN, |r| r.1)
        .table(&TABLE)?)
}
