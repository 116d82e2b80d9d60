//! `dissociation`: the rate at which thermal atoms break thermal bound pairs
//! (`A2 + A -> 3A`) for one potential with a well, from scrambled Sobol'
//! scenes (`physics::dissociation`), with the recombination rate detailed
//! balance predicts from it.

use serde_json::Value;

use crate::config::DissociationParams;
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::physics::dissociation::{BoundPair, dissociation_rate, dissociation_scenes};
use crate::physics::quasi_random::ScrambledSobol;
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
        let sobol = ScrambledSobol::new(self.params.seed, u64::from(randomization));
        let points: Vec<[f64; 3]> = (0..self.params.points).map(|k| sobol.point(k)).collect();
        dissociation_scenes(&self.params.potential, &self.params.engine, &points, || {
            progress.advance(1)
        })
        .ok_or_else(|| {
            StageError::Invariant(format!(
                "{} has no well: no bound pairs to break",
                self.params.potential.id()
            ))
        })
    }
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
        &[contract::dissociation::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        u64::from(self.params.points) * u64::from(self.params.randomizations)
    }

    /// One scene per point: ~0.9 ms at `theta = 0.1`, ~0.05 ms at `theta = 10`
    /// (deep wells oscillate many times while the atom approaches).
    fn cost(&self, _inputs: &[Cost]) -> Cost {
        let scenes = self.work_units() as f64;
        Cost {
            cpu_seconds: scenes * 9e-4,
            bytes: 200.0,
            rows: 1.0,
        }
    }

    fn run(&self, _inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::dissociation::*;
        let mut rates = Vec::new();
        let (mut failed, mut max_energy_error) = (0_u32, 0.0_f64);
        for randomization in 0..self.params.randomizations {
            let scenes = self.scenes(randomization, progress)?;
            rates.push(dissociation_rate(&scenes));
            for (_, collision) in &scenes {
                if collision.outcome.is_failure() {
                    failed += 1;
                } else {
                    max_energy_error = max_energy_error.max(collision.energy_error.abs());
                }
            }
        }
        let family = self.params.potential.family();
        let bound_length = family.bound_pair_length();
        let rate = Estimate::from_replicates(&rates);
        let balanced = Estimate {
            mean: 3.0 * bound_length * rate.mean,
            stderr: 3.0 * bound_length * rate.stderr,
        };
        let table = Rows::new(&[()])
            .optional(THETA, |_| family.theta())
            .with(BOUND_PAIR_LENGTH, |_| bound_length)
            .estimate(DISSOCIATION_RATE, |_| rate)
            .estimate(BALANCED_RECOMBINATION, |_| balanced)
            .with(SCENES, |_| self.work_units() as u32)
            .with(FAILED_SCENES, |_| failed)
            .with(MAX_ENERGY_ERROR, |_| max_energy_error)
            .table(&TABLE)?;
        Ok(vec![table])
    }
}
