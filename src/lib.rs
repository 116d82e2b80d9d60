//! `ternary`: three-body thermalization of a dilute one-dimensional classical gas.
//!
//! * [`physics`]: pure physics (potentials, the three-body scattering engine,
//!   mono-energetic scans, ring molecular dynamics); no IO.
//! * [`binning`]: velocity bins around `u'`, shared by physics and kernel.
//! * [`stats`]: estimates over replicates (standard errors, ratios,
//!   jackknife, chi-square).
//! * [`integrate`]: embedded Runge-Kutta(-Nystrom) steps for tiny systems and
//!   the adaptive step driver.
//! * [`kernel`]: the collision kernel and its moments from integrated scenes.
//! * [`evolve`]: the evolution of `h(u, t)` under the kernel.
//! * [`analysis`]: molecular dynamics against the Boltzmann evolution.
//! * [`rates`]: a Lennard-Jones gas's rates in physical units, interpolated
//!   in `theta` from the study's table (`ternary rate`).
//! * [`pipeline`]: the generic content-addressed DAG (keys, store, executor,
//!   Parquet tables); no physics.
//! * [`stages`]: one adapter per stage between the two; [`plan`]: which
//!   stage instances a study runs, with their inputs (the DAG), built
//!   without running anything.
//! * [`paper`]: the paper's published numbers and how ours are computed.
//! * [`contract`]: every output table's columns, declared once for the
//!   stages that write and read them and for the report.
//! * [`config`]: `pipeline.toml`, parsed strictly.
//! * [`report`]: what `ternary run` prints and `ternary show` displays.
//! * [`export`]: citable dataset bundles; [`slurm`]: sharded runs on a cluster.
//!
//! The benchmarks (`ternary bench`) belong to the command line, not the library.

pub mod analysis;
pub mod binning;
pub mod calibration;
pub mod config;
pub mod contract;
pub mod evolve;
pub mod export;
pub mod figures;
pub mod integrate;
pub mod kernel;
pub mod linalg;
pub mod paper;
pub mod physics;
pub mod pipeline;
pub mod plan;
pub mod rates;
pub mod report;
pub mod scaling;
pub mod slurm;
pub mod stages;
pub mod stats;
pub mod thresholds;
