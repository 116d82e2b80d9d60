//! Table contracts: every output table's name, description and columns
//! (name, type, unit, description) are declared once, in [`tables`], and
//! used by the stage that writes the table, by every stage that reads it and
//! by the report. A column's Rust type is part of its declaration
//! ([`Col<f64>`], [`Col<u32>`], [`Col<String>`]), so a reader cannot ask for
//! the wrong type; a value and its standard error are one [`Pair`], written
//! from and read back as [`Estimate`]s. Columns are bound to row fields by
//! name ([`Rows`]), never by position.
//!
//! Builds on the pipeline's `Column` and `Table` from the stage side; owns no
//! computation and no file layout beyond the names.

use std::marker::PhantomData;

use arrow_array::{Float64Array, RecordBatch};

use crate::pipeline::table::{TableError, column, f64_values, text_values, u32_values};
use crate::pipeline::{Column, Input, InstanceId, StageError, Table};
use crate::stats::Estimate;

/// A value and its standard error: columns `name` (`unit`, `description`)
/// and `name_stderr` (same unit, `stderr` as its description).
macro_rules! pair {
    ($name:literal, $unit:expr, $description:expr, $stderr:expr) => {
        $crate::contract::Pair {
            value: $crate::contract::Col::f64($name, $unit, $description),
            stderr: $crate::contract::Col::f64(concat!($name, "_stderr"), $unit, $stderr),
        }
    };
}

/// A value and its error bound: columns `name` and `name_error`.
macro_rules! bounded {
    ($name:literal, $unit:expr, $description:expr, $error:expr) => {
        $crate::contract::Pair {
            value: $crate::contract::Col::f64($name, $unit, $description),
            stderr: $crate::contract::Col::f64(concat!($name, "_error"), $unit, $error),
        }
    };
}

pub mod instances;
pub mod printout;
pub mod readers;
pub mod study_column;
pub mod tables;

pub use tables::*;

/// A column type: how values of it are written and read.
pub trait Value: Sized {
    /// The column `col` holding `values`.
    fn column(col: &Col<Self>, values: Vec<Self>) -> Column;
    /// Column `name` of `batch`.
    fn read(batch: &RecordBatch, name: &str) -> Result<Vec<Self>, TableError>;
}

impl Value for f64 {
    /// A NaN (a value that is missing or undefined) is written as a null.
    fn column(col: &Col<f64>, values: Vec<f64>) -> Column {
        Column::f64(col.name, col.unit, col.description, col.null, values)
    }

    fn read(batch: &RecordBatch, name: &str) -> Result<Vec<f64>, TableError> {
        f64_values(batch, name)
    }
}

impl Value for u32 {
    fn column(col: &Col<u32>, values: Vec<u32>) -> Column {
        Column::u32(col.name, col.unit, col.description, values)
    }

    fn read(batch: &RecordBatch, name: &str) -> Result<Vec<u32>, TableError> {
        u32_values(batch, name)
    }
}

impl Value for String {
    fn column(col: &Col<String>, values: Vec<String>) -> Column {
        Column::text(col.name, col.description, values)
    }

    fn read(batch: &RecordBatch, name: &str) -> Result<Vec<String>, TableError> {
        text_values(batch, name)
    }
}

/// The unit of a column whose unit differs from row to row (the `paper`
/// table's values): each row's unit is in its text column `unit`. A unit
/// that starts with `per ` is never a unit but says where the units are.
pub const UNIT_PER_ROW: &str = "per row: see column `unit`";

/// The unit of a figure coordinate (`x`, `y`, `y_error` of `points.parquet`):
/// the panel's axis unit, in the file's `ternary.axes` metadata.
pub const UNIT_PER_PANEL: &str = "per panel: see the axes in the `ternary.axes` metadata";

/// One declared column holding values of type `T`.
#[derive(Debug)]
pub struct Col<T> {
    /// Column name.
    pub name: &'static str,
    /// Unit (`1` dimensionless, empty for labels, [`UNIT_PER_ROW`] or
    /// [`UNIT_PER_PANEL`] where it varies).
    pub unit: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// What a null in this column means; `None` for a column that never
    /// holds one (the only nullable columns are `float64` ones declared with
    /// [`Col::or_null`]).
    pub null: Option<&'static str>,
    kind: PhantomData<fn() -> T>,
}

impl<T> Clone for Col<T> {
    fn clone(&self) -> Col<T> {
        *self
    }
}

impl<T> Copy for Col<T> {}

impl Col<f64> {
    /// A `float64` column without nulls.
    pub const fn f64(name: &'static str, unit: &'static str, description: &'static str) -> Self {
        Col {
            name,
            unit,
            description,
            null: None,
            kind: PhantomData,
        }
    }

