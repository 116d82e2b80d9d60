//! Figure tables with polars: the input artifacts' tables as data frames,
//! their columns renamed into the long form of a figure (panel, series, `x`,
//! `y`, `y_error`), stacked and sorted, and read back for drawing.

use std::collections::BTreeMap;
use std::io::Cursor;

use arrow::array::RecordBatch;
use polars::prelude::{
    Column, DataFrame, DataType, IntoColumn, NamedFrom, ParquetReader, SerReader, Series,
};

use crate::contract::figures::points::{PANEL, SERIES, X, Y, Y_ERROR};
use crate::contract::{Rows, TableSpec};
use crate::pipeline::{StageError, Table};
use crate::stats::Estimate;

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

/// A kernel's bins at `x > 0` averaged over log-spaced groups, `per_decade`
/// per decade counted down from the largest `x` (bin `k` joins group
/// `ceil(per_decade log10(x_k / x_max))`, so the outermost group is as wide
/// as the others rather than a lone bin on a decade's boundary), as the
/// series `name` of `panel`: each group's mean `x`, its mean kernel and that
/// mean's standard error from the spread of the randomizations' own group
/// means (`replicates[randomization][bin]`). Neighbouring bins share scenes
/// (one slow launch feeds many), so their errors do not add like those of
/// independent bins. Fine bins far out in a kernel's tail hold few events;
/// the groups show the trend with errors a reader can trust.
pub fn log_groups(
    (panel, name): (&str, &str),
    x: &[f64],
    replicates: &[Vec<f64>],
    per_decade: f64,
) -> Result<DataFrame, StageError> {
    let largest = x.iter().copied().fold(0.0, f64::max);
    let mut groups: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
    for (k, &x_k) in x.iter().enumerate().filter(|(_, x_k)| **x_k > 0.0) {
        let group = (per_decade * libm::log10(x_k / largest)).ceil() as i64;
        groups.entry(group).or_default().push(k);
    }
    let (mut xs, mut ys, mut errors) = (Vec::new(), Vec::new(), Vec::new());
    for members in groups.values() {
        let count = members.len() as f64;
        let means: Vec<f64> = replicates
            .iter()
            .map(|kernel| members.iter().map(|&k| kernel[k]).sum::<f64>() / count)
            .collect();
        let mean = Estimate::from_replicates(&means);
        xs.push(members.iter().map(|&k| x[k]).sum::<f64>() / count);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Bin centres of a kernel window's positive side: `k w`, `k = 1..=500`,
    /// `w = 2e-4`, up to the edge at 0.1.
    fn window() -> Vec<f64> {
        (1..=500).map(|k| f64::from(k) * 2e-4).collect()
    }

    /// The outermost group spans the top 1/20 of a decade, `(0.1 10^(-1/20),
    /// 0.1]`, like every other group. Before, groups were cut at multiples of
    /// 1/20 decade from 1, so the bin at 0.1 (on a boundary) was a group of
    /// its own: one bin's noise drawn as the kernel's end.
    #[test]
    fn the_outermost_group_is_as_wide_as_the_rest() {
        let x = window();
        let replicates = vec![vec![1.0; x.len()]; 2];
        let groups = log_groups(("kernels", "G"), &x, &replicates, 20.0).unwrap();
        let lower = 0.1 * libm::pow(10.0, -1.0 / 20.0);
        let top: Vec<f64> = x.iter().copied().filter(|&v| v > lower).collect();
        let mean = top.iter().sum::<f64>() / top.len() as f64;
        let centres = numbers(&groups, X.name).unwrap();
        assert!(top.len() > 50, "{}", top.len());
        assert!(
            (centres[centres.len() - 1] - mean).abs() < 1e-12,
            "{centres:?}"
        );
    }

    /// Bins that move together over the randomizations (one slow launch
    /// feeds them all): the error of a group's mean is the spread of the
    /// randomizations' group means, `s / sqrt(R)` of the common shifts,
    /// whatever the number of bins; independent bins' errors added in
    /// quadrature would give `sqrt(n)` times less.
    #[test]
    fn a_group_of_correlated_bins_has_the_error_of_its_randomizations() {
        let x = window();
        let shifts = [0.3, -0.1, -0.4, 0.2, 0.0, 0.5, -0.3, -0.2];
        let replicates: Vec<Vec<f64>> = shifts.iter().map(|c| vec![1.0 + c; x.len()]).collect();
        let count = shifts.len() as f64;
        let mean = shifts.iter().sum::<f64>() / count;
        let variance = shifts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (count - 1.0);
        let expected = (variance / count).sqrt();
        let groups = log_groups(("kernels", "G"), &x, &replicates, 20.0).unwrap();
        let (values, errors) = (
            numbers(&groups, Y.name).unwrap(),
            numbers(&groups, Y_ERROR.name).unwrap(),
        );
        assert!(errors.len() > 10);
        for (value, error) in values.iter().zip(errors) {
            assert!((value - (1.0 + mean)).abs() < 1e-12, "{value}");
            assert!(
                (error / expected - 1.0).abs() < 1e-12,
                "{error} vs {expected}"
            );
        }
    }
}
