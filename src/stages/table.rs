//! `table`: the study's summary, one row per potential: the thermalization
//! constant `a_n` (self variance rate at `u' = 0`, dilute limit, within the
//! kernel window) with its standard error, the untruncated value, the kernel shape `alpha, beta,
//! sigma` with standard errors, and `|u1f,max|` of every scanned launch pair
//! with its error bound.

use serde_json::Value;

use super::fit::FitStage;
use super::moments::MomentsStage;
use crate::config::KernelParams;
use crate::physics::potential::Potential;
use crate::pipeline::table::{f64_values, text_values, u32_values};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

/// The `table` stage.
pub struct TableStage {
    /// The `u' = 0`, dilute-limit moments parameters of every potential.
    rows: Vec<KernelParams>,
}

impl TableStage {
    /// A table over these potentials.
    pub fn new(rows: Vec<KernelParams>) -> TableStage {
        TableStage { rows }
    }
}

fn scan_instance(potential: &Potential) -> InstanceId {
    InstanceId::new("scan", &potential.id())
}

/// One value with its error from a moments table at the truncation `limit`.
fn moment_at(
    batch: &arrow::array::RecordBatch,
    name: &str,
    limit: f64,
) -> Result<(f64, f64), StageError> {
    let truncation = f64_values(batch, "truncation")?;
    let row = truncation
        .iter()
        .position(|&x| x == limit || (limit.is_finite() && (x - limit).abs() <= 1e-12 * limit))
        .ok_or_else(|| StageError::Input(format!("no truncation {limit} in moments")))?;
    Ok((
        f64_values(batch, name)?[row],
        f64_values(batch, &format!("{name}_stderr"))?[row],
    ))
}

fn input<'a>(
    inputs: &'a [Input],
    id: &InstanceId,
    table: &str,
) -> Result<&'a arrow::array::RecordBatch, StageError> {
    inputs
        .iter()
        .find(|input| &input.id == id)
        .and_then(|input| input.tables.get(table))
        .ok_or_else(|| StageError::Input(format!("missing {id} table {table}")))
}

impl Stage for TableStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("table", "study")
    }

    fn version(&self) -> u32 {
        3
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.rows).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["table"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.rows
            .iter()
            .flat_map(|params| {
                [
                    MomentsStage::instance(params),
                    FitStage::instance(params),
                    scan_instance(&params.potential),
                ]
            })
            .collect()
    }

    fn work_units(&self) -> u64 {
        self.rows.len() as u64
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let mut numbers: Vec<(String, &str, &str, Vec<f64>)> = Vec::new();
        let mut push =
            |name: &str, unit: &'static str, description: &'static str, value: f64| match numbers
                .iter_mut()
                .find(|(n, ..)| n == name)
            {
                Some((.., values)) => values.push(value),
                None => numbers.push((name.to_string(), unit, description, vec![value])),
            };
        let mut counts: [Vec<u32>; 2] = Default::default();
        for params in &self.rows {
            let moments = input(inputs, &MomentsStage::instance(params), "moments")?;
            let edge = 0.5 * params.window;
            let (a, a_err) = moment_at(moments, "self_variance", edge)?;
            let (a_all, a_all_err) = moment_at(moments, "self_variance", f64::INFINITY)?;
            let (exponent, theta) = match params.potential {
                Potential::InversePower { n } => (n, f64::NAN),
                Potential::LennardJones { theta } => (6.0, theta),
            };
            push(
                "n",
                "1",
                "exponent of the inverse power law (6 for Lennard-Jones: sets the length unit)",
                exponent,
            );
            push(
                "theta",
                "1",
                "kT/eps of Lennard-Jones (NaN for inverse power laws)",
                theta,
            );
            push(
                "a_n",
                "rho^2 l v_th",
                "self variance rate at u' = 0, dilute limit, |u - u'| <= window/2",
                a,
            );
            push(
                "a_n_stderr",
                "rho^2 l v_th",
                "standard error of a_n (spread of randomizations)",
                a_err,
            );
            push(
                "a_n_untruncated",
                "rho^2 l v_th",
                "self variance rate without truncation",
                a_all,
            );
            push(
                "a_n_untruncated_stderr",
                "rho^2 l v_th",
                "standard error of a_n_untruncated",
                a_all_err,
            );
            let fit = input(inputs, &FitStage::instance(params), "fit")?;
            for (name, description) in [
                (
                    "alpha",
                    "amplitude of the kernel shape fit alpha |x|^-beta exp(-x^2/2 sigma^2) at u' = 0",
                ),
                ("beta", "power-law exponent of the kernel near u'"),
                (
                    "sigma",
                    "Gaussian cut-off of the kernel (largest momentum transfer), v_th",
                ),
            ] {
                push(
                    name,
                    "see fit stage",
                    description,
                    f64_values(fit, name)?[0],
                );
                push(
                    &format!("{name}_stderr"),
                    "see fit stage",
                    "standard error from refitting each randomization",
                    f64_values(fit, &format!("{name}_stderr"))?[0],
                );
            }
            counts[0].push(u32_values(moments, "events")?[0]);
            counts[1].push(u32_values(moments, "failed_events")?[0]);
            let peaks = input(inputs, &scan_instance(&params.potential), "peak")?;
            let launches = text_values(peaks, "launch")?;
            let kicks = f64_values(peaks, "u1_final_max_abs")?;
            let errors = f64_values(peaks, "u1_final_max_abs_error")?;
            for (k, launch) in launches.iter().enumerate() {
                push(
                    &format!("u1f_max_{launch}"),
                    "v_th",
                    "largest |u1f| of the mono-energetic scan of this launch pair",
                    kicks[k],
                );
                push(
                    &format!("u1f_max_{launch}_error"),
                    "v_th",
                    "error bound of the scan maximum",
                    errors[k],
                );
            }
            progress.advance(1);
        }
        let mut columns = vec![Column::text(
            "potential",
            "potential id",
            self.rows.iter().map(|p| p.potential.id()).collect(),
        )];
        columns.extend(
            numbers
                .into_iter()
                .map(|(name, unit, description, values)| {
                    Column::f64(&name, unit, description, values)
                }),
        );
        let [events, failed] = counts;
        columns.push(Column::u32(
            "events",
            "1",
            "scenes drawn for the kernel",
            events,
        ));
        columns.push(Column::u32(
            "failed_events",
            "1",
            "scenes that failed",
            failed,
        ));
        let table = Table::new("table", columns)?.with_metadata(
            "ternary.description",
            "thermalization constants a_n and scan maxima per potential".into(),
        );
        Ok(vec![table])
    }
}
