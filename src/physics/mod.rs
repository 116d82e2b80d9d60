//! Pure physics in scaled units (physics.md §1): lengths in `l`, velocities in
//! `v_th`, times in `l / v_th`, energies in `kT`. No IO, no tables, no CLI.

pub mod clusters;
pub mod dissociation;
pub mod launch;
pub mod md;
pub mod offset_quadrature;
pub mod pair_kinetics;
pub mod potential;
pub mod quasi_random;
pub mod ring;
pub mod sampling;
pub mod scan;
pub mod scene;
pub mod species;
pub mod units;
