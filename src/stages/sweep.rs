//! `sweep`: the special particle's drift and variance rates for `u'` on a grid
//! (physics.md §3), their Fokker-Planck consistency with relaxation to `f0`,
//! and a detailed-balance table `G(a -> b)` against `G(b -> a)` for nearby
//! velocities (physics.md §8). All from one event set by reweighting; every
//! uncertainty from the spread of randomizations (per-replicate differences, so
//! the correlation of quantities computed from the same events is kept).
//! The Fokker-Planck reading `D1 = (D2' - u D2) / 2` and the balance
//! arithmetic are `kernel::equilibrium`'s; the table gives both sides of
//! each and their difference. For a potential with a well, the rate of
//! three-body recombination against `u'` and averaged over thermal `u'`,
//! and the distribution of the bound pairs' binding energy
//! (`kernel::binding`).

use std::collections::HashMap;

use rayon::prelude::*;
use serde_json::Value;

use crate::analysis::thermal_average;
use crate::binning::Bins;
use crate::config::SweepParams;
use crate::contract::instances;
use crate::contract::readers::input_events;
use crate::contract::{self, Rows};
use crate::kernel::binding::{BindingBins, BindingSums, binding_sums};
use crate::kernel::equilibrium::{
    Balance, FokkerPlanckPoint, JointBalance, SelfRates, balance_between, fokker_planck_check,
    joint_balance, joint_stationarity, self_rates,
};
use crate::kernel::{Draws, Event, Target, self_bin_feeders};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};

/// The `sweep` stage for one potential.
pub struct SweepStage {
    params: SweepParams,
    /// The collisions instance it reads (reaching every `u'` of its grid).
    collisions: String,
}

impl SweepStage {
    /// A sweep stage with resolved parameters, reading the collisions
    /// named `collisions`.
    pub fn new(params: SweepParams, collisions: String) -> SweepStage {
        SweepStage { params, collisions }
    }

    fn grid(&self) -> Vec<f64> {
        let p = &self.params;
        let last = f64::from(p.points - 1);
        (0..p.points)
            .map(|k| p.u_prime_min + (p.u_prime_max - p.u_prime_min) * f64::from(k) / last)
            .collect()
    }

    fn target(&self, u_prime: f64) -> Target {
        Target {
            u_prime,
            density: 0.0,
            launch_length: self.params.kernel.launch_length,
            kick_floor: self.params.kernel.kick_floor,
        }
    }

    /// Self drift and variance rates (within half the window) per replicate at every grid point.
    fn rates(&self, events: &[Event], draws: &Draws, grid: &[f64]) -> Vec<SelfRates> {
        let edge = self.params.kernel.edge();
        grid.par_iter()
            .map(|&u| self_rates(events, &self.target(u), edge, draws))
            .collect()
    }

    /// The recombination sums ([`binding_sums`]) at every grid point, and
    /// averaged over thermal `u'` ([`thermal_average`], per replicate: the
    /// points share scenes). Where the average's nodes are grid points (on
    /// the default grid, all of them) it takes the grid's sums, bit for bit
    /// the ones it would compute.
    fn recombination_sums(
        &self,
        events: &[Event],
        draws: &Draws,
        grid: &[f64],
        bins: &BindingBins,
    ) -> (Vec<BindingSums>, BindingSums) {
        let at = |u: f64| binding_sums(events, &self.target(u), draws, bins);
        let per_point: Vec<BindingSums> = grid.par_iter().map(|&u| at(u)).collect();
        let average = thermal_average(|u| match grid.iter().position(|&node| node == u) {
            Some(k) => per_point[k].flat(),
            None => at(u).flat(),
        });
        (per_point, BindingSums::from_flat(&average, bins))
    }

