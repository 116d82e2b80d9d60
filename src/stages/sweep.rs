//! `sweep`: the special particle's drift and variance rates for `u'` on a grid
//! (physics.md §3), their Fokker-Planck consistency with relaxation to `f0`,
//! and a detailed-balance table `G(a -> b)` against `G(b -> a)` for nearby
//! velocities (physics.md §8). All from one event set by reweighting; every
//! uncertainty from the spread of randomizations (per-replicate differences, so
//! the correlation of quantities computed from the same events is kept).
//! The Fokker-Planck reading `D1 = (D2' - u D2) / 2` and the balance
//! arithmetic are `kernel::equilibrium`'s; the table gives both sides of
//! each and their difference.

use rayon::prelude::*;
use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::input_events;
use crate::binning::Bins;
use crate::config::SweepParams;
use crate::kernel::equilibrium::{SelfRates, detailed_balance, fokker_planck_check, self_rates};
use crate::kernel::{Draws, Event, Target, self_bin};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};

/// The `sweep` stage for one potential.
pub struct SweepStage {
    params: SweepParams,
}

impl SweepStage {
    /// A sweep stage with resolved parameters.
    pub fn new(params: SweepParams) -> SweepStage {
        SweepStage { params }
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
        let edge = 0.5 * self.params.kernel.window;
        grid.par_iter()
            .map(|&u| self_rates(events, &self.target(u), edge, draws))
            .collect()
    }

    fn rates_table(&self, grid: &[f64], rates: &[SelfRates]) -> Result<Table, StageError> {
        let mut columns: [Vec<f64>; 8] = Default::default();
        for (&u, point) in grid.iter().zip(fokker_planck_check(grid, rates)) {
            let row = [
                u,
                point.drift.mean,
                point.drift.stderr,
                point.variance.mean,
                point.variance.stderr,
                point.predicted_drift.mean,
                point.predicted_drift.stderr,
                point.z,
            ];
            for (column, value) in columns.iter_mut().zip(row) {
                column.push(value);
            }
        }
        let [
            u,
            drift,
            drift_err,
            variance,
            variance_err,
            predicted,
            predicted_err,
            z,
        ] = columns;
        let rate = "rho^2 l v_th";
        Ok(Table::new(
            "rates",
            vec![
                Column::f64("u_prime", "v_th", "velocity of the special particle", u),
                Column::f64(
                    "self_drift",
                    rate,
                    "D1 = d<u - u'>/dt of the special particle (|u - u'| <= window/2)",
                    drift,
                ),
                Column::f64("self_drift_stderr", rate, "standard error", drift_err),
                Column::f64(
                    "self_variance",
                    "rho^2 l v_th",
                    "D2 = d<(u - u')^2>/dt of the special particle",
                    variance,
                ),
                Column::f64(
                    "self_variance_stderr",
                    "rho^2 l v_th",
                    "standard error",
                    variance_err,
                ),
                Column::f64(
                    "fokker_planck_drift",
                    rate,
                    "(dD2/du - u D2) / 2: the drift for which f0 is stationary",
                    predicted,
                ),
                Column::f64(
                    "fokker_planck_drift_stderr",
                    rate,
                    "standard error (finite differences on the grid)",
                    predicted_err,
                ),
                Column::f64(
                    "fokker_planck_z",
                    "1",
                    "(D1 - Fokker-Planck drift) / its standard error (per-replicate differences)",
                    z,
                ),
            ],
        )?
        .with_metadata(
            "ternary.description",
            "drift and variance rates against u', dilute limit".into(),
        ))
    }

    fn balance_table(
        &self,
        events: &[Event],
        draws: &Draws,
        grid: &[f64],
    ) -> Result<Table, StageError> {
        let width = self.params.balance_bin_width;
        let largest = self
            .params
            .balance_separations
            .iter()
            .copied()
            .fold(0.0, f64::max);
        let bins = Bins::for_window(2.0 * largest + 4.0 * width, width);
        let rows: Vec<[f64; 10]> = grid
            .par_iter()
            .flat_map_iter(|&a| {
                self.params
                    .balance_separations
                    .iter()
                    .map(move |&separation| {
                        let steps = (separation / width).round() as usize;
                        let b = a + steps as f64 * width;
                        let self_kernel = |from: f64, k: usize| -> Vec<f64> {
                            self_bin(events, &self.target(from), &bins, k, draws)
                                .iter()
                                .map(|v| v / width)
                                .collect()
                        };
                        let there = self_kernel(a, bins.half_bins + steps);
                        let back = self_kernel(b, bins.half_bins - steps);
                        let balance = detailed_balance(a, b, &there, &back);
                        [
                            a,
                            b,
                            balance.forward.mean,
                            balance.forward.stderr,
                            balance.backward.mean,
                            balance.backward.stderr,
                            balance.ratio.mean,
                            balance.ratio.stderr,
                            balance.expected_ratio,
                            balance.imbalance_z,
                        ]
                    })
            })
            .collect();
        let mut columns: [Vec<f64>; 10] = Default::default();
        for row in rows {
            for (column, value) in columns.iter_mut().zip(row) {
                column.push(value);
            }
        }
        let [
            from,
            to,
            forward,
            forward_err,
            backward,
            backward_err,
            ratio,
            ratio_err,
            expected,
            z,
        ] = columns;
        let unit = "rho^2 l v_th / v_th";
        Ok(Table::new(
            "detailed_balance",
            vec![
                Column::f64("a", "v_th", "initial velocity", from),
                Column::f64("b", "v_th", "final velocity (a plus a whole number of bins)", to),
                Column::f64("G_self_ab", unit, "self kernel G(a -> b), bin centred on b", forward),
                Column::f64("G_self_ab_stderr", unit, "standard error", forward_err),
                Column::f64("G_self_ba", unit, "self kernel G(b -> a)", backward),
                Column::f64("G_self_ba_stderr", unit, "standard error", backward_err),
                Column::f64("ratio", "1", "G(a -> b) / G(b -> a)", ratio),
                Column::f64("ratio_stderr", "1", "standard error (first order, estimates treated as independent)", ratio_err),
                Column::f64("expected_ratio", "1", "f0(b) / f0(a): detailed balance", expected),
                Column::f64("imbalance_z", "1", "(f0(a) G(a->b) - f0(b) G(b->a)) / its standard error (per-replicate differences)", z),
            ],
        )?
        .with_metadata("ternary.description", "detailed balance of the self kernel for nearby velocities".into()))
    }
}

impl Stage for SweepStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("sweep", &self.params.kernel.potential.id())
    }

    fn version(&self) -> u32 {
        3
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["rates", "detailed_balance"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        vec![CollisionsStage::instance(&self.params.collisions)]
    }

    fn work_units(&self) -> u64 {
        2
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let (events, draws, _) = input_events(inputs)?;
        let grid = self.grid();
        let rates = self.rates(&events, &draws, &grid);
        progress.advance(1);
        let balance = self.balance_table(&events, &draws, &grid)?;
        progress.advance(1);
        Ok(vec![self.rates_table(&grid, &rates)?, balance])
    }
}
