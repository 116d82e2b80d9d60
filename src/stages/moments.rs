//! `moments`: drift and variance rates of the perturbation at one `u'` and
//! density (physics.md §3), for the special particle alone (self) and for all
//! particles in the window, as functions of the truncation half-width `X`
//! (`|u - u'| <= X`), so readers see where they converge. Computed from the
//! events without binning; standard errors from the spread of randomizations.
//! `a_n` is the self variance rate at `u' = 0`, dilute limit, `X` = half the window.

use serde::Serialize;
use serde_json::Value;

use crate::config::KernelParams;
use crate::contract::instances;
use crate::contract::readers::input_events;
use crate::contract::{self, Rows};
use crate::kernel::{MomentSums, moments, recombination_rates};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// Truncation half-widths per decade below the window edge.
const TRUNCATIONS_PER_DECADE: u32 = 5;
/// Decades of truncation below the window edge.
const TRUNCATION_DECADES: u32 = 3;
/// Decades of truncation beyond the window edge for a family with a well:
/// its free-atom kicks reach O(v_th) (Lennard-Jones at `theta = 0.1`: 19%
/// of the free scenes kick the special particle by more than 0.1 v_th, none
/// by more than 3 v_th), so its `a(X)` levels off only there.
const BEYOND_WINDOW_DECADES: u32 = 2;

/// The `moments` stage for one potential, `u'` and density.
pub struct MomentsStage {
    params: KernelParams,
    /// Truncations added to the grid (`kernel.truncations`).
    extra: Vec<f64>,
}

/// The key of a moments instance: the kernel's parameters and the added truncations.
#[derive(Serialize)]
struct MomentsKey<'a> {
    #[serde(flatten)]
    kernel: &'a KernelParams,
    truncations: &'a [f64],
}

impl MomentsStage {
    /// A moments stage with resolved parameters and the truncations `extra`
    /// added to its grid.
    pub fn new(params: KernelParams, extra: Vec<f64>) -> MomentsStage {
        MomentsStage { params, extra }
    }

    /// Log-spaced `X` from `10^-3` of the half window to the half window
    /// (and, for a family with a well, on to [`BEYOND_WINDOW_DECADES`]
    /// beyond it) and the added truncations, ascending, then infinity.
    fn truncations(&self) -> Vec<f64> {
        let edge = self.params.edge();
        let below = TRUNCATIONS_PER_DECADE * TRUNCATION_DECADES;
        let above = if self.params.potential.family().has_well() {
            TRUNCATIONS_PER_DECADE * BEYOND_WINDOW_DECADES
        } else {
            0
        };
        let mut grid: Vec<f64> = (0..=below + above)
            .map(|k| {
                let decades = (f64::from(k) - f64::from(below)) / f64::from(TRUNCATIONS_PER_DECADE);
                edge * libm::pow(10f64, decades)
            })
            .chain(self.extra.iter().copied())
            .collect();
        grid.sort_by(f64::total_cmp);
        grid.dedup();
        grid.push(f64::INFINITY);
        grid
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for MomentsStage {
    fn id(&self) -> InstanceId {
        instances::moments(&self.params)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        let key = MomentsKey {
            kernel: &self.params,
            truncations: &self.extra,
        };
        serde_json::to_value(key).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::moments::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![instances::collisions(&self.params.potential.id())]
    }

    fn work_units(&self) -> u64 {
        1
    }

    /// Every event read, 0.36 us each (the default study's 122 instances,
    /// 36 CPU s measured against 103 s at the default 1 us, 2026-12-02).
    fn cost(&self, inputs: &[Cost]) -> Cost {
        Cost::reading(inputs, 0.36e-6, 1e3, 100.0)
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::moments::*;
        let (events, draws, failed) = input_events(inputs)?;
        let truncations = self.truncations();
        let target = self.params.target();
        let sums = moments(&events, &target, &truncations, &draws);
        let recombination =
            Estimate::from_replicates(&recombination_rates(&events, &target, &draws));
        let recombined = events.iter().filter(|e| e.recombined()).count() as u32;
        let rows: Vec<usize> = (0..truncations.len()).collect();
        let sums = &sums;
        let estimate = |part: fn(&MomentSums) -> f64| {
            move |&k: &usize| {
                Estimate::from_replicates(
                    &sums
                        .iter()
                        .map(|replicate| part(&replicate[k]))
                        .collect::<Vec<_>>(),
                )
            }
        };
        progress.advance(1);
        let table = Rows::new(&rows)
            .optional(TRUNCATION, |&k| {
                Some(truncations[k]).filter(|x| x.is_finite())
            })
            .estimate(SELF_DRIFT, estimate(|m| m.self_drift))
            .estimate(SELF_VARIANCE, estimate(|m| m.self_variance))
            .estimate(WINDOW_DRIFT, estimate(|m| m.window_drift))
            .estimate(WINDOW_VARIANCE, estimate(|m| m.window_variance))
            .optional(ENERGY_ERROR_BOUND, |&k| {
                truncations[k]
                    .is_infinite()
                    .then(|| estimate(|m| m.energy_change)(&k).mean)
            })
            .estimate(RECOMBINATION_RATE, |_| recombination)
            .with(RECOMBINED_EVENTS, |_| recombined)
            .with(EVENTS, |_| events.len() as u32)
            .with(FAILED_EVENTS, |_| failed as u32)
            .table(&TABLE)?;
        Ok(vec![table])
    }
}
