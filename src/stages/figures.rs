//! `figures`: one instance per figure. Its table (`points.parquet`) is built
//! with polars from the tables of the artifacts it draws; its files are the
//! figure drawn from that table as SVG and PNG, one journal column wide and at
//! a screen size ([`crate::figures`]).

use serde_json::{Value, json};

use crate::contract::{self, TableSpec};
use crate::figures::{Drawn, FigureKind, FigureRows, Size, frames, render};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};

/// The figure table's name (`points.parquet`).
const POINTS: &str = "points";

/// Metadata key of the figure's layout (panels, axis labels with units, log
/// scales, marks) in `points.parquet`.
const AXES: &str = "ternary.axes";

/// The `figures` stage for one figure.
pub struct FiguresStage {
    figure: Box<dyn FigureKind>,
    inputs: Vec<InstanceId>,
}

impl FiguresStage {
    /// The stage drawing a figure from its inputs (in the figure's input
    /// order).
    pub fn new(Drawn { figure, inputs }: Drawn) -> FiguresStage {
        FiguresStage { figure, inputs }
    }

    /// The figure table's declaration; each table carries its own figure's
    /// description.
    const SPEC: TableSpec = TableSpec {
        stage: contract::figures::STAGE,
        name: POINTS,
        description: "the points a figure draws",
    };
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for FiguresStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::figures::STAGE, &self.figure.name())
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        json!({ "figure": self.figure.keyed(), "layout": self.figure.layout() })
    }

    fn tables(&self) -> &'static [&'static str] {
        &[POINTS]
    }

    fn files(&self) -> Vec<String> {
        let name = self.figure.name();
        [Size::COLUMN_SVG.suffix, Size::SCREEN.suffix]
            .iter()
            .flat_map(|suffix| [format!("{name}{suffix}.svg"), format!("{name}{suffix}.png")])
            .collect()
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.inputs.clone()
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let figure = &self.figure;
        let frame = figure.frame(inputs)?;
        let points = frames::points(&frame)?;
        progress.advance(1);
        let layout = serde_json::to_string(&figure.layout())
            .map_err(|error| StageError::Input(format!("figure layout: {error}")))?;
        let table = FigureRows::table(&points, &Self::SPEC, &figure.description())?
            .with_metadata(AXES, layout);
        Ok(vec![table])
    }

    fn render(&self, tables: &[Table]) -> Result<Vec<(String, Vec<u8>)>, StageError> {
        let (figure, points) = (&self.figure, FigureRows::read(&tables[0])?);
        render(&figure.name(), &figure.layout(), &points)
            .map_err(|error| StageError::Input(format!("drawing {}: {error}", figure.name())))
    }
}
