//! Columns of the study table (`table`, one row per potential) that other
//! stages supply, each declared beside that stage's own tables: the study
//! table's column and where its value is read. The `table` stage reads
//! every declared column from the supplying stage's instance of the row's
//! potential, so a stage that adds a per-potential column edits neither the
//! study table's contract nor the `table` stage.

use arrow_array::RecordBatch;

use super::{Col, Pair, TableSpec};
use crate::pipeline::StageError;
use crate::stats::Estimate;

/// A study-table column supplied by another stage.
#[derive(Clone, Copy, Debug)]
pub struct StudyColumn {
    /// The study table's column (value and error; null where the supplying
    /// stage has no instance for the potential).
    pub column: Pair,
    /// The table it is read from, of the supplying stage's instance named
    /// by the row's potential id.
    pub source: TableSpec,
    /// Which row of it: the first, or the one whose label column holds the
    /// label.
    pub row: Option<(Col<String>, &'static str)>,
    /// The value and error read.
    pub value: Pair,
}

impl StudyColumn {
    /// The value this column takes from `batch`, the source table of one
    /// potential.
    pub fn read(&self, batch: &RecordBatch) -> Result<Estimate, StageError> {
        let row = match self.row {
            None => 0,
            Some((labels, label)) => labels.row_of(batch, label)?,
        };
        self.value
            .read(batch)?
            .get(row)
            .copied()
            .ok_or_else(|| StageError::Input(format!("{} has no row {row}", self.source.name)))
    }
}