    /// The recombination rate and the mean binding energy of its pairs at
    /// every grid point, then averaged over thermal `u'` (a null `u'`).
    fn recombination_table(
        grid: &[f64],
        per_point: &[BindingSums],
        thermal: &BindingSums,
    ) -> Result<Table, StageError> {
        use contract::sweep::recombination::*;
        let rows: Vec<(Option<f64>, &BindingSums)> = grid
            .iter()
            .map(|&u| Some(u))
            .zip(per_point)
            .chain([(None, thermal)])
            .collect();
        Ok(Rows::new(&rows)
            .optional(U_PRIME, |(u, _)| *u)
            .estimate(RATE_COLUMN, |(_, sums)| sums.rate())
            .estimate(MEAN_BINDING, |(_, sums)| sums.mean_binding())
            .table(&TABLE)?)
    }

    /// The thermally averaged recombination rate per unit binding energy on `bins`.
    fn binding_table(bins: &BindingBins, thermal: &BindingSums) -> Result<Table, StageError> {
        use contract::sweep::binding::*;
        let rows: Vec<usize> = (0..bins.count).collect();
        Ok(Rows::new(&rows)
            .with(BINDING_LOW, |&k| bins.edge(k))
            .with(BINDING_HIGH, |&k| bins.edge(k + 1))
            .estimate(RATE_DENSITY, |&k| thermal.density(bins, k))
            .table(&TABLE)?)
    }

    fn rates_table(&self, grid: &[f64], rates: &[SelfRates]) -> Result<Table, StageError> {
        use contract::sweep::rates::*;
        let rows: Vec<(f64, FokkerPlanckPoint)> = grid
            .iter()
            .copied()
            .zip(fokker_planck_check(grid, rates))
            .collect();
        Ok(Rows::new(&rows)
            .with(U_PRIME, |(u, _)| *u)
            .estimate(SELF_DRIFT, |(_, p)| p.drift)
            .estimate(SELF_VARIANCE, |(_, p)| p.variance)
            .estimate(FOKKER_PLANCK_DRIFT, |(_, p)| p.predicted_drift)
            .with(FOKKER_PLANCK_Z, |(_, p)| p.z)
            .table(&TABLE)?)
    }

    /// The joint test of stationarity over the independent half of the grid.
    fn stationarity_table(grid: &[f64], rates: &[SelfRates]) -> Result<Table, StageError> {
        use contract::sweep::stationarity::*;
        let joint = [joint_stationarity(grid, rates)];
        Ok(Rows::new(&joint)
            .with(POINTS, |j| j.points as u32)
            .estimate(RELATIVE_RESIDUAL, |j| j.relative_residual)
            .with(JOINT_Z, |j| j.relative_residual.z())
            .with(LARGEST_SHARE, |j| j.largest_share)
            .table(&TABLE)?)
    }

    /// The detailed-balance pairs and their joint tests.
    fn balance_tables(
        &self,
        events: &[Event],
        draws: &Draws,
        grid: &[f64],
    ) -> Result<[Table; 2], StageError> {
        use contract::sweep::detailed_balance::*;
        let width = self.params.balance_bin_width;
        let largest = self
            .params
            .balance_separations
            .iter()
            .copied()
            .fold(0.0, f64::max);
        let bins = Bins::for_window(2.0 * largest + 4.0 * width, width);
        // The self kicks landing in a bin do not depend on u': each bin's
        // feeders are found once for the whole grid.
        let kick_floor = self.params.kernel.kick_floor;
        let feeders: HashMap<usize, Vec<Event>> = self
            .params
            .balance_separations
            .iter()
            .flat_map(|&separation| {
                let steps = (separation / width).round() as usize;
                [bins.half_bins + steps, bins.half_bins - steps]
            })
            .map(|k| (k, self_bin_feeders(events, &bins, k, kick_floor)))
            .collect();
        let feeders = &feeders;
        let rows: Vec<(f64, f64, Balance)> = grid
            .par_iter()
            .flat_map_iter(|&a| {
                self.params
                    .balance_separations
                    .iter()
                    .map(move |&separation| {
                        let steps = (separation / width).round() as usize;
                        let fed = (
                            feeders[&(bins.half_bins + steps)].as_slice(),
                            feeders[&(bins.half_bins - steps)].as_slice(),
                        );
                        let balance =
                            balance_between(fed, draws, &bins, (a, steps), |u| self.target(u));
                        (a, a + steps as f64 * width, balance)
                    })
            })
            .collect();
        let table = Rows::new(&rows)
            .with(A, |(a, ..)| *a)
            .with(B, |(_, b, _)| *b)
            .estimate(G_SELF_AB, |(.., balance)| balance.forward)
            .estimate(G_SELF_BA, |(.., balance)| balance.backward)
            .estimate(RATIO, |(.., balance)| balance.ratio)
            .with(EXPECTED_RATIO, |(.., balance)| balance.expected_ratio)
            .with(IMBALANCE_Z, |(.., balance)| balance.imbalance_z)
            .with(LARGEST_SHARE, |(.., balance)| balance.largest_share)
            .table(&TABLE)?;
        Ok([table, self.joint_tests(&rows)?])
    }