    /// The column, nullable: a null means `meaning` (a value that is missing
    /// or undefined, e.g. `no fit converged`).
    pub const fn or_null(self, meaning: &'static str) -> Self {
        Col {
            null: Some(meaning),
            ..self
        }
    }

    /// The column with these values (`None` written as a null).
    pub fn optional_column(&self, values: impl IntoIterator<Item = Option<f64>>) -> Column {
        Column::optional_f64(
            self.name,
            self.unit,
            self.description,
            self.null,
            values.into_iter().collect(),
        )
    }

    /// This column of `batch`, nulls as `None`.
    pub fn optional(&self, batch: &RecordBatch) -> Result<Vec<Option<f64>>, TableError> {
        Ok(column::<Float64Array>(batch, self.name)?.iter().collect())
    }
}

impl Col<u32> {
    /// A `uint32` column (counts).
    pub const fn u32(name: &'static str, unit: &'static str, description: &'static str) -> Self {
        Col {
            name,
            unit,
            description,
            null: None,
            kind: PhantomData,
        }
    }
}

impl Col<String> {
    /// A `utf8` column (labels), without a unit.
    pub const fn text(name: &'static str, description: &'static str) -> Self {
        Col {
            name,
            unit: "",
            description,
            null: None,
            kind: PhantomData,
        }
    }

    /// The row of `batch` whose label in this column is `label` (the first).
    pub fn row_of(&self, batch: &RecordBatch, label: &str) -> Result<usize, StageError> {
        self.read(batch)?
            .iter()
            .position(|l| l == label)
            .ok_or_else(|| StageError::Input(format!("no {} `{label}`", self.name)))
    }
}

impl<T: Value> Col<T> {
    /// The column with these values.
    pub fn column(&self, values: Vec<T>) -> Column {
        T::column(self, values)
    }

    /// This column of `batch`.
    pub fn read(&self, batch: &RecordBatch) -> Result<Vec<T>, TableError> {
        T::read(batch, self.name)
    }
}

/// A value column and its error column.
#[derive(Clone, Copy, Debug)]
pub struct Pair {
    /// The value.
    pub value: Col<f64>,
    /// Its standard error (or error bound).
    pub stderr: Col<f64>,
}

impl Pair {
    /// The pair, both columns nullable: a null means `meaning`.
    pub const fn or_null(self, meaning: &'static str) -> Pair {
        Pair {
            value: self.value.or_null(meaning),
            stderr: self.stderr.or_null(meaning),
        }
    }

    /// The two columns of `estimates`.
    pub fn columns(&self, estimates: &[Estimate]) -> [Column; 2] {
        [
            self.value
                .column(estimates.iter().map(|e| e.mean).collect()),
            self.stderr
                .column(estimates.iter().map(|e| e.stderr).collect()),
        ]
    }

    /// Both columns of `batch`, row by row.
    pub fn read(&self, batch: &RecordBatch) -> Result<Vec<Estimate>, TableError> {
        Ok(self
            .value
            .read(batch)?
            .into_iter()
            .zip(self.stderr.read(batch)?)
            .map(|(mean, stderr)| Estimate { mean, stderr })
            .collect())
    }
}

/// A declared table: the stage that writes it, its file stem and description.
#[derive(Clone, Copy, Debug)]
pub struct TableSpec {
    /// The stage writing it.
    pub stage: &'static str,
    /// File stem: the table is `<name>.parquet`.
    pub name: &'static str,
    /// What it holds (the file's `ternary.description`).
    pub description: &'static str,
}

impl TableSpec {
    /// The table of these columns, with its description.
    pub fn table(&self, columns: Vec<Column>) -> Result<Table, TableError> {
        self.described(columns, self.description)
    }

    /// The table of these columns with a description composed at run time
    /// (a figure's, which names what it draws).
    pub fn described(&self, columns: Vec<Column>, description: &str) -> Result<Table, TableError> {
        Ok(
            Table::new(self.name, columns)?
                .with_metadata("ternary.description", description.into()),
        )
    }

    /// This table of `input`.
    pub fn of<'a>(&self, input: &'a Input) -> Result<&'a RecordBatch, StageError> {
        input.tables.get(self.name).ok_or_else(|| {
            StageError::Invariant(format!("{} has no {} table", input.id, self.name))
        })
    }

    /// This table of the input `id` among `inputs`.
    pub fn find<'a>(
        &self,
        inputs: &'a [Input],
        id: &InstanceId,
    ) -> Result<&'a RecordBatch, StageError> {
        let input = inputs
            .iter()
            .find(|input| &input.id == id)
            .ok_or_else(|| StageError::Invariant(format!("missing input {id}")))?;
        self.of(input)
    }
}

