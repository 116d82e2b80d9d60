//! Which published numbers a study can check: every Table I cell and other
//! number of the paper whose inputs the plan computes, and the collisions
//! the detailed-balance pair is computed from.

use std::collections::HashSet;

use super::collisions::tuned_collisions;
use crate::config::{CollisionsParams, MdParams, Study};
use crate::contract::instances;
use crate::paper::published::*;
use crate::paper::{Check, Column, ScalingRing};
use crate::physics::potential::Potential;
use crate::physics::units::PhysicalGas;
use crate::pipeline::{InstanceId, Stage};
use crate::stages::paper::PaperStage;

/// The `paper` stage of a study: every published number whose inputs `plan`
/// computes (none: no stage).
pub(super) fn paper_stage(study: &Study, plan: &[Box<dyn Stage>]) -> Option<PaperStage> {
    let planned: HashSet<InstanceId> = plan.iter().map(|stage| stage.id()).collect();
    let present = |id: &InstanceId| planned.contains(id);
    let dilute = |p: Potential| study.kernel_params(p, 0.0, 0.0);
    let has = |p: Potential| present(&instances::moments(&dilute(p)));
    let mut checks = table_i_checks(study, &planned);
    if has(LJ_0_1) {
        checks.push(Check::Rate {
            published: A_LJ,
            moments: dilute(LJ_0_1),
        });
    }
    if let Some((collisions, _)) = balance_collisions(study) {
        let (a, b) = BALANCE_PAIR;
        let bin_width = study.config.sweep.balance_bin_width;
        checks.push(Check::Balance {
            published: BALANCE,
            sweep: IPP_6.id(),
            collisions,
            a,
            steps: ((b - a) / bin_width).round() as usize,
            bin_width,
            kernel: dilute(IPP_6),
        });
    }
    let compared = study.md_params().first().map(|ring| ring.potential);
    if present(&instances::compare()) && compared == Some(IPP_6) {
        checks.push(Check::RingTime {
            published: RING_TIME,
            moments: dilute(IPP_6),
        });
    }
    checks.extend(scaling_checks(study, present(&instances::compare())));
    if let Some(gas) = study.gases().into_iter().find(|g| g.name == NITROGEN_GAS) {
        checks.push(Check::GasTime {
            published: NITROGEN,
            gas: gas.name,
            moments: dilute(gas.potential),
        });
    }
    (!checks.is_empty()).then(|| PaperStage::new(checks))
}

/// The `rho^2 T^(1/2 - 1/n)` scaling checks the rings allow: the ratio of
/// two temperatures from the kernels, and with `compared` rings from MD too,
/// with the exponents fitted to MD.
fn scaling_checks(study: &Study, compared: bool) -> Vec<Check> {
    let mut checks = Vec::new();
    if let Some((cold, hot)) = scaling_rings(study) {
        checks.push(Check::ScalingKernel {
            published: SCALING_KERNEL,
            cold: cold.clone(),
            hot: hot.clone(),
        });
        if compared {
            checks.push(Check::ScalingMd {
                published: SCALING_MD,
                cold,
                hot,
            });
        }
    }
    if let Some(rings) = exponent_rings(study).filter(|_| compared) {
        for (published, density) in [(DENSITY_EXPONENT, true), (TEMPERATURE_EXPONENT, false)] {
            checks.push(Check::ScalingExponent {
                published,
                density,
                rings: rings.clone(),
            });
        }
    }
    checks
}

