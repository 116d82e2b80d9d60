//! What the command line prints: the run summary, the DAG, verification and
//! garbage-collection reports, artifact listings and a gas's rates. Reads artifacts with
//! polars, as any user would, by the columns the stages declare
//! (`contract`). Numbers are printed to the digits their errors justify
//! ([`with_error`]); a number that does not exist says why.

mod dag;
mod folder;
pub mod html;
mod kernel_model;
mod layout;
mod numbers;
mod pairs;
mod printout;
mod rates;
mod show;
mod status;
mod store;
mod summary;

pub use dag::{DagFormat, dag};
pub use kernel_model::{Asked, Interpolation, Node, interpolated_kernel_text, kernel_model_text};
pub use numbers::with_error;
pub use pairs::{PairPrediction, pairs_text};
pub use rates::{SourcedTable, rate_text, theta_table};
pub use show::show;
pub use status::{cost_estimate, costs_by_stage, describe, hours, size, status, total_cost};
pub use store::{audit, gc, verify};
pub use summary::summary;

use std::fs::File;
use std::path::Path;

use anyhow::{Context, Result};
use polars::prelude::{DataFrame, ParquetReader, SerReader};

use crate::contract::{Col, Pair, TableSpec};
use crate::pipeline::executor::InstanceReport;
use crate::pipeline::store::Store;
use crate::stats::Estimate;
use layout::Cell;

/// Cell `col` of `row` as a number (NaN when null).
fn number(frame: &DataFrame, row: usize, col: Col<f64>) -> Result<f64> {
    Ok(frame.column(col.name)?.f64()?.get(row).unwrap_or(f64::NAN))
}

/// Cells `pair` of `row` as a value and its error (NaN where null).
fn pair_of(frame: &DataFrame, row: usize, pair: Pair) -> Result<Estimate> {
    Ok(Estimate {
        mean: number(frame, row, pair.value)?,
        stderr: number(frame, row, pair.stderr)?,
    })
}

/// Cells `pair` of `row` as a `value ± error` cell (`undefined` when the
/// value is not a number).
fn estimate(frame: &DataFrame, row: usize, pair: Pair, undefined: &str) -> Result<Cell> {
    let Estimate { mean, stderr } = pair_of(frame, row, pair)?;
    Ok(Cell::estimate(mean, stderr, undefined))
}

/// Cells `pair` of `row`, a variance of velocities `[v_th^2]`: one whose
/// value and error are both below the square of the study's kick floor
/// (`kick_floor`, `v_th`: by default 1000x the engine's velocity error) is
/// the integrator's rounding, not a spread (the integrable n = 2 ring
/// printed `(3.83 ± 0.72)e-23`), and says so.
fn variance(frame: &DataFrame, row: usize, pair: Pair, kick_floor: f64) -> Result<Cell> {
    let floor = kick_floor.powi(2);
    let Estimate {
        mean: value,
        stderr: error,
    } = pair_of(frame, row, pair)?;
    Ok(if value != 0.0 && value.abs() + error < floor {
        Cell::text(format!("< {floor:e} (engine floor)"))
    } else {
        Cell::estimate(value, error, "-")
    })
}

/// Cell `col` of `row` as a count (0 when null).
fn count(frame: &DataFrame, row: usize, col: Col<u32>) -> Result<u32> {
    Ok(frame.column(col.name)?.u32()?.get(row).unwrap_or(0))
}

/// Cell `col` of `row` as text (empty when null).
fn text(frame: &DataFrame, row: usize, col: Col<String>) -> Result<String> {
    Ok(frame
        .column(col.name)?
        .str()?
        .get(row)
        .unwrap_or_default()
        .to_string())
}

fn read_frame(path: &Path) -> Result<DataFrame> {
    let file = File::open(path).with_context(|| format!("opening {}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .with_context(|| format!("reading {}", path.display()))
}

/// One table of each instance that has it: the instance and its frame.
type InstanceFrames = Vec<(String, DataFrame)>;

/// The table `spec` of every intact artifact of its stage in a run.
fn table_frames(
    store: &Store,
    reports: &[InstanceReport],
    spec: &TableSpec,
) -> Result<InstanceFrames> {
    reports
        .iter()
        .filter(|r| r.id.stage == spec.stage)
        .filter(|r| r.action.has_artifact())
        .filter_map(|r| r.key.as_ref().map(|key| (r, key)))
        .map(|(report, key)| {
            let frame = read_frame(
                &store
                    .artifact_dir(spec.stage, key)
                    .join(format!("{}.parquet", spec.name)),
            )?;
            Ok((report.id.instance.clone(), frame))
        })
        .collect()
}
