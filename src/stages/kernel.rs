//! `kernel`: the dimensionless collision kernel `G(u' -> u)` of one potential at
//! one `u'` and density, reweighted from the `collisions` events and binned with
//! the +-1 rule (physics.md §3), split into self and bath parts, with standard
//! errors from the spread of independent randomizations.

use serde_json::Value;

use crate::binning::Bins;
use crate::config::KernelParams;
use crate::contract::instances;
use crate::contract::readers::input_events;
use crate::contract::{self, Rows};
use crate::kernel::{Histogram, histograms, tail};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `kernel` stage for one potential, `u'` and density.
pub struct KernelStage {
    params: KernelParams,
}

impl KernelStage {
    /// A kernel stage with resolved parameters.
    pub fn new(params: KernelParams) -> KernelStage {
        KernelStage { params }
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for KernelStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::kernel::STAGE, &instances::target(&self.params))
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[
            contract::kernel::TABLE.name,
            contract::kernel::replicates::TABLE.name,
            contract::kernel::log::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![instances::collisions(&self.params.potential.id())]
    }

    fn work_units(&self) -> u64 {
        1
    }

    /// Every event read (1.1 us each on average in the default study,
    /// 2026-12-02: 110 CPU s for its 118 instances);
    /// the kernel and its per-randomization table (the whole and its self
    /// part), one row per bin and per bin and randomization (16, the
    /// default; 20 bytes a row in the default study, 2026-12-02).
    fn cost(&self, inputs: &[Cost]) -> Cost {
        let bins = self.params.window / self.params.bin_width;
        Cost::reading(inputs, 1.1e-6, bins * 17.0, 20.0)
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::kernel::*;
        let (events, draws, failed) = input_events(inputs)?;
        let bins = Bins::for_window(self.params.window, self.params.bin_width);
        let replicates = histograms(&events, &self.params.target(), &bins, &draws);
        let parts = Parts::of(&replicates, &bins);
        let per_bin = |k: usize, part: &[Vec<f64>]| {
            let values: Vec<f64> = part.iter().map(|values| values[k]).collect();
            Estimate::from_replicates(&values)
        };
        let rows: Vec<usize> = (0..bins.len()).collect();
        progress.advance(1);
        let table = Rows::new(&rows)
            .with(U, |&k| self.params.u_prime + bins.centre(k))
            .with(DU, |&k| bins.centre(k))
            .estimate(G, |&k| per_bin(k, &parts.total))
            .estimate(G_SELF, |&k| per_bin(k, &parts.self_part))
            .estimate(G_BATH, |&k| per_bin(k, &parts.bath_part))
            .table(&TABLE)?
            .with_metadata("ternary.events", events.len().to_string())
            .with_metadata("ternary.failed_events", failed.to_string());
        Ok(vec![
            table,
            replicates_table(&parts, &bins)?,
            log_table(&parts, &bins)?,
        ])
    }
}

/// The kernel of every randomization per bin (`[randomization][bin]`,
/// `rho^2 l v_th / v_th`): the whole and its self and bath parts.
struct Parts {
    total: Vec<Vec<f64>>,
    self_part: Vec<Vec<f64>>,
    bath_part: Vec<Vec<f64>>,
}

impl Parts {
    fn of(replicates: &[Histogram], bins: &Bins) -> Parts {
        let per_bin = |part: fn(&Histogram, usize) -> f64| -> Vec<Vec<f64>> {
            replicates
                .iter()
                .map(|h| (0..bins.len()).map(|k| part(h, k) / bins.width).collect())
                .collect()
        };
        Parts {
            total: per_bin(|h, k| h.self_part[k] + h.bath_part[k]),
            self_part: per_bin(|h, k| h.self_part[k]),
            bath_part: per_bin(|h, k| h.bath_part[k]),
        }
    }
}

/// `G` and its self part of every randomization alone: one row per
/// randomization and bin.
fn replicates_table(parts: &Parts, bins: &Bins) -> Result<Table, StageError> {
    use contract::kernel::replicates::*;
    let rows: Vec<(u32, usize)> = (0..parts.total.len() as u32)
        .flat_map(|r| (0..bins.len()).map(move |k| (r, k)))
        .collect();
    Ok(Rows::new(&rows)
        .with(contract::kernel::DU, |&(_, k)| bins.centre(k))
        .with(RANDOMIZATION, |&(r, _)| r)
        .with(G, |&(r, k)| parts.total[r as usize][k])
        .with(G_SELF, |&(r, k)| parts.self_part[r as usize][k])
        .table(&TABLE)?)
}

/// A log-spaced group of bins on one side of `u'` (`-1` below, `+1` above):
/// the side and the members' bin indices, nearest `u'` first.
type Group = (f64, Vec<usize>);

/// The kernel on log-spaced groups of bins ([`tail::sided_log_groups`]), below
/// `u'` then above in ascending `du`: each group's edges, width and mean
/// parts, with errors from the spread of the randomizations' group means.
fn log_table(parts: &Parts, bins: &Bins) -> Result<Table, StageError> {
    use contract::kernel::log::*;
    let centres: Vec<f64> = (0..bins.len()).map(|k| bins.centre(k)).collect();
    let groups: Vec<Group> = tail::sided_log_groups(&centres);
    let edge = |side: f64, k: usize| centres[k] + side * 0.5 * bins.width;
    let inner = |(side, members): &Group| edge(-side, members[0]);
    let outer = |(side, members): &Group| edge(*side, members[members.len() - 1]);
    let mean = |part: &[Vec<f64>], (_, members): &Group| tail::group_mean(part, members);
    Ok(Rows::new(&groups)
        .with(DU, |(_, members)| {
            members.iter().map(|&k| centres[k]).sum::<f64>() / members.len() as f64
        })
        .with(DU_INNER, inner)
        .with(DU_OUTER, outer)
        .with(WIDTH, |group| (outer(group) - inner(group)).abs())
        .with(BINS, |(_, members)| members.len() as u32)
        .estimate(contract::kernel::G, |group| mean(&parts.total, group))
        .estimate(contract::kernel::G_SELF, |group| {
            mean(&parts.self_part, group)
        })
        .estimate(contract::kernel::G_BATH, |group| {
            mean(&parts.bath_part, group)
        })
        .table(&TABLE)?)
}
