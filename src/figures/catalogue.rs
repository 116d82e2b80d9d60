//! The figures `ternary` draws, listed once: each kind is a file of its own
//! behind [`FigureKind`] (its parameters, the artifacts it reads and how
//! polars turns their tables into the figure table, its layout, its
//! caption), and [`Figure`] lists the kinds.

use polars::prelude::DataFrame;
use serde::Serialize;

use super::Layout;
use super::collapse::Collapse;
use super::evolution::Evolution;
use super::finite_size::FiniteSize;
use super::gaps::Gaps;
use super::kernel_fit::KernelFit;
use super::kernels::KernelsEveryN;
use super::kernels_at_theta::KernelsAtTheta;
use super::kernels_density::KernelsAtDensity;
use super::kernels_u_prime::KernelsAtUPrime;
use super::kicks::Kicks;
use super::md_boltzmann::MdBoltzmann;
use super::md_times::MdTimes;
use super::near_integrable::NearIntegrable;
use super::pulls::Pulls;
use super::rates::Rates;
use super::spectrum::Spectrum;
use super::truncation::Truncation;
use crate::pipeline::{Input, StageError};

/// What the `figures` stage asks of a figure: one implementation per kind,
/// one file each, so that the stage asks the figure instead of matching on
/// its kind.
pub trait FigureKind {
    /// The figure's name: its instance and file stem.
    fn name(&self) -> String;
    /// What the figure shows (its table's description, the caption).
    fn description(&self) -> String;
    /// How the figure is drawn.
    fn layout(&self) -> Layout;
    /// The figure's long table, built with polars from its inputs' tables
    /// (in the order the plan gives them).
    fn frame(&self, inputs: &[Input]) -> Result<DataFrame, StageError>;
}

/// A figure of the study: its kind, with the parameters (series labels in
/// input order, ids, rings) its file declares. Its serialized form (`kind`
/// and those parameters) enters the figure's key.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Figure {
    /// `kernels`.
    KernelsEveryN(KernelsEveryN),
    /// `kernels_<family>`.
    KernelsAtTheta(KernelsAtTheta),
    /// `kernel_fit_<id>`.
    KernelFit(KernelFit),
    /// `rates_<id>`.
    Rates(Rates),
    /// `md_boltzmann_<ring>`.
    MdBoltzmann(MdBoltzmann),
    /// `truncation_<id>`.
    Truncation(Truncation),
    /// `kicks_<id>`.
    Kicks(Kicks),
    /// `collapse`.
    Collapse(Collapse),
    /// `evolution_<instance>`.
    Evolution(Evolution),
    /// `finite_size`.
    FiniteSize(FiniteSize),
    /// `kernels_u_prime_<id>`.
    KernelsAtUPrime(KernelsAtUPrime),
    /// `kernels_density_<id>`.
    KernelsAtDensity(KernelsAtDensity),
    /// `spectrum_<id>`.
    Spectrum(Spectrum),
    /// `gaps`.
    Gaps(Gaps),
    /// `near_integrable`.
    NearIntegrable(NearIntegrable),
    /// `pulls`.
    Pulls(Pulls),
    /// `md_times_<ring>`.
    MdTimes(MdTimes),
}

impl Figure {
    /// The figure's kind: what it reads, shows and how it is drawn (the one
    /// dispatch on the kind).
    pub fn kind(&self) -> &dyn FigureKind {
        match self {
            Figure::KernelsEveryN(figure) => figure,
            Figure::KernelsAtTheta(figure) => figure,
            Figure::KernelFit(figure) => figure,
            Figure::Rates(figure) => figure,
            Figure::MdBoltzmann(figure) => figure,
            Figure::Truncation(figure) => figure,
            Figure::Kicks(figure) => figure,
            Figure::Collapse(figure) => figure,
            Figure::Evolution(figure) => figure,
            Figure::FiniteSize(figure) => figure,
            Figure::KernelsAtUPrime(figure) => figure,
            Figure::KernelsAtDensity(figure) => figure,
            Figure::Spectrum(figure) => figure,
            Figure::Gaps(figure) => figure,
            Figure::NearIntegrable(figure) => figure,
            Figure::Pulls(figure) => figure,
            Figure::MdTimes(figure) => figure,
        }
    }
}
