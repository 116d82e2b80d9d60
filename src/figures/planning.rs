//! What the figure kinds' plans share: the potentials with kicks, the main
//! potential, its dilute instances, picking curves, ring labels.

use crate::config::{MdParams, Study};
use crate::contract::instances;
use crate::physics::potential::Potential;
use crate::pipeline::InstanceId;

/// The study's potentials that kick (every one but the integrable `n = 2`).
pub(super) fn kicked(study: &Study) -> Vec<Potential> {
    study
        .potentials()
        .into_iter()
        .filter(|p| !p.family().is_integrable())
        .collect()
}

/// The potential the detailed figures show: `n = 6`, or the first that
/// kicks.
pub(super) fn main_potential(study: &Study) -> Option<Potential> {
    let kicked = kicked(study);
    kicked
        .iter()
        .find(|p| **p == Potential::inverse_power(6.0))
        .or(kicked.first())
        .copied()
}

/// The `stage` instance of `potential`'s dilute kernel at `u' = 0`.
pub(super) fn dilute(study: &Study, stage: &str, potential: &Potential) -> InstanceId {
    let params = study.kernel_params(*potential, 0.0, 0.0);
    InstanceId::new(stage, &instances::target(&params))
}

/// At most `count` of `values`, spread evenly over them, first and last
/// included (more curves than colours, or than a panel shows, cannot be
/// told apart).
pub(super) fn spread<T: Copy + PartialEq>(values: &[T], count: usize) -> Vec<T> {
    if values.len() <= count {
        return values.to_vec();
    }
    let last = values.len() - 1;
    let mut picked: Vec<T> = (0..count)
        .map(|k| values[(k * last + (count - 1) / 2) / (count - 1)])
        .collect();
    picked.dedup();
    picked
}

/// A ring's `kT`, meV (to a micro-electronvolt).
pub(super) fn kt_mev(ring: &MdParams) -> f64 {
    (ring.gas.kt_ev * 1e6).round() / 1e3
}

/// A ring's legend label: `N = 161, R = 51.2 mm, 100 meV`.
pub(super) fn ring_label(ring: &MdParams) -> String {
    let radius_mm = ring.radius_um / 1e3;
    format!(
        "N = {}, R = {radius_mm} mm, {} meV",
        ring.particles,
        kt_mev(ring)
    )
}

/// The first ring, when the study compares MD with Boltzmann (`compare`
/// planned): the figures of MD are drawn from `compare`.
pub(super) fn compared(study: &Study, present: &dyn Fn(&InstanceId) -> bool) -> Option<MdParams> {
    let first = study.md_params().first().cloned()?;
    present(&instances::compare()).then_some(first)
}
