//! The study's stages, one per file: thin adapters between the pipeline and the
//! physics. [`plan`] is the one place where stages are registered.

pub mod collisions;
pub mod compare;
pub mod convergence;
pub mod evolve;
pub mod figures;
pub mod fit;
pub mod gases;
pub mod kernel;
pub mod launches;
pub mod md;
pub mod moments;
pub mod paper;
pub mod scan;
pub mod sweep;
pub mod table;

use crate::config::{CollisionsParams, Study};
use crate::contract::instances;
use crate::pipeline::Stage;

/// Registers the collisions named `name` after the launch set they
/// integrate: an already registered set with the same parameters (e.g. the
/// main set, for a re-integration at another tolerance), else a new one
/// named like them.
fn push_collisions(stages: &mut Vec<Box<dyn Stage>>, params: CollisionsParams, name: String) {
    let launches = params.launches();
    let wanted = serde_json::to_value(&launches).unwrap_or_default();
    let existing = stages.iter().find_map(|stage| {
        let id = stage.id();
        (id.stage == crate::contract::launches::STAGE && stage.params() == wanted)
            .then(|| id.instance.clone())
    });
    let launches_name = existing.unwrap_or_else(|| {
        stages.push(Box::new(launches::LaunchesStage::new(
            launches,
            name.clone(),
        )));
        name.clone()
    });
    stages.push(Box::new(collisions::CollisionsStage::new(
        params,
        name,
        launches_name,
    )));
}

/// Every stage instance of a study, in topological order.
pub fn plan(study: &Study) -> Vec<Box<dyn Stage>> {
    let mut stages: Vec<Box<dyn Stage>> = Vec::new();
    let potentials = study.potentials();
    let truncations = &study.config.kernel.truncations;
    for &potential in &potentials {
        stages.push(Box::new(scan::ScanStage::new(study.scan_params(potential))));
        push_collisions(
            &mut stages,
            study.collisions_params(potential),
            potential.id(),
        );
        for (u_prime, density) in study.kernel_targets() {
            let params = study.kernel_params(potential, u_prime, density);
            stages.push(Box::new(kernel::KernelStage::new(params)));
            stages.push(Box::new(moments::MomentsStage::new(
                params,
                truncations.clone(),
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
        if let (true, (name, Some(wide))) = (
            sweep.is_some() || evolve.is_some() || compared,
            study.wide_collisions(potential),
        ) {
            push_collisions(&mut stages, wide, name);
        }
        if let Some(params) = sweep {
            stages.push(Box::new(sweep::SweepStage::new(params)));
        }
        if let Some(params) = evolve {
            stages.push(Box::new(evolve::EvolveStage::new(params)));
        }
    }
    let gases = study.gases();
    for gas in &gases {
        let dense = study.kernel_params(gas.potential, 0.0, gas.scaled_density());
        let id = instances::moments(&dense);
        if !stages.iter().any(|stage| stage.id() == id) {
            stages.push(Box::new(moments::MomentsStage::new(
                dense,
                truncations.clone(),
            )));
        }
    }
    // The kernel at each collapse ring's own rho l (figure kernels_density):
    // the literal algorithm's finite-density factor, one instance per ring.
    for ring in study.collapse_rings() {
        let dense = study.kernel_params(ring.potential, 0.0, ring.scaled_density());
        let stage = kernel::KernelStage::new(dense);
        if !stages.iter().any(|other| other.id() == stage.id()) {
            stages.push(Box::new(stage));
        }
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
    if let Some((params, variants)) = study.convergence() {
        for variant in variants {
            let name = convergence::ConvergenceStage::tolerance_instance(
                &variant.potential.id(),
                variant.engine.tolerance,
            );
            push_collisions(&mut stages, variant, name);
        }
        stages.push(Box::new(convergence::ConvergenceStage::new(params)));
    }
    let rings = study.md_params();
    for params in &rings {
        stages.push(Box::new(md::MdStage::new(params.clone())));
    }
    if let Some(first) = rings.first() {
        let kernel = study.kernel_params(first.potential, 0.0, 0.0);
        let systems = study.compared_rings();
        let (thermal_collisions, _) = study.wide_collisions(first.potential);
        let other_systems = study.other_compared_rings();
        let mut other_kernels: Vec<_> = Vec::new();
        for ring in &other_systems {
            let kernel = study.kernel_params(ring.potential, 0.0, 0.0);
            if !other_kernels.contains(&kernel) {
                other_kernels.push(kernel);
            }
        }
        stages.push(Box::new(compare::CompareStage::new(
            compare::CompareParams {
                kernel,
                thermal_collisions,
                systems,
                other_kernels,
                other_systems,
            },
        )));
    }
    let rows = potentials
        .iter()
        .map(|&p| study.kernel_params(p, 0.0, 0.0))
        .collect();
    stages.push(Box::new(table::TableStage::new(rows)));
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