/// Every Table I cell whose inputs are `planned`, column by column.
fn table_i_checks(study: &Study, planned: &HashSet<InstanceId>) -> Vec<Check> {
    let present = |id: &InstanceId| planned.contains(id);
    let scans_symmetric = study
        .config
        .scan
        .launch
        .iter()
        .any(|launch| (launch.u2, launch.u3) == SYMMETRIC_LAUNCH);
    let mut checks = Vec::new();
    for column in [
        Column::RateConstant,
        Column::Alpha,
        Column::Beta,
        Column::Sigma,
        Column::KickMax,
    ] {
        for row in &TABLE_I {
            let potential = Potential::inverse_power(f64::from(row.n));
            let kernel = study.kernel_params(potential, 0.0, 0.0);
            let Some(published) = row.published(column) else {
                continue;
            };
            let check = match column {
                Column::RateConstant => {
                    present(&instances::moments(&kernel)).then_some(Check::Rate {
                        published,
                        moments: kernel,
                    })
                }
                Column::Alpha | Column::Beta | Column::Sigma => present(&instances::fit(&kernel))
                    .then_some(Check::Shape {
                        published,
                        kernel,
                        column,
                    }),
                Column::KickMax => (scans_symmetric && present(&instances::scan(&potential)))
                    .then_some(Check::KickMax {
                        published,
                        potential,
                    }),
            };
            checks.extend(check);
        }
    }
    checks
}

/// The collisions the paper's detailed-balance pair is computed from, when
/// the study offers the pair (`n = 6` among its potentials, a sweep from `u' = -3` with the
/// separation 0.04): launches drawn for `u' = -3` itself. The sweep's own
/// scenes, a launch mixture for its whole grid, leave the ratio at +-0.044 with
/// the default study's 2560 pairs; drawn for `-3`, 4096 pairs reach +-0.015
/// (docs/benchmarks.md, `bench balance`).
pub(super) fn balance_collisions(study: &Study) -> Option<(String, CollisionsParams)> {
    if !study.potentials().contains(&IPP_6) {
        return None;
    }
    let sweep = study.sweep_params(IPP_6)?;
    let (a, b) = BALANCE_PAIR;
    let width = sweep.balance_bin_width;
    let offers = sweep.u_prime_min == a
        && sweep
            .balance_separations
            .iter()
            .any(|s| ((s / width).round() * width - (b - a)).abs() < 1e-9);
    offers.then(|| tuned_collisions(study, IPP_6, a))
}

/// A ring of the scaling checks: its time, its gas's units and the
/// moments at its own `rho l`.
fn scaling_ring(study: &Study, r: &MdParams) -> ScalingRing {
    ScalingRing {
        name: r.name.clone(),
        final_time_ns: r.final_time_ns,
        rate_unit_per_ns: r
            .gas
            .rate_per_ns(1.0, r.potential.family().length_exponent()),
        density_per_um: r.gas.density_per_um,
        kt_ev: r.gas.kt_ev,
        moments: study.kernel_params(r.potential, 0.0, r.scaled_density()),
    }
}

/// The `n = 6` rings of the scaling collapse (the same `N` and
/// `rho^2 l v_th t_f`) when they span two densities and two temperatures.
fn exponent_rings(study: &Study) -> Option<Vec<ScalingRing>> {
    let rings: Vec<MdParams> = study
        .collapse_rings()
        .into_iter()
        .filter(|r| r.potential == IPP_6)
        .collect();
    let distinct = |value: fn(&MdParams) -> f64| {
        rings
            .iter()
            .any(|r| (value(r) / value(&rings[0]) - 1.0).abs() > 1e-9)
    };
    (rings.len() >= 3 && distinct(|r| r.gas.density_per_um) && distinct(|r| r.gas.kt_ev))
        .then(|| rings.iter().map(|r| scaling_ring(study, r)).collect())
}

/// The first two collapse rings of `n = 6` at one density whose
/// temperatures differ by the paper's factor 8 (the rest of the gas equal),
/// colder first.
fn scaling_rings(study: &Study) -> Option<(ScalingRing, ScalingRing)> {
    let rings = study.collapse_rings();
    let ring = |r: &MdParams| scaling_ring(study, r);
    let pair = |cold: &MdParams, hot: &MdParams| {
        let apart_from_temperature = PhysicalGas {
            kt_ev: hot.gas.kt_ev,
            ..cold.gas
        } == hot.gas;
        cold.potential == IPP_6
            && hot.potential == IPP_6
            && apart_from_temperature
            && (hot.gas.kt_ev / cold.gas.kt_ev / SCALING_TEMPERATURES - 1.0).abs() < 1e-9
    };
    rings.iter().find_map(|cold| {
        rings
            .iter()
            .find(|hot| pair(cold, hot))
            .map(|hot| (ring(cold), ring(hot)))
    })
}
