//! The study's stages, one per file: thin adapters between the pipeline and the
//! physics. [`plan`] is the one place where stages are registered.

pub mod scan;

use crate::config::Study;
use crate::pipeline::Stage;

/// Every stage instance of a study, in topological order.
pub fn plan(study: &Study) -> Vec<Box<dyn Stage>> {
    let mut stages: Vec<Box<dyn Stage>> = Vec::new();
    for potential in study.potentials() {
        stages.push(Box::new(scan::ScanStage::new(study.scan_params(potential))));
    }
    stages
}
