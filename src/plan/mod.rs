//! The study's plan: every stage instance a study computes, with its
//! parameters and inputs, in topological order, built from the resolved
//! [`Study`] without running anything (like a lazy query plan; the default
//! study's is `tests/golden/default-plan.txt`). This module is the one place
//! that decides which instances exist: `Study` resolves values, the stages
//! compute, and every instance name comes from [`crate::contract::instances`].

mod collisions;
mod figures;
mod paper;

pub use collisions::wide_collisions;

use std::collections::HashSet;

use crate::config::Study;
use crate::contract::{self, instances};
use crate::physics::potential::Potential;
use crate::pipeline::{InstanceId, Stage};
use crate::stages::compare::{CompareParams, CompareStage};
use crate::stages::{
    convergence, dissociation, evolve, fit, gases, interpolation, kernel, md, moments,
    near_integrable, pulls, scan, spectrum, sweep, table,
};
use collisions::push_collisions;

/// Every stage instance of a study, in topological order.
pub fn plan(study: &Study) -> Vec<Box<dyn Stage>> {
    let mut stages: Vec<Box<dyn Stage>> = Vec::new();
    for potential in study.potentials() {
        push_potential(&mut stages, study, potential);
    }
    push_interpolation(&mut stages, study);
    push_gases(&mut stages, study);
    push_convergence(&mut stages, study);
    push_rings(&mut stages, study);
    let rows = study
        .potentials()
        .iter()
        .map(|&p| study.kernel_params(p, 0.0, 0.0))
        .collect();
    // Each potential's instance of a stage, where the plan holds one.
    let ids: HashSet<InstanceId> = stages.iter().map(|s| s.id()).collect();
    let planned = |instance: fn(&Potential) -> InstanceId| -> Vec<InstanceId> {
        let potentials = study.potentials();
        let ids_of = potentials.iter().map(instance);
        ids_of.filter(|id| ids.contains(id)).collect()
    };
    let (dissociations, spectra) = (
        planned(instances::dissociation),
        planned(instances::spectrum),
    );
    push_near_integrable(&mut stages, study, &spectra);
    push_pulls(
        &mut stages,
        study,
        &planned(instances::sweep),
        &dissociations,
    );
    stages.push(Box::new(table::TableStage::new(
        rows,
        suppliers(study, &ids),
    )));
    if let Some((name, params)) = paper::balance_collisions(study) {
        push_collisions(&mut stages, params, name);
    }
    if let Some(paper) = paper::paper_stage(study, &stages) {
        stages.push(Box::new(paper));
    }
    if study.config.figures.enabled {
        let figures = figures::figure_stages(study, &stages);
        stages.extend(figures.into_iter().map(|f| Box::new(f) as Box<dyn Stage>));
    }
    stages
}

/// The planned instances (`ids`) of the stages that supply columns of the
/// study table, each potential's once.
fn suppliers(study: &Study, ids: &HashSet<InstanceId>) -> Vec<InstanceId> {
    let mut suppliers = Vec::new();
    for potential in study.potentials() {
        for column in contract::STUDY_COLUMNS.iter().copied().flatten() {
            let id = InstanceId::new(column.source.stage, &potential.id());
            if ids.contains(&id) && !suppliers.contains(&id) {
                suppliers.push(id);
            }
        }
    }
    suppliers
}

/// The `interpolation` between the models of every kernel (each has a
/// `fit`), when one of them can be held out.
fn push_interpolation(stages: &mut Vec<Box<dyn Stage>>, study: &Study) {
    let kernels = study
        .potentials()
        .into_iter()
        .flat_map(|p| {
            study
                .kernel_targets()
                .into_iter()
                .map(move |(u_prime, density)| study.kernel_params(p, u_prime, density))
        })
        .collect();
    if let Some(stage) = interpolation::InterpolationStage::planned(kernels) {
        stages.push(Box::new(stage));
    }
}

/// The `pulls` of the study's cross-checks, when it runs a sweep: the
/// joint detailed-balance tests of every sweep, the recombination rates
/// of every potential whose sweep and dissociation run, and the
/// near-integrable exponents when `near_integrable` is planned already.
fn push_pulls(
    stages: &mut Vec<Box<dyn Stage>>,
    study: &Study,
    sweeps: &[InstanceId],
    dissociations: &[InstanceId],
) {
    if sweeps.is_empty() {
        return;
    }
    let recombinations = study
        .potentials()
        .into_iter()
        .filter(|p| {
            sweeps.contains(&instances::sweep(p))
                && dissociations.contains(&instances::dissociation(p))
        })
        .map(|p| study.kernel_params(p, 0.0, 0.0))
        .collect();
    let near_integrable = stages
        .iter()
        .any(|s| s.id() == instances::near_integrable());
    stages.push(Box::new(pulls::PullsStage::new(
        sweeps.to_vec(),
        recombinations,
        near_integrable,
    )));
}

/// The `near_integrable` table and fits, when an inverse power law with a
/// planned spectrum lies in `2 < n <= spectrum.near_integrable_max_n` (the
/// fits need four).
fn push_near_integrable(stages: &mut Vec<Box<dyn Stage>>, study: &Study, spectra: &[InstanceId]) {
    let near: Vec<Potential> = study
        .potentials()
        .into_iter()
        .filter(|&p| {
            study.config.spectrum.near_integrable(p) && spectra.contains(&instances::spectrum(&p))
        })
        .collect();
    if !near.is_empty() {
        stages.push(Box::new(near_integrable::NearIntegrableStage::new(near)));
    }
}