    /// One joint test per separation over its pairs that are evidence.
    fn joint_tests(&self, rows: &[(f64, f64, Balance)]) -> Result<Table, StageError> {
        use contract::sweep::balance_tests::*;
        let width = self.params.balance_bin_width;
        let tests: Vec<(f64, u32, u32, JointBalance)> = self
            .params
            .balance_separations
            .iter()
            .map(|&separation| {
                let distance = (separation / width).round() * width;
                // Every scene enters with its mirror image, so a pair at a > 0
                // repeats the evidence of its mirror at -a: one half counts.
                let pairs: Vec<&Balance> = rows
                    .iter()
                    .filter(|(a, b, _)| *a <= 0.0 && ((b - a) - distance).abs() < 0.5 * width)
                    .map(|(.., balance)| balance)
                    .collect();
                let counted: Vec<&Balance> =
                    pairs.iter().copied().filter(|p| !p.dominated()).collect();
                let joint = joint_balance(counted.iter().copied());
                (distance, pairs.len() as u32, counted.len() as u32, joint)
            })
            .collect();
        Ok(Rows::new(&tests)
            .with(SEPARATION, |(s, ..)| *s)
            .with(PAIRS, |(_, pairs, ..)| *pairs)
            .with(COUNTED, |(_, _, counted, _)| *counted)
            .estimate(JOINT_IMBALANCE, |(.., joint)| joint.imbalance)
            .with(JOINT_Z, |(.., joint)| joint.imbalance.z())
            .with(JOINT_LARGEST_SHARE, |(.., joint)| joint.largest_share)
            .table(&TABLE)?)
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for SweepStage {
    fn id(&self) -> InstanceId {
        instances::sweep(&self.params.kernel.potential)
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[
            contract::sweep::rates::TABLE.name,
            contract::sweep::stationarity::TABLE.name,
            contract::sweep::detailed_balance::TABLE.name,
            contract::sweep::balance_tests::TABLE.name,
            contract::sweep::recombination::TABLE.name,
            contract::sweep::binding::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![instances::collisions(&self.collisions)]
    }

    fn work_units(&self) -> u64 {
        2
    }

    /// Every event read, 1.9-3.7 us each (2.5 us over the default study's
    /// sweeps, 2026-12-01); a small table.
    fn cost(&self, inputs: &[Cost]) -> Cost {
        Cost::reading(inputs, 2.5e-6, 200.0, 100.0)
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let (events, draws, _) = input_events(inputs)?;
        let grid = self.grid();
        let rates = self.rates(&events, &draws, &grid);
        progress.advance(1);
        let [balance, tests] = self.balance_tables(&events, &draws, &grid)?;
        progress.advance(1);
        let bins = BindingBins::of_well(self.params.kernel.potential.well_depth());
        let (per_point, thermal) = self.recombination_sums(&events, &draws, &grid, &bins);
        Ok(vec![
            self.rates_table(&grid, &rates)?,
            Self::stationarity_table(&grid, &rates)?,
            balance,
            tests,
            Self::recombination_table(&grid, &per_point, &thermal)?,
            Self::binding_table(&bins, &thermal)?,
        ])
    }
}
