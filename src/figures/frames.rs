//! Figure tables with polars: the input artifacts' tables as data frames,
//! their columns renamed into the long form of a figure (panel, series, `x`,
//! `y`, `y_error`), stacked and sorted, and read back for drawing.

use std::io::Cursor;

use arrow::array::RecordBatch;
use polars::prelude::{
    ChunkAgg, ChunkCompareIneq, Column, DataFrame, DataType, IntoColumn, NamedFrom, ParquetReader,
    SerReader, Series,
};

use crate::contract::figures::points::{PANEL, SERIES, X, Y, Y_ERROR};
use crate::contract::{Rows, TableSpec};
use crate::pipeline::{StageError, Table};

/// One plotted point of a figure table.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Panel.
    pub panel: String,
    /// Series.
    pub series: String,
    /// Horizontal coordinate.
    pub x: f64,
    /// Vertical coordinate.
    pub y: f64,
    /// Standard error of `y` (0 for lines without errors).
    pub y_error: f64,
}

impl Point {
    /// Points from their columns.
    fn rows(
        panels: Vec<String>,
        names: Vec<String>,
        xs: Vec<f64>,
        ys: Vec<f64>,
        errors: Vec<f64>,
    ) -> Vec<Point> {
        panels
            .into_iter()
            .zip(names)
            .zip(xs.into_iter().zip(ys).zip(errors))
            .map(|((panel, series), ((x, y), y_error))| Point {
                panel,
                series,
                x,
                y,
                y_error,
            })
            .collect()
    }
}

/// A polars failure while building a figure table.
pub(super) fn failed(error: impl std::fmt::Display) -> StageError {
    StageError::Input(format!("figure table: {error}"))
}

/// An input table as a polars data frame (through its Parquet encoding, which
/// both libraries read exactly).
pub fn frame(batch: &RecordBatch) -> Result<DataFrame, StageError> {
    let table = Table {
        name: "input".into(),
        batch: batch.clone(),
        metadata: Default::default(),
    };
    let bytes = table.to_parquet(&Default::default())?;
    ParquetReader::new(Cursor::new(bytes))
        .finish()
        .map_err(failed)
}

/// The long form of one series: `x`, `y` and `y_error` (0 without) from the
/// named columns of `frame`, tagged with its panel and series.
pub fn series(
    frame: &DataFrame,
    panel: &str,
    series: &str,
    (x, y, error): (&str, &str, Option<&str>),
) -> Result<DataFrame, StageError> {
    let rows = frame.height();
    let numbers = |name: &str| -> Result<Column, StageError> {
        Ok(frame.column(name).map_err(failed)?.clone())
    };
    let error = match error {
        Some(name) => numbers(name)?,
        None => Series::new(Y_ERROR.name.into(), vec![0.0; rows]).into_column(),
    };
    DataFrame::new(
        rows,
        vec![
            Series::new(PANEL.name.into(), vec![panel; rows]).into_column(),
            Series::new(SERIES.name.into(), vec![series; rows]).into_column(),
            numbers(x)?.with_name(X.name.into()),
            numbers(y)?.with_name(Y.name.into()),
            error.with_name(Y_ERROR.name.into()),
        ],
    )
    .map_err(failed)
}

/// The long form of one series from its values (`errors` `None`: 0).
pub fn series_of(
    panel: &str,
    name: &str,
    x: Vec<f64>,
    y: Vec<f64>,
    errors: Option<Vec<f64>>,
) -> Result<DataFrame, StageError> {
    let rows = x.len();
    let errors = errors.unwrap_or_else(|| vec![0.0; rows]);
    let values = DataFrame::new(
        rows,
        vec![
            Series::new(X.name.into(), x).into_column(),
            Series::new(Y.name.into(), y).into_column(),
            Series::new(Y_ERROR.name.into(), errors).into_column(),
        ],
    )
    .map_err(failed)?;
    series(&values, panel, name, (X.name, Y.name, Some(Y_ERROR.name)))
}

