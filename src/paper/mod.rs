//! The paper's published numbers next to ours (Phys. Rev. E 110, 014114
//! (2024)): what the paper prints ([`published`]) and how ours is computed
//! from a study's instances ([`checks`]). The `paper` stage encodes the rows;
//! the plan chooses which checks a study's instances allow.

pub mod checks;
pub mod published;

pub use checks::{Check, Converged, PaperRow, ScalingRing};
pub use published::{Cell, Column, Published};
