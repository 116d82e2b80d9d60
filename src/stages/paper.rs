//! `paper`: the published numbers of Phys. Rev. E 110, 014114 (2024) next to
//! ours under the paper's definition, with the relative difference and the
//! z-score, and ours under our own definition where the two differ. One row per
//! published number whose inputs the study computes ([`crate::paper`] holds
//! the numbers and computes each row; this stage encodes them).

use serde_json::Value;

use crate::contract::{self, Rows};
use crate::paper::Check;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `paper` stage.
pub struct PaperStage {
    checks: Vec<Check>,
}

impl PaperStage {
    /// The stage computing `checks`, one row each, in order.
    pub fn new(checks: Vec<Check>) -> PaperStage {
        PaperStage { checks }
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for PaperStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::paper::STAGE, "study")
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.checks).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::paper::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let mut ids: Vec<InstanceId> = Vec::new();
        for id in self.checks.iter().flat_map(Check::inputs) {
            if !ids.contains(&id) {
                ids.push(id);
            }
        }
        ids
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::paper::*;
        let rows = self
            .checks
            .iter()
            .map(|check| check.row(inputs))
            .collect::<Result<Vec<_>, _>>()?;
        progress.advance(1);
        let table = Rows::new(&rows)
            .with(QUANTITY, |r| r.published.quantity.to_string())
            .with(SOURCE, |r| r.published.source.to_string())
            .with(TABLE_I_N, |r| {
                r.published
                    .table_i
                    .map_or(f64::NAN, |cell| f64::from(cell.n))
            })
            .with(TABLE_I_COLUMN, |r| {
                r.published
                    .table_i
                    .map_or(String::new(), |cell| cell.column.name().to_string())
            })
            .with(UNIT, |r| r.published.unit.to_string())
            .estimate(PUBLISHED, |r| Estimate {
                mean: r.published.value,
                stderr: r.published.uncertainty,
            })
            .estimate(OURS, |r| r.ours)
            .optional(RELATIVE_DIFFERENCE, |r| r.relative_difference())
            .with(Z, |r| r.z())
            .estimate(OURS_CONVERGED, |r| r.converged.estimate())
            .with(CONVERGED, |r| r.converged.state().to_string())
            .with(NOTE, |r| r.note.clone())
            .table(&TABLE)?;
        Ok(vec![table])
    }
}