/// The columns of a table with one row per element of `rows`, each column
/// bound to its contract by name and filled by an accessor.
pub struct Rows<'r, R> {
    rows: &'r [R],
    columns: Vec<Column>,
}

impl<'r, R> Rows<'r, R> {
    /// No columns yet.
    pub fn new(rows: &'r [R]) -> Rows<'r, R> {
        Rows {
            rows,
            columns: Vec::new(),
        }
    }

    /// Adds the column `col` with `value` of every row.
    pub fn with<T: Value>(mut self, col: Col<T>, value: impl Fn(&R) -> T) -> Rows<'r, R> {
        self.columns
            .push(col.column(self.rows.iter().map(value).collect()));
        self
    }

    /// Adds the nullable column `col` with `value` of every row (`None`
    /// written as a null).
    pub fn optional(mut self, col: Col<f64>, value: impl Fn(&R) -> Option<f64>) -> Rows<'r, R> {
        self.columns
            .push(col.optional_column(self.rows.iter().map(value)));
        self
    }

    /// Adds the value and error columns of `pair` from the estimate of every row.
    pub fn estimate(mut self, pair: Pair, value: impl Fn(&R) -> Estimate) -> Rows<'r, R> {
        let estimates: Vec<Estimate> = self.rows.iter().map(value).collect();
        self.columns.extend(pair.columns(&estimates));
        self
    }

    /// Adds columns built elsewhere (names made at run time).
    pub fn columns(mut self, columns: impl IntoIterator<Item = Column>) -> Rows<'r, R> {
        self.columns.extend(columns);
        self
    }

    /// The table `spec` of these columns.
    pub fn table(self, spec: &TableSpec) -> Result<Table, TableError> {
        spec.table(self.columns)
    }

    /// The table of these rows with a description composed at run time.
    pub fn described(self, spec: &TableSpec, description: &str) -> Result<Table, TableError> {
        spec.described(self.columns, description)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: TableSpec = TableSpec {
        stage: "tests",
        name: "example",
        description: "a table of the tests",
    };
    const LABEL: Col<String> = Col::text("label", "which row");
    const COUNT: Col<u32> = Col::u32("count", "1", "how many");
    const RATE: Pair = pair!("rate", "1/s", "a rate", "its standard error");
    const BOUND: Col<f64> = Col::f64("bound", "1/s", "an upper bound").or_null("no bound");

    /// A table written from rows reads back the same values under the
    /// declared names, the pair as `rate` and `rate_stderr`.
    #[test]
    fn rows_written_by_contract_read_back_by_contract() {
        let rows = [("first", 3, 1.5, 0.25), ("second", 4, -2.0, 0.5)];
        let table = Rows::new(&rows)
            .with(LABEL, |r| r.0.to_string())
            .with(COUNT, |r| r.1)
            .estimate(RATE, |r| Estimate {
                mean: r.2,
                stderr: r.3,
            })
            .table(&SPEC)
            .unwrap();
        assert_eq!(table.name, "example");
        let batch = &table.batch;
        let names: Vec<String> = batch
            .schema()
            .fields()
            .iter()
            .map(|f| f.name().clone())
            .collect();
        assert_eq!(names, ["label", "count", "rate", "rate_stderr"]);
        assert_eq!(COUNT.read(batch).unwrap(), vec![3, 4]);
        assert_eq!(LABEL.row_of(batch, "second").unwrap(), 1);
        let rates = RATE.read(batch).unwrap();
        assert_eq!((rates[1].mean, rates[1].stderr), (-2.0, 0.5));
        assert!(LABEL.row_of(batch, "third").is_err());
    }

    /// A missing value is a null, allowed only in a column declared nullable
    /// (whose field carries what a null means); infinity is never written.
    #[test]
    fn nulls_only_where_declared_and_no_infinity() {
        let rows = [Some(2.0), None];
        let table = Rows::new(&rows)
            .optional(BOUND, |r| *r)
            .table(&SPEC)
            .unwrap();
        assert_eq!(BOUND.optional(&table.batch).unwrap(), rows);
        let schema = table.batch.schema();
        let field = schema.field(0);
        assert!(field.is_nullable());
        assert_eq!(field.metadata()["null"], "no bound");
        let written =
            |col: Col<f64>, value: f64| Rows::new(&[value]).with(col, |v| *v).table(&SPEC);
        let plain = written(RATE.value, 1.0).unwrap().batch.schema();
        assert!(!plain.field(0).is_nullable() && !plain.field(0).metadata().contains_key("null"));
        assert!(
            written(RATE.value, f64::NAN).is_err(),
            "a null where none is declared"
        );
        assert!(written(BOUND, f64::NAN).is_ok());
        assert!(written(BOUND, f64::INFINITY).is_err(), "infinity");
    }
}
