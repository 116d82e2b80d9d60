//! Instance names: what each stage instance is computed for (a potential, a
//! kernel's `u'` and density, a ring, the study), named once, here. The plan
//! composes them; each stage names itself and its inputs through them.

use super::dissociation as dissociation_stage;
use super::spectrum as spectrum_stage;
use super::table as table_stage;
use super::{collisions as collisions_stage, compare as compare_stage, fit as fit_stage};
use super::{kernel as kernel_stage, scan as scan_stage};
use super::{launches as launches_stage, md as md_stage, moments as moments_stage};
use crate::config::KernelParams;
use crate::physics::potential::Potential;
use crate::pipeline::InstanceId;

/// Name of a per-`(potential, u', density)` instance, e.g. `ipp-6_u0_rho0`.
pub fn target(params: &KernelParams) -> String {
    format!(
        "{}_u{}_rho{}",
        params.potential.id(),
        params.u_prime,
        params.density
    )
}

/// Name of the collisions that reach every `u'` of the sweep and of the
/// evolution grid: the potential's own wide set (`<id>_sweep`) when the
/// sweep spreads its launches (`own_set`), else its main set (`<id>`).
pub fn wide_collisions(potential: &Potential, own_set: bool) -> String {
    if own_set {
        format!("{}_sweep", potential.id())
    } else {
        potential.id()
    }
}

/// Name of the collisions of `potential` drawn for a special particle at
/// `u'` (no launch mixture), e.g. `ipp-6_u-3`.
pub fn tuned_collisions(potential: &Potential, u_prime: f64) -> String {
    format!("{}_u{u_prime}", potential.id())
}

/// Name of the collisions of the potential with id `potential_id`
/// re-integrated at engine tolerance `tolerance`, e.g. `ipp-6_tol1e-10`.
pub fn tolerance_collisions(potential_id: &str, tolerance: f64) -> String {
    format!("{potential_id}_tol{tolerance:e}")
}

/// The `launches` instance named `name`.
pub fn launches(name: &str) -> InstanceId {
    InstanceId::new(launches_stage::STAGE, name)
}

/// The `collisions` instance named `name`.
pub fn collisions(name: &str) -> InstanceId {
    InstanceId::new(collisions_stage::STAGE, name)
}

/// The `collisions` instances of scene sets `main` and `other`, `other` left
/// out when it is the same set (a stage then reads it once).
pub fn collisions_of(main: &str, other: &str) -> Vec<InstanceId> {
    let mut ids = vec![collisions(main)];
    if other != main {
        ids.push(collisions(other));
    }
    ids
}

/// The `scan` instance of `potential`.
pub fn scan(potential: &Potential) -> InstanceId {
    InstanceId::new(scan_stage::STAGE, &potential.id())
}

/// The `dissociation` instance of a potential with a well.
pub fn dissociation(potential: &Potential) -> InstanceId {
    InstanceId::new(dissociation_stage::STAGE, &potential.id())
}

/// The `spectrum` instance of a potential.
pub fn spectrum(potential: &Potential) -> InstanceId {
    InstanceId::new(spectrum_stage::STAGE, &potential.id())
}

/// The `kernel` instance of kernel parameters.
pub fn kernel(params: &KernelParams) -> InstanceId {
    InstanceId::new(kernel_stage::STAGE, &target(params))
}

/// The `moments` instance of kernel parameters.
pub fn moments(params: &KernelParams) -> InstanceId {
    InstanceId::new(moments_stage::STAGE, &target(params))
}

/// The `fit` instance of kernel parameters.
pub fn fit(params: &KernelParams) -> InstanceId {
    InstanceId::new(fit_stage::STAGE, &target(params))
}

/// The `md` instance of the ring named `name`.
pub fn md(name: &str) -> InstanceId {
    InstanceId::new(md_stage::STAGE, name)
}

/// The study's one `compare` instance.
pub fn compare() -> InstanceId {
    InstanceId::new(compare_stage::STAGE, "study")
}

/// The study's one `near_integrable` instance.
pub fn near_integrable() -> InstanceId {
    InstanceId::new(super::near_integrable::STAGE, "study")
}

/// The `sweep` instance of a potential.
pub fn sweep(potential: &Potential) -> InstanceId {
    InstanceId::new(super::sweep::STAGE, &potential.id())
}

/// The study's one `interpolation` instance.
pub fn interpolation() -> InstanceId {
    InstanceId::new(super::interpolation::STAGE, "kernels")
}

/// The study's one `pulls` instance.
pub fn pulls() -> InstanceId {
    InstanceId::new(super::pulls::STAGE, "study")
}

/// The study's one `table` instance.
pub fn table() -> InstanceId {
    InstanceId::new(table_stage::STAGE, "study")
}