/// One series per value of the column `key` (ascending when every value is a
/// number, else in order of first appearance), each named by `label` of that
/// value (as text), from the same columns.
pub fn series_by(
    frame: &DataFrame,
    panel: &str,
    key: &str,
    label: impl Fn(&str) -> String,
    columns: (&str, &str, Option<&str>),
) -> Result<Vec<DataFrame>, StageError> {
    let parts = frame.partition_by_stable([key], true).map_err(failed)?;
    let mut valued = parts
        .iter()
        .map(|part| {
            let value = part
                .column(key)
                .map_err(failed)?
                .cast(&DataType::String)
                .map_err(failed)?;
            let value = value
                .str()
                .map_err(failed)?
                .get(0)
                .unwrap_or_default()
                .to_string();
            Ok((value, part))
        })
        .collect::<Result<Vec<_>, StageError>>()?;
    let number = |value: &str| value.parse::<f64>().ok();
    if valued.iter().all(|(value, _)| number(value).is_some()) {
        valued.sort_by(|(a, _), (b, _)| {
            number(a)
                .partial_cmp(&number(b))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
    }
    valued
        .into_iter()
        .map(|(value, part)| series(part, panel, &label(&value), columns))
        .collect()
}

/// Series stacked in the given order (the legend's).
pub fn stack(parts: Vec<DataFrame>) -> Result<DataFrame, StageError> {
    let mut parts = parts.into_iter();
    let mut all = parts.next().ok_or_else(|| failed("no series to draw"))?;
    for part in parts {
        all.vstack_mut(&part).map_err(failed)?;
    }
    Ok(all)
}

/// One series averaged over log-spaced groups of `x > 0` (`per_decade` per
/// decade, a stable polars partition by group): mean `x`, mean `y`, and the
/// error of the mean of independent bins, `sqrt(sum e^2) / count`. Fine bins
/// far out in a kernel's tail hold few events; the groups show the trend with
/// errors a reader can see.
pub fn log_groups(long: &DataFrame, per_decade: f64) -> Result<DataFrame, StageError> {
    let positive = long
        .column(X.name)
        .map_err(failed)?
        .f64()
        .map_err(failed)?
        .gt(0.0);
    let mut frame = long.filter(&positive).map_err(failed)?;
    let group: Vec<f64> = numbers(&frame, X.name)?
        .iter()
        .map(|x| (libm::log10(*x) * per_decade).floor())
        .collect();
    frame
        .with_column(Series::new(GROUP.into(), group).into_column())
        .map_err(failed)?;
    let (mut xs, mut ys, mut errors) = (Vec::new(), Vec::new(), Vec::new());
    let parts = frame.partition_by_stable([GROUP], true).map_err(failed)?;
    for part in &parts {
        let mean = |name: &str| -> Result<f64, StageError> {
            let column = part.column(name).map_err(failed)?.f64().map_err(failed)?;
            column.mean().ok_or_else(|| failed("empty group"))
        };
        xs.push(mean(X.name)?);
        ys.push(mean(Y.name)?);
        let squares: f64 = numbers(part, Y_ERROR.name)?.iter().map(|e| e * e).sum();
        errors.push(squares.sqrt() / part.height() as f64);
    }
    let first = |name: &str| -> Result<String, StageError> {
        let column = frame.column(name).map_err(failed)?.str().map_err(failed)?;
        Ok(column.get(0).unwrap_or_default().to_string())
    };
    let rows = xs.len();
    DataFrame::new(
        rows,
        vec![
            Series::new(PANEL.name.into(), vec![first(PANEL.name)?; rows]).into_column(),
            Series::new(SERIES.name.into(), vec![first(SERIES.name)?; rows]).into_column(),
            Series::new(X.name.into(), xs).into_column(),
            Series::new(Y.name.into(), ys).into_column(),
            Series::new(Y_ERROR.name.into(), errors).into_column(),
        ],
    )
    .map_err(failed)
}

/// Working column of [`log_groups`]: the group of a bin.
const GROUP: &str = "group";

/// A numeric column of `frame` as values (missing: NaN).
pub fn numbers(frame: &DataFrame, name: &str) -> Result<Vec<f64>, StageError> {
    let column = frame.column(name).map_err(failed)?.f64().map_err(failed)?;
    Ok(column.iter().map(|v| v.unwrap_or(f64::NAN)).collect())
}

/// The rows of a long figure frame.
pub fn points(frame: &DataFrame) -> Result<Vec<Point>, StageError> {
    let text = |name: &str| -> Result<Vec<String>, StageError> {
        let column = frame.column(name).map_err(failed)?.str().map_err(failed)?;
        Ok(column
            .iter()
            .map(|v| v.unwrap_or_default().to_string())
            .collect())
    };
    Ok(Point::rows(
        text(PANEL.name)?,
        text(SERIES.name)?,
        numbers(frame, X.name)?,
        numbers(frame, Y.name)?,
        numbers(frame, Y_ERROR.name)?,
    ))
}

/// The rows of a figure as its table `spec`.
pub struct FigureRows;

impl FigureRows {
    /// The figure table of `points`.
    pub fn table(points: &[Point], spec: &TableSpec) -> Result<Table, StageError> {
        Ok(Rows::new(points)
            .with(PANEL, |p| p.panel.clone())
            .with(SERIES, |p| p.series.clone())
            .with(X, |p| p.x)
            .with(Y, |p| p.y)
            .with(Y_ERROR, |p| p.y_error)
            .table(spec)?)
    }

    /// The points of a figure table.
    pub fn read(table: &Table) -> Result<Vec<Point>, StageError> {
        let batch = &table.batch;
        Ok(Point::rows(
            PANEL.read(batch)?,
            SERIES.read(batch)?,
            X.read(batch)?,
            Y.read(batch)?,
            Y_ERROR.read(batch)?,
        ))
    }
}
