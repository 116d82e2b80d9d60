//! `table`: the study's summary, one row per potential: the thermalization
//! constant `a_n` (self variance rate at `u' = 0`, dilute limit, within the
//! kernel window) with its standard error, the untruncated value, the kernel shape `alpha, beta,
//! sigma` with standard errors, the relaxation gaps of the gas and of one
//! particle (rate units and over `Gamma`), and `|u1f,max|` of every scanned
//! launch pair with its error bound.

use serde_json::Value;

use crate::config::KernelParams;
use crate::contract::instances;
use crate::contract::readers::self_variance_at;
use crate::contract::{self, Col, Pair, Rows, table};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `table` stage.
pub struct TableStage {
    /// The `u' = 0`, dilute-limit moments parameters of every potential.
    rows: Vec<KernelParams>,
    /// The instances the study runs of the stages that supply columns
    /// (`contract::STUDY_COLUMNS`), one per potential they run for.
    suppliers: Vec<InstanceId>,
}

/// A quantity the study does not compute (null in the table).
const NOT_COMPUTED: Estimate = Estimate {
    mean: f64::NAN,
    stderr: f64::NAN,
};

impl TableStage {
    /// A table over these potentials, with the supplied columns of those
    /// whose supplying instance is listed in `suppliers`.
    pub fn new(rows: Vec<KernelParams>, suppliers: Vec<InstanceId>) -> TableStage {
        TableStage { rows, suppliers }
    }

    /// Every supplied column of `params`' potential, in
    /// `contract::STUDY_COLUMNS` order: NaN where the study does not run
    /// the supplying stage for it.
    fn supplied(
        &self,
        inputs: &[Input],
        params: &KernelParams,
    ) -> Result<Vec<Estimate>, StageError> {
        let potential = params.potential.id();
        let mut values = Vec::new();
        for column in contract::STUDY_COLUMNS.iter().copied().flatten() {
            let instance = InstanceId::new(column.source.stage, &potential);
            values.push(if self.suppliers.contains(&instance) {
                column.read(column.source.find(inputs, &instance)?)?
            } else {
                NOT_COMPUTED
            });
        }
        Ok(values)
    }
}

/// One potential's row.
struct PotentialRow {
    params: KernelParams,
    /// The self variance rate at `u' = 0`, dilute, untruncated.
    a_n: Estimate,
    /// Rate of encounters leaving a bound pair and a free atom.
    recombination: Estimate,
    /// `alpha`, `beta`, `sigma` of the fit.
    shape: [Estimate; 3],
    /// The columns other stages supply (NaN: not computed).
    supplied: Vec<Estimate>,
    /// Scanned launch pairs with their `|u1f,max|` and its error bound.
    maxima: Vec<(String, Estimate)>,
    events: u32,
    failed_events: u32,
}

impl TableStage {
    /// The row of the potential of `params` from its inputs.
    fn row(&self, inputs: &[Input], params: &KernelParams) -> Result<PotentialRow, StageError> {
        let moments = contract::moments::TABLE.find(inputs, &instances::moments(params))?;
        let fit = contract::fit::TABLE.find(inputs, &instances::fit(params))?;
        let peaks =
            contract::scan::peak::TABLE.find(inputs, &instances::scan(&params.potential))?;
        // The study's fit (the first row), its refit error and the spread
        // over the fit protocols combined.
        let first = |pair: Pair, systematic: Col<f64>| -> Result<Estimate, StageError> {
            let estimate = pair.read(fit)?[0];
            Ok(Estimate {
                mean: estimate.mean,
                stderr: libm::hypot(estimate.stderr, systematic.read(fit)?[0]),
            })
        };
        let launches = contract::scan::LAUNCH.read(peaks)?;
        let maxima = contract::scan::peak::U1_FINAL_MAX_ABS.read(peaks)?;
        Ok(PotentialRow {
            params: *params,
            a_n: self_variance_at(moments, f64::INFINITY)?,
            recombination: contract::moments::RECOMBINATION_RATE.read(moments)?[0],
            shape: [
                first(contract::fit::ALPHA, contract::fit::ALPHA_SYSTEMATIC)?,
                first(contract::fit::BETA, contract::fit::BETA_SYSTEMATIC)?,
                first(contract::fit::SIGMA, contract::fit::SIGMA_SYSTEMATIC)?,
            ],
            supplied: self.supplied(inputs, params)?,
            maxima: launches.into_iter().zip(maxima).collect(),
            events: contract::moments::EVENTS.read(moments)?[0],
            failed_events: contract::moments::FAILED_EVENTS.read(moments)?[0],
        })
    }
}