/// Adds `stage` unless an instance with its id is planned already.
fn push_once(stages: &mut Vec<Box<dyn Stage>>, stage: Box<dyn Stage>) {
    if !stages.iter().any(|other| other.id() == stage.id()) {
        stages.push(stage);
    }
}

/// One potential's scan, collisions, kernels with their moments and fits at
/// every `(u', density)` target, the sweep, spectrum and evolution that read
/// its wide collisions, and the dissociation of its bound pairs if it has a well.
fn push_potential(stages: &mut Vec<Box<dyn Stage>>, study: &Study, potential: Potential) {
    stages.push(Box::new(scan::ScanStage::new(study.scan_params(potential))));
    push_collisions(stages, study.collisions_params(potential), potential.id());
    for (u_prime, density) in study.kernel_targets() {
        let params = study.kernel_params(potential, u_prime, density);
        stages.push(Box::new(kernel::KernelStage::new(params)));
        stages.push(Box::new(moments::MomentsStage::new(
            params,
            study.config.kernel.truncations.clone(),
        )));
        stages.push(Box::new(fit::FitStage::new(study.fit_params(params))));
    }
    let sweep = study.sweep_params(potential);
    let evolve = study
        .evolve_params()
        .filter(|e| e.kernel.potential == potential);
    let compared = study
        .md_params()
        .first()
        .is_some_and(|ring| ring.potential == potential);
    let spectrum = study.spectrum_params(potential);
    let (wide_name, wide) = wide_collisions(study, potential);
    let reads_wide = sweep.is_some() || evolve.is_some() || spectrum.is_some() || compared;
    if let (true, Some(wide)) = (reads_wide, wide) {
        push_collisions(stages, wide, wide_name.clone());
    }
    if let Some(params) = sweep {
        stages.push(Box::new(sweep::SweepStage::new(params, wide_name.clone())));
    }
    if let Some(params) = spectrum {
        stages.push(Box::new(spectrum::SpectrumStage::new(
            params,
            wide_name.clone(),
        )));
    }
    if let Some(params) = evolve {
        stages.push(Box::new(evolve::EvolveStage::new(params, wide_name)));
    }
    if let Some(params) = study.dissociation_params(potential) {
        stages.push(Box::new(dissociation::DissociationStage::new(params)));
    }
}

/// The moments at each gas's own `rho l`, the kernel at each collapse ring's
/// (figure `kernels_density`: the literal algorithm's finite-density
/// factor), and the `gases` table.
fn push_gases(stages: &mut Vec<Box<dyn Stage>>, study: &Study) {
    let gases = study.gases();
    for gas in &gases {
        let dense = study.kernel_params(gas.potential, 0.0, gas.scaled_density());
        let truncations = study.config.kernel.truncations.clone();
        push_once(
            stages,
            Box::new(moments::MomentsStage::new(dense, truncations)),
        );
    }
    for ring in study.collapse_rings() {
        let dense = study.kernel_params(ring.potential, 0.0, ring.scaled_density());
        push_once(stages, Box::new(kernel::KernelStage::new(dense)));
    }
    if !gases.is_empty() {
        let rows = gases
            .into_iter()
            .map(|gas| {
                let dilute = study.kernel_params(gas.potential, 0.0, 0.0);
                let dense = study.kernel_params(gas.potential, 0.0, gas.scaled_density());
                (gas, dilute, dense)
            })
            .collect();
        stages.push(Box::new(gases::GasesStage::new(rows)));
    }
}

/// The collisions re-integrated at each varied tolerance and the
/// `convergence` table, if enabled.
fn push_convergence(stages: &mut Vec<Box<dyn Stage>>, study: &Study) {
    let Some((params, variants)) = study.convergence() else {
        return;
    };
    for variant in variants {
        let name =
            instances::tolerance_collisions(&variant.potential.id(), variant.engine.tolerance);
        push_collisions(stages, variant, name);
    }
    stages.push(Box::new(convergence::ConvergenceStage::new(params)));
}

/// Every MD ring and, when there is one, the `compare` stage setting the
/// compared rings against the Boltzmann evolution.
fn push_rings(stages: &mut Vec<Box<dyn Stage>>, study: &Study) {
    let rings = study.md_params();
    for params in &rings {
        stages.push(Box::new(md::MdStage::new(params.clone())));
    }
    let Some(first) = rings.first() else {
        return;
    };
    let other_systems = study.other_compared_rings();
    let mut other_kernels = Vec::new();
    for ring in &other_systems {
        let kernel = study.kernel_params(ring.potential, 0.0, 0.0);
        if !other_kernels.contains(&kernel) {
            other_kernels.push(kernel);
        }
    }
    stages.push(Box::new(CompareStage::new(CompareParams {
        kernel: study.kernel_params(first.potential, 0.0, 0.0),
        thermal_collisions: wide_collisions(study, first.potential).0,
        systems: study.compared_rings(),
        other_kernels,
        other_systems,
    })));
}
