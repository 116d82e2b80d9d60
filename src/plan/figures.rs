//! Which figures a study draws: every figure kind's own plan (each kind is a
//! file of `src/figures/` and says when a study draws it, from which
//! instances), the figures by topic.

use std::collections::HashSet;

use crate::config::Study;
use crate::figures::{Drawn, PLANS};
use crate::pipeline::{InstanceId, Stage};
use crate::stages::figures::FiguresStage;

/// The figures of a study whose inputs `plan` computes, by topic and within
/// one by file: each kind's plan decides ([`crate::figures::Plan`]).
pub(super) fn figure_stages(study: &Study, plan: &[Box<dyn Stage>]) -> Vec<FiguresStage> {
    let planned: HashSet<InstanceId> = plan.iter().map(|s| s.id()).collect();
    let present = |id: &InstanceId| planned.contains(id);
    let mut drawn: Vec<Drawn> = PLANS
        .iter()
        .flat_map(|kind| kind(study, &present))
        .collect();
    drawn.sort_by_key(|figure| figure.figure.topic());
    drawn.into_iter().map(FiguresStage::new).collect()
}
