//! `gases`: thermalization rates of gases given in physical units (physics.md
//! §2): `Gamma = a_n rho^2 l v_th` in the dilute limit and with the literal
//! algorithm's finite-density factor at the gas's own `rho l`, with standard
//! errors, plus the scaled units of each gas. Gases that differ only in
//! temperature share every collision artifact (inverse power laws scale).

use serde_json::Value;

use super::moments::MomentsStage;
use crate::config::{GasParams, KernelParams};
use crate::pipeline::table::f64_values;
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

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

/// Self variance rate within half the window, with its error, from a moments table.
fn variance_rate(inputs: &[Input], params: &KernelParams) -> Result<(f64, f64), StageError> {
    let id = MomentsStage::instance(params);
    let table = inputs
        .iter()
        .find(|input| input.id == id)
        .and_then(|input| input.tables.get("moments"))
        .ok_or_else(|| StageError::Input(format!("missing {id}")))?;
    let truncation = f64_values(table, "truncation")?;
    let edge = 0.5 * params.window;
    let row = truncation
        .iter()
        .position(|&x| (x - edge).abs() <= 1e-12 * edge)
        .ok_or_else(|| StageError::Input(format!("{id} has no truncation at the window edge")))?;
    Ok((
        f64_values(table, "self_variance")?[row],
        f64_values(table, "self_variance_stderr")?[row],
    ))
}

impl Stage for GasesStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("gases", "study")
    }

    fn version(&self) -> u32 {
        2
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.gases.iter().map(|(gas, ..)| gas).collect::<Vec<_>>())
            .unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["gases"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let mut inputs: Vec<InstanceId> = Vec::new();
        for (_, dilute, dense) in &self.gases {
            for id in [
                MomentsStage::instance(dilute),
                MomentsStage::instance(dense),
            ] {
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
        let mut columns: [Vec<f64>; 14] = Default::default();
        for (params, dilute, dense) in &self.gases {
            let gas = &params.gas;
            let exponent = params.potential.length_exponent();
            let (a, a_err) = variance_rate(inputs, dilute)?;
            let (a_dense, a_dense_err) = variance_rate(inputs, dense)?;
            let rate = |x: f64| gas.rate_per_ns(x, exponent);
            let row = [
                gas.kt_ev,
                gas.density_per_um,
                gas.length_unit_um(exponent),
                gas.thermal_speed_um_per_ns(),
                gas.time_unit_ns(exponent),
                params.scaled_density(),
                a,
                a_err,
                rate(a),
                rate(a_err),
                rate(a_dense),
                rate(a_dense_err),
                1.0 / rate(a),
                rate(a_err) / rate(a).powi(2),
            ];
            for (column, value) in columns.iter_mut().zip(row) {
                column.push(value);
            }
            progress.advance(1);
        }
        let [
            kt,
            density,
            length,
            speed,
            time,
            rho_l,
            a,
            a_err,
            gamma,
            gamma_err,
            gamma_dense,
            gamma_dense_err,
            relaxation,
            relaxation_err,
        ] = columns;
        let table = Table::new(
            "gases",
            vec![
                Column::text("gas", "name of the gas", self.gases.iter().map(|(g, ..)| g.name.clone()).collect()),
                Column::text("potential", "potential id", self.gases.iter().map(|(g, ..)| g.potential.id()).collect()),
                Column::f64("kt", "eV", "temperature", kt),
                Column::f64("density", "1/um", "linear number density rho", density),
                Column::f64("length_unit", "um", "l = l0 (eps/kT)^(1/n)", length),
                Column::f64("thermal_speed", "um/ns", "v_th = sqrt(kT/m)", speed),
                Column::f64("time_unit", "ns", "l / v_th", time),
                Column::f64("rho_l", "1", "scaled density rho l (dilute when << 1)", rho_l),
                Column::f64("a_n", "rho^2 l v_th", "self variance rate at u' = 0, dilute limit", a),
                Column::f64("a_n_stderr", "rho^2 l v_th", "standard error", a_err),
                Column::f64("gamma", "1/ns", "Gamma = a_n rho^2 l v_th: initial growth rate of <(u - u')^2> (u in v_th) per ns, dilute limit", gamma),
                Column::f64("gamma_stderr", "1/ns", "standard error", gamma_err),
                Column::f64("gamma_at_density", "1/ns", "Gamma with the literal algorithm's exp(-r |delay|) at this rho l", gamma_dense),
                Column::f64("gamma_at_density_stderr", "1/ns", "standard error", gamma_dense_err),
                Column::f64("relaxation_time", "ns", "1 / Gamma (dilute)", relaxation),
                Column::f64("relaxation_time_stderr", "ns", "standard error", relaxation_err),
            ],
        )?
        .with_metadata("ternary.description", "thermalization rates of gases in physical units".into());
        Ok(vec![table])
    }
}
