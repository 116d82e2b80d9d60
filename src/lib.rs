//! `ternary`: three-body thermalization of a dilute one-dimensional classical gas.
//!
//! * [`physics`]: pure physics (potentials, the three-body scattering engine,
//!   mono-energetic scans); no IO.
//! * [`integrate`]: embedded Runge-Kutta(-Nystrom) steps for tiny systems.
//! * [`kernel`]: the collision kernel and its moments from integrated scenes.
//! * [`pipeline`]: the generic content-addressed DAG (keys, store, executor,
//!   Parquet tables); no physics.
//! * [`stages`]: one adapter per stage between the two.
//! * [`config`]: `pipeline.toml`, parsed strictly.
//! * [`report`]: what `ternary run` prints and `ternary show` displays.
//! * [`bench`]: work-precision benchmarks.

pub mod bench;
pub mod config;
pub mod evolve;
pub mod export;
pub mod integrate;
pub mod kernel;
pub mod linalg;
pub mod physics;
pub mod pipeline;
pub mod report;
pub mod slurm;
pub mod stages;
