//! `gases`: thermalization rates of gases given in physical units (physics.md
//! §2): `Gamma = a_n rho^2 l v_th` in the dilute limit and with the literal
//! algorithm's finite-density factor at the gas's own `rho l`, with standard
//! errors, plus the scaled units of each gas. Gases that differ only in
//! temperature share every collision artifact (inverse power laws scale).

use serde_json::Value;

use crate::config::{GasParams, KernelParams};
use crate::contract::instances;
use crate::contract::readers::self_variance_at;
use crate::contract::{self, Rows};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `gases` stage.
pub struct GasesStage {
    /// Each gas with its dilute and finite-density moments parameters.
    gases: Vec<(GasParams, KernelParams, KernelParams)>,
}

impl GasesStage {
    /// A table over these gases: `(gas, dilute moments, moments at the gas's density)`.
    pub fn new(gases: Vec<(GasParams, KernelParams, KernelParams)>) -> GasesStage {
        GasesStage { gases }
    }
}

/// `a_n` of `params` (the self variance rate, untruncated: where it has
/// converged) from its moments table.
fn variance_rate(inputs: &[Input], params: &KernelParams) -> Result<Estimate, StageError> {
    let table = contract::moments::TABLE.find(inputs, &instances::moments(params))?;
    self_variance_at(table, f64::INFINITY)
}

/// One gas's rates.
struct GasRates<'a> {
    params: &'a GasParams,
    dilute: Estimate,
    dense: Estimate,
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for GasesStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::gases::STAGE, "study")
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.gases.iter().map(|(gas, ..)| gas).collect::<Vec<_>>())
            .unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::gases::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let mut inputs: Vec<InstanceId> = Vec::new();
        for (_, dilute, dense) in &self.gases {
            for id in [instances::moments(dilute), instances::moments(dense)] {
                if !inputs.contains(&id) {
                    inputs.push(id);
                }
            }
        }
        inputs
    }

    fn work_units(&self) -> u64 {
        self.gases.len() as u64
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::gases::*;
        let rows = self
            .gases
            .iter()
            .map(|(params, dilute, dense)| {
                let rates = GasRates {
                    params,
                    dilute: variance_rate(inputs, dilute)?,
                    dense: variance_rate(inputs, dense)?,
                };
                progress.advance(1);
                Ok(rates)
            })
            .collect::<Result<Vec<_>, StageError>>()?;
        let exponent = |r: &GasRates| r.params.potential.family().length_exponent();
        let rate = |r: &GasRates, x: f64| r.params.gas.rate_per_ns(x, exponent(r));
        let gamma = |r: &GasRates, a: Estimate| Estimate {
            mean: rate(r, a.mean),
            stderr: rate(r, a.stderr),
        };
        let table = Rows::new(&rows)
            .with(GAS, |r| r.params.name.clone())
            .with(POTENTIAL, |r| r.params.potential.id())
            .with(KT, |r| r.params.gas.kt_ev)
            .with(DENSITY, |r| r.params.gas.density_per_um)
            .with(LENGTH_UNIT, |r| r.params.gas.length_unit_um(exponent(r)))
            .with(THERMAL_SPEED, |r| r.params.gas.thermal_speed_um_per_ns())
            .with(TIME_UNIT, |r| r.params.gas.time_unit_ns(exponent(r)))
            .with(RHO_L, |r| r.params.scaled_density())
            .estimate(A_N, |r| r.dilute)
            .estimate(GAMMA, |r| gamma(r, r.dilute))
            .estimate(GAMMA_AT_DENSITY, |r| gamma(r, r.dense))
            .estimate(RELAXATION_TIME, |r| {
                let Estimate { mean, stderr } = gamma(r, r.dilute);
                // Without kicks (Gamma = 0) there is no relaxation time: null.
                let defined = |value: f64| if mean == 0.0 { f64::NAN } else { value };
                Estimate {
                    mean: defined(1.0 / mean),
                    stderr: defined(stderr / mean.powi(2)),
                }
            })
            .table(&TABLE)?;
        Ok(vec![table])
    }
}
