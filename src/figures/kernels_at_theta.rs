//! `kernels_<family>`: the kernels of a family with a well at each `theta = kT/eps`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::kernels::{every_kernel, kernels_layout};
use super::{FigureKind, Layout};
use crate::pipeline::{Input, StageError};

/// `G(0 -> u)` of every `theta = kT/eps` of one family with a well, in
/// scaled units (paper, Lennard-Jones: scaling holds at low `T`, breaks
/// at high `T`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KernelsAtTheta {
    /// The family's name (`Lennard-Jones`).
    pub family: String,
    /// Its id prefix, which names the figure (`kernels_lj`).
    pub prefix: String,
    /// Its length unit (`l = l0 (eps/kT)^(1/6)`).
    pub unit: String,
    /// Legend label of each kernel input.
    pub labels: Vec<String>,
}

impl FigureKind for KernelsAtTheta {
    fn name(&self) -> String {
        format!("kernels_{}", self.prefix)
    }

    fn description(&self) -> String {
        let (family, unit) = (&self.family, &self.unit);
        format!(
            "G(0 -> u) of every {family} theta = kT/eps (u' = 0, dilute, units of {unit}) against u - u' > 0, log axes, +- standard error; bins grouped 20 per decade, groups with relative error above 0.5 left out"
        )
    }

    fn layout(&self) -> Layout {
        kernels_layout()
    }

    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError> {
        every_kernel(&self.labels, inputs)
    }
}
