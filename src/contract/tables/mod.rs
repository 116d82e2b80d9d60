//! Every output table of the study, grouped by the stage that writes it: its
//! name, description and columns in file order. The only place a column name
//! is spelled; units follow physics.md (`v_th`, `l/v_th`, `rho^2 l v_th`).
//! One file per stage; this file holds the column names and units that
//! several stages' tables share.

pub mod collisions;
pub mod compare;
pub mod convergence;
pub mod dissociation;
pub mod estimator;
pub mod evolve;
pub mod figures;
pub mod fit;
pub mod gases;
pub mod interpolation;
pub mod kernel;
pub mod launches;
pub mod md;
pub mod moments;
pub mod near_integrable;
pub mod paper;
pub mod pulls;
pub mod scan;
pub mod spectrum;
pub mod sweep;
pub mod table;

use super::printout::{Footnote, Layout, Printed, Printout, Selection, Shown};
use super::study_column::StudyColumn;
use super::{Col, Pair, TableSpec, UNIT_PER_PANEL, UNIT_PER_ROW};

// `DETAILS: &[&Printout]`, every `PRINTOUT` of this directory's files in
// file order (the build script's): the stages' tables that `ternary run
// --details` and the HTML report print after the study's own (`a_n`, the
// paper's, the pulls', each a `HEADLINE` that `report::summary` places).
include!(concat!(env!("OUT_DIR"), "/details.rs"));

/// The study table's columns that other stages supply (`table` reads each
/// from the supplying stage's instance of the row's potential, where the
/// study has one), in the table's order.
pub const STUDY_COLUMNS: [&[StudyColumn]; 2] =
    [&dissociation::study::COLUMNS, &spectrum::study::COLUMNS];

/// Bin centre relative to `u'` (kernel, md and early-evolution tables).
pub const DU: Col<f64> = Col::f64("du", "v_th", "bin centre relative to u'");
/// Bin centre in the lab (md and early-evolution tables).
pub const BIN_CENTRE: Col<f64> = Col::f64("u", "v_th", "bin centre");
/// Potential id (gases and study tables).
pub const POTENTIAL: Col<String> = Col::text("potential", "potential id");
/// Density `h` in `1/v_th`.
const DENSITY: &str = "1/v_th";
/// Rates in scaled units.
const RATE: &str = "rho^2 l v_th";

/// Scenes drawn (moments and study tables).
const EVENTS: &str = "events";
/// Scenes failed (moments and study tables).
const FAILED_EVENTS: &str = "failed_events";

/// Names of the kernel shape parameters (fit and study tables).
const ALPHA: &str = "alpha";
const BETA: &str = "beta";
const SIGMA: &str = "sigma";

/// Unit of the shape amplitude alpha: `g(x) = alpha |x|^-beta exp(...)` is a
/// rate density in `rho^2 l v_th` per `v_th`, and `|x|^-beta` carries
/// `v_th^-beta`.
pub const ALPHA_UNIT: &str = "rho^2 l v_th (v_th)^(beta-1)";

/// `a_n` (convergence, gases and study tables).
const A_N: &str = "a_n";

/// Error over MD runs.
const OVER_RUNS: &str = "standard error over runs";

/// The md system (compare's tables).
const RING: &str = "ring";
