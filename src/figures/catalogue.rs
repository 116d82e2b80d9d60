//! The figures `ternary` draws, each kind a file of its own behind
//! [`FigureKind`]: its parameters, when a study draws it and from which
//! instances, how polars turns their tables into the figure table, its
//! layout and its caption. The list of kinds is the files themselves: the
//! build script finds every `impl FigureKind for <Kind>` in `src/figures/`
//! and lists `<Kind>::planned` in [`PLANS`].

use polars::prelude::DataFrame;
use serde::Serialize;
use serde_json::{Value, json};

use super::Layout;
use crate::config::Study;
use crate::pipeline::{Input, InstanceId, StageError};

/// What the `figures` stage asks of a figure: one implementation per kind,
/// one file each, so that the stage asks the figure instead of matching on
/// its kind. Besides it, each kind has an inherent
/// `fn planned(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn>`:
/// the figures of its kind a study draws ([`Plan`]).
pub trait FigureKind: Keyed + Send + Sync {
    /// The figure's name: its instance and file stem.
    fn name(&self) -> String;
    /// Where the figure stands among the study's figures.
    fn topic(&self) -> Topic;
    /// What the figure shows (its table's description, the caption).
    fn description(&self) -> String;
    /// How the figure is drawn.
    fn layout(&self) -> Layout;
    /// The figure's long table, built with polars from its inputs' tables
    /// (in the order the plan gives them).
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError>;
}

/// A figure's parameters as they enter its key: its serialized form, which
/// each kind tags with its name in snake case
/// (`#[serde(tag = "kind", rename = "md_times")]`).
pub trait Keyed {
    /// The serialized parameters (`kind` and the plan's ids, rings, labels).
    fn keyed(&self) -> Value;
}

impl<T: Serialize> Keyed for T {
    fn keyed(&self) -> Value {
        json!(self)
    }
}

/// Where a figure stands: the plan lists (and the report shows) the study's
/// figures by topic, in this order, and within a topic by file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Topic {
    /// The kernels of every potential.
    Kernels,
    /// The main potential's kernel in detail: its fit, at each `u'` and
    /// density, its kicks, `a_n(X)`.
    MainKernel,
    /// Rates against `u'` and `n`.
    Rates,
    /// The relaxation: spectrum and evolution.
    Relaxation,
    /// Molecular dynamics against Boltzmann.
    MolecularDynamics,
    /// The study's cross-checks.
    Checks,
}

/// A figure a study draws, with its inputs in the order its `frame` reads
/// them.
pub struct Drawn {
    /// The figure.
    pub figure: Box<dyn FigureKind>,
    /// Its input instances.
    pub inputs: Vec<InstanceId>,
}

impl Drawn {
    /// `figure` drawn from `inputs`.
    pub fn new(figure: impl FigureKind + 'static, inputs: Vec<InstanceId>) -> Drawn {
        Drawn {
            figure: Box::new(figure),
            inputs,
        }
    }

    /// `figure` drawn from the one instance `input`, when the study
    /// computes it (`present`).
    pub fn if_present(
        figure: impl FigureKind + 'static,
        input: InstanceId,
        present: &dyn Fn(&InstanceId) -> bool,
    ) -> Vec<Drawn> {
        if present(&input) {
            vec![Drawn::new(figure, vec![input])]
        } else {
            Vec::new()
        }
    }
}

/// A kind's plan: the figures of its kind that `study` draws, given which
/// instances the study's plan computes (`present`).
pub type Plan = fn(&Study, &dyn Fn(&InstanceId) -> bool) -> Vec<Drawn>;

// `PLANS: &[Plan]`, every kind's `planned` in file order (the build script's).
include!(concat!(env!("OUT_DIR"), "/figure_plans.rs"));
