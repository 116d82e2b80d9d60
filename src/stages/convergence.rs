//! `convergence`: `a_n` of one potential under changes of the numerical
//! settings, to show the defaults are converged rather than assert it: the
//! density `rho l` of the literal algorithm's `exp(-r |delay|)` (a physical
//! finite-density correction, tabulated), a bound on the arrival offset
//! `|tau| <= B T`, the integrator tolerance (the leading share of every
//! randomization's and stratum's launch pairs re-integrated, compared with
//! the default on the same pairs), and the bin width when `a_n` is taken from
//! the binned kernel.
//! Every shift is a per-replicate difference against the default, so the
//! shared randomness cancels and its standard error says whether it is resolved;
//! `shift_over_error` compares it with the default's statistical error.

use std::collections::HashSet;

use serde_json::Value;

use crate::binning::Bins;
use crate::config::ConvergenceParams;
use crate::contract::instances;
use crate::contract::readers::collision_events;
use crate::contract::{self, Rows};
use crate::kernel::equilibrium::self_rates;
use crate::kernel::{Draws, Event, Target, self_histograms};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `convergence` stage.
pub struct ConvergenceStage {
    params: ConvergenceParams,
}

impl ConvergenceStage {
    /// A convergence stage with resolved parameters.
    pub fn new(params: ConvergenceParams) -> ConvergenceStage {
        ConvergenceStage { params }
    }

    /// `a_n` per replicate from unbinned self kicks within half the window.
    fn self_variance(&self, events: &[Event], draws: &Draws, target: &Target) -> Vec<f64> {
        self_rates(events, target, self.params.kernel.edge(), draws).variance
    }

    /// `a_n` per replicate from the binned self kernel: `sum_k G_self,k x_k^2 dx`.
    fn binned_self_variance(&self, events: &[Event], draws: &Draws, width: f64) -> Vec<f64> {
        let bins = Bins::for_window(self.params.kernel.window, width);
        self_histograms(events, &self.params.kernel.target(), &bins, draws)
            .iter()
            .map(|h| {
                (0..bins.len())
                    .map(|k| h.self_part[k] * bins.centre(k).powi(2))
                    .sum()
            })
            .collect()
    }
}

/// One row: a setting, its `a_n` per replicate, and the default's on the
/// share of the launch pairs a tolerance re-integrates (`None`: on all of
/// them, the baseline).
struct Row {
    parameter: &'static str,
    value: f64,
    replicates: Vec<f64>,
    default: Option<Vec<f64>>,
}

/// The events of `events` whose launch pair (randomization, stratum, point)
/// is among those of `subset`.
fn same_launches(events: &[Event], subset: &[Event]) -> Vec<Event> {
    let pairs: HashSet<(u32, u32, u32)> = subset.iter().map(launch_of).collect();
    events
        .iter()
        .filter(|e| pairs.contains(&launch_of(e)))
        .copied()
        .collect()
}

/// The launch pair of an event.
fn launch_of(event: &Event) -> (u32, u32, u32) {
    (event.randomization, event.stratum.index(), event.point)
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for ConvergenceStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(
            contract::convergence::STAGE,
            &self.params.kernel.potential.id(),
        )
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::convergence::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let id = self.params.kernel.potential.id();
        let mut inputs = vec![instances::collisions(&id)];
        inputs.extend(
            self.params
                .tolerances
                .iter()
                .map(|&t| instances::collisions(&instances::tolerance_collisions(&id, t))),
        );
        inputs
    }

    fn work_units(&self) -> u64 {
        4
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::convergence::parameter::*;
        let (events, draws, _) = collision_events(&inputs[0])?;
        let target = self.params.kernel.target();
        let baseline = self.self_variance(&events, &draws, &target);
        let mut rows = vec![Row {
            parameter: DEFAULT,
            value: f64::NAN,
            replicates: baseline.clone(),
            default: None,
        }];
        for &density in &self.params.densities {
            let dense = Target { density, ..target };
            rows.push(Row {
                parameter: DENSITY,
                value: density,
                replicates: self.self_variance(&events, &draws, &dense),
                default: None,
            });
        }
        progress.advance(1);
        for &bound in &self.params.offset_bounds {
            // Dropping scenes beyond the bound while counting them as drawn
            // integrates over |tau| <= bound * T only.
            let kept: Vec<Event> = events
                .iter()
                .filter(|e| e.offset.abs() <= bound * (1.0 / e.u2.abs() + 1.0 / e.u3.abs()))
                .copied()
                .collect();
            rows.push(Row {
                parameter: OFFSET_BOUND,
                value: bound,
                replicates: self.self_variance(&kept, &draws, &target),
                default: None,
            });
        }
        progress.advance(1);
        for (input, &tolerance) in inputs[1..].iter().zip(&self.params.tolerances) {
            let (again, again_draws, _) = collision_events(input)?;
            let same = same_launches(&events, &again);
            rows.push(Row {
                parameter: TOLERANCE,
                value: tolerance,
                replicates: self.self_variance(&again, &again_draws, &target),
                default: Some(self.self_variance(&same, &Draws::count(&same), &target)),
            });
        }
        progress.advance(1);
        for &width in &self.params.bin_widths {
            rows.push(Row {
                parameter: BIN_WIDTH,
                value: width,
                replicates: self.binned_self_variance(&events, &draws, width),
                default: None,
            });
        }
        progress.advance(1);
        Ok(vec![convergence_table(&rows, &baseline)?])
    }
}

fn convergence_table(rows: &[Row], baseline: &[f64]) -> Result<Table, StageError> {
    use contract::convergence::*;
    let default = Estimate::from_replicates(baseline);
    let shifts: Vec<(&Row, Estimate)> = rows
        .iter()
        .map(|row| {
            let differences: Vec<f64> = row
                .replicates
                .iter()
                .zip(row.default.as_deref().unwrap_or(baseline))
                .map(|(a, b)| a - b)
                .collect();
            (row, Estimate::from_replicates(&differences))
        })
        .collect();
    Ok(Rows::new(&shifts)
        .with(PARAMETER, |(r, _)| r.parameter.to_string())
        .with(VALUE, |(r, _)| r.value)
        .with(UNIT, |(r, _)| parameter::unit(r.parameter).to_string())
        .estimate(A_N, |(r, _)| Estimate::from_replicates(&r.replicates))
        .estimate(SHIFT, |(_, shift)| *shift)
        .with(SHIFT_OVER_ERROR, |(_, shift)| shift.mean / default.stderr)
        .table(&TABLE)?)
}
