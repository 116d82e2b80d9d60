//! Figure tables with polars: the input artifacts' tables as data frames,
//! their columns renamed into the long form of a figure (panel, series, `x`,
//! `y`, `y_error`), stacked and sorted, and read back for drawing.

use std::io::Cursor;

use arrow_array::RecordBatch;
use polars::prelude::{
    ChunkCompareEq, Column, DataFrame, DataType, IntoColumn, NamedFrom, ParquetReader, SerReader,
    Series,
};

use crate::contract::figures::points::{PANEL, SERIES, X, Y, Y_ERROR};
use crate::contract::{Rows, TableSpec};
use crate::kernel::tail;
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

/// A kernel's bins at `x > 0` averaged over log-spaced groups
/// ([`tail::log_groups`], `per_decade` per decade counted down from the
/// largest `x`), as the series `name` of `panel`: each group's mean `x`, its
/// mean kernel and that mean's standard error from the spread of the
/// randomizations' own group means ([`tail::group_mean`],
/// `replicates[randomization][bin]`).
pub fn log_groups(
    (panel, name): (&str, &str),
    x: &[f64],
    replicates: &[Vec<f64>],
    per_decade: f64,
) -> Result<DataFrame, StageError> {
    let (mut xs, mut ys, mut errors) = (Vec::new(), Vec::new(), Vec::new());
    for members in tail::log_groups(x, per_decade) {
        let mean = tail::group_mean(replicates, &members);
        xs.push(members.iter().map(|&k| x[k]).sum::<f64>() / members.len() as f64);
        ys.push(mean.mean);
        errors.push(mean.stderr);
    }
    series_of(panel, name, xs, ys, Some(errors))
}

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
    /// The figure table of `points`, described as `description`.
    pub fn table(
        points: &[Point],
        spec: &TableSpec,
        description: &str,
    ) -> Result<Table, StageError> {
        Ok(Rows::new(points)
            .with(PANEL, |p| p.panel.clone())
            .with(SERIES, |p| p.series.clone())
            .with(X, |p| p.x)
            .with(Y, |p| p.y)
            .with(Y_ERROR, |p| p.y_error)
            .described(spec, description)?)
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

/// The rows of `all` whose text column `key` equals `value`.
pub(super) fn rows_where(all: &DataFrame, key: &str, value: &str) -> Result<DataFrame, StageError> {
    let mask = all
        .column(key)
        .map_err(failed)?
        .str()
        .map_err(failed)?
        .equal(value);
    all.filter(&mask).map_err(failed)
}

/// The standard normal density at `xs`, a series `name` of `panel` without errors.
pub(super) fn standard_normal(
    panel: &str,
    name: &str,
    xs: Vec<f64>,
) -> Result<DataFrame, StageError> {
    let density = xs
        .iter()
        .map(|x| libm::exp(-0.5 * x * x) / libm::sqrt(2.0 * std::f64::consts::PI))
        .collect();
    series_of(panel, name, xs, density, None)
}
