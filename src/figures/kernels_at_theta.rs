//! `kernels_<family>`: the kernels of a family with a well at each `theta = kT/eps`.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::PALETTE;
use super::kernels::{every_kernel, kernels_layout};
use super::planning::{dilute, kicked, spread};
use super::{Drawn, FigureKind, Layout, Topic};
use crate::config::Study;
use crate::contract;
use crate::physics::potential::{Family, Potential};
use crate::pipeline::{Input, InstanceId, StageError};

/// `G(0 -> u)` of every `theta = kT/eps` of one family with a well, in
/// scaled units (paper, Lennard-Jones: scaling holds at low `T`, breaks
/// at high `T`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "kernels_at_theta")]
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

impl KernelsAtTheta {
    /// The kernels of each family with a `theta` in one figure per family,
    /// at most one `theta` per colour, spread over them.
    pub fn planned(study: &Study, _present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn> {
        let at_theta: Vec<Potential> = kicked(study)
            .into_iter()
            .filter(|p| p.family().theta().is_some())
            .collect();
        let mut families: Vec<(&dyn Family, Vec<Potential>)> = Vec::new();
        for p in &at_theta {
            match families
                .iter_mut()
                .find(|(f, _)| f.name() == p.family().name())
            {
                Some((_, members)) => members.push(*p),
                None => families.push((p.family(), vec![*p])),
            }
        }
        families
            .into_iter()
            .map(|(family, members)| {
                let shown = spread(&members, PALETTE.len());
                let figure = KernelsAtTheta {
                    family: family.name().into(),
                    prefix: family.prefix().into(),
                    unit: family.length_unit().into(),
                    labels: shown.iter().map(|p| p.family().label()).collect(),
                };
                let inputs = shown
                    .iter()
                    .map(|p| dilute(study, contract::kernel::STAGE, p))
                    .collect();
                Drawn::new(figure, inputs)
            })
            .collect()
    }
}

impl FigureKind for KernelsAtTheta {
    fn topic(&self) -> Topic {
        Topic::Kernels
    }

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
