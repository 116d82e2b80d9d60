//! `moments`: drift and variance rates of the perturbation at one `u'` and
//! density (physics.md §3), for the special particle alone (self) and for all
//! particles in the window, as functions of the truncation half-width `X`
//! (`|u - u'| <= X`), so readers see where they converge. Computed from the
//! events without binning; standard errors from the spread of randomizations.
//! `a_n` is the self variance rate at `u' = 0`, dilute limit, `X` = half the window.

use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::{input_events, target_instance, target_of};
use crate::config::KernelParams;
use crate::kernel::{MomentSums, moments};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// Truncation half-widths per decade below the window edge.
const TRUNCATIONS_PER_DECADE: u32 = 5;
/// Decades of truncation below the window edge.
const TRUNCATION_DECADES: u32 = 3;

/// Name, unit, description and accessor of one moment column.
type MomentColumn = (
    &'static str,
    &'static str,
    &'static str,
    fn(&MomentSums) -> f64,
);

/// The `moments` stage for one potential, `u'` and density.
pub struct MomentsStage {
    params: KernelParams,
}

impl MomentsStage {
    /// A moments stage with resolved parameters.
    pub fn new(params: KernelParams) -> MomentsStage {
        MomentsStage { params }
    }

    /// Instance id for kernel parameters.
    pub fn instance(params: &KernelParams) -> InstanceId {
        InstanceId::new("moments", &target_instance(params))
    }

    /// Log-spaced `X` from `10^-3` of the half window to the half window, then infinity.
    fn truncations(&self) -> Vec<f64> {
        let edge = 0.5 * self.params.window;
        let count = TRUNCATIONS_PER_DECADE * TRUNCATION_DECADES;
        let mut grid: Vec<f64> = (0..=count)
            .map(|k| edge * 10f64.powf(-f64::from(count - k) / f64::from(TRUNCATIONS_PER_DECADE)))
            .collect();
        grid.push(f64::INFINITY);
        grid
    }
}

impl Stage for MomentsStage {
    fn id(&self) -> InstanceId {
        MomentsStage::instance(&self.params)
    }

    fn version(&self) -> u32 {
        2
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["moments"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![CollisionsStage::instance(&self.params.potential.id())]
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let (events, draws, failed) = input_events(inputs)?;
        let truncations = self.truncations();
        let sums = moments(&events, &target_of(&self.params), &truncations, &draws);
        let estimate = |k: usize, part: fn(&MomentSums) -> f64| {
            Estimate::from_replicates(
                &sums
                    .iter()
                    .map(|replicate| part(&replicate[k]))
                    .collect::<Vec<_>>(),
            )
        };
        let parts: [MomentColumn; 4] = [
            (
                "self_drift",
                "rho^2 l v_th",
                "drift rate d<u - u'>/dt of the special particle",
                |m| m.self_drift,
            ),
            (
                "self_variance",
                "rho^2 l v_th",
                "variance rate d<(u - u')^2>/dt of the special particle (a_n at u' = 0)",
                |m| m.self_variance,
            ),
            (
                "window_drift",
                "rho^2 l v_th",
                "drift rate of all particles within the truncation",
                |m| m.window_drift,
            ),
            (
                "window_variance",
                "rho^2 l v_th",
                "variance rate of all particles within the truncation",
                |m| m.window_variance,
            ),
        ];
        let mut columns = vec![Column::f64(
            "truncation",
            "v_th",
            "half-width X: only |u - u'| <= X counts (inf: no truncation)",
            truncations.clone(),
        )];
        for (name, unit, description, part) in parts {
            let values: Vec<Estimate> = (0..truncations.len()).map(|k| estimate(k, part)).collect();
            columns.push(Column::f64(
                name,
                unit,
                description,
                values.iter().map(|e| e.mean).collect(),
            ));
            columns.push(Column::f64(
                &format!("{name}_stderr"),
                unit,
                "standard error from the spread of randomizations",
                values.iter().map(|e| e.stderr).collect(),
            ));
        }
        let rows = truncations.len();
        columns.push(Column::u32(
            "events",
            "1",
            "scenes drawn",
            vec![events.len() as u32; rows],
        ));
        columns.push(Column::u32(
            "failed_events",
            "1",
            "scenes that failed (counted as drawn, contributing nothing)",
            vec![failed as u32; rows],
        ));
        progress.advance(1);
        let table = Table::new("moments", columns)?.with_metadata(
            "ternary.description",
            "drift and variance rates against truncation, units of rho^2 l v_th".into(),
        );
        Ok(vec![table])
    }
}
