//! The study's stages, one per file: thin adapters between the pipeline and the
//! physics. [`crate::plan`] decides which instances of them a study runs.

pub mod collisions;
pub mod compare;
pub mod convergence;
pub mod dissociation;
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