/// The supplied columns of every row, in `contract::STUDY_COLUMNS` order.
fn supplied_columns(rows: &[PotentialRow]) -> Vec<Column> {
    contract::STUDY_COLUMNS
        .iter()
        .copied()
        .flatten()
        .enumerate()
        .flat_map(|(k, column)| {
            let values: Vec<Estimate> = rows.iter().map(|r| r.supplied[k]).collect();
            column.column.columns(&values)
        })
        .collect()
}

/// The scan maxima's columns, one pair per launch pair of the first potential.
fn scan_maxima(rows: &[PotentialRow]) -> Result<Vec<Column>, StageError> {
    let launches: Vec<&String> = rows
        .first()
        .map(|r| r.maxima.iter().map(|(launch, _)| launch).collect())
        .unwrap_or_default();
    let mut columns = Vec::new();
    for (k, launch) in launches.into_iter().enumerate() {
        let maxima = rows
            .iter()
            .map(|r| match r.maxima.get(k) {
                Some((name, maximum)) if name == launch => Ok(*maximum),
                _ => Err(StageError::Input(format!(
                    "the potentials' scans differ in launch pair {launch}"
                ))),
            })
            .collect::<Result<Vec<Estimate>, StageError>>()?;
        columns.extend(table::scan_maximum(
            launch,
            maxima.iter().map(|e| e.mean).collect(),
            maxima.iter().map(|e| e.stderr).collect(),
        ));
    }
    Ok(columns)
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for TableStage {
    fn id(&self) -> InstanceId {
        instances::table()
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::json!({
            "rows": self.rows,
            "suppliers": self.suppliers.iter().map(ToString::to_string).collect::<Vec<_>>(),
        })
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::table::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.rows
            .iter()
            .flat_map(|params| {
                [
                    instances::moments(params),
                    instances::fit(params),
                    instances::scan(&params.potential),
                ]
            })
            .chain(self.suppliers.iter().cloned())
            .collect()
    }

    fn work_units(&self) -> u64 {
        self.rows.len() as u64
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::table::*;
        let rows = self
            .rows
            .iter()
            .map(|params| {
                let row = self.row(inputs, params)?;
                progress.advance(1);
                Ok(row)
            })
            .collect::<Result<Vec<_>, StageError>>()?;
        let table = Rows::new(&rows)
            .with(POTENTIAL, |r| r.params.potential.id())
            .with(N, |r| {
                r.params
                    .potential
                    .family()
                    .length_exponent()
                    .unwrap_or(f64::NAN)
            })
            .with(THETA, |r| {
                r.params.potential.family().theta().unwrap_or(f64::NAN)
            })
            .estimate(A_N, |r| r.a_n)
            .estimate(RECOMBINATION_RATE, |r| r.recombination)
            .estimate(ALPHA, |r| r.shape[0])
            .estimate(BETA, |r| r.shape[1])
            .estimate(SIGMA, |r| r.shape[2])
            .columns(supplied_columns(&rows))
            .columns(scan_maxima(&rows)?)
            .with(EVENTS, |r| r.events)
            .with(FAILED_EVENTS, |r| r.failed_events)
            .table(&TABLE)?;
        Ok(vec![table])
    }
}
