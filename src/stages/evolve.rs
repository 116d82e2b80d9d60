//! `evolve`: `h(u, t)` from `delta(u - u')` (physics.md §4) three ways, with
//! jackknife uncertainties over the Monte Carlo randomizations:
//!
//! * early times: the translation-invariant kernel `G(u' -> u' + x)` on the
//!   kernel's fine bins, evolved exactly in Fourier space (`early_evolution`,
//!   `early_summary`, with the closed-form cumulants `t kappa_p` as a check);
//! * up to several `1/Gamma`: the full `u'`-dependent master equation on a
//!   velocity grid spanning the Maxwellian (`evolution`, `evolution_summary`),
//!   for the linearized operator (`full`: conserves number, momentum and
//!   energy, relaxes to `f0 (1 + u u' + (u'^2 - 1)(u^2 - 1)/2)`), for the
//!   special particle alone (`tagged`: relaxes to `f0`), and for the
//!   Fokker-Planck equation of the tagged variance rate in detailed-balance
//!   form. The generators are the Dirichlet forms of the scenes
//!   (`evolve::operator::balanced_generators`, as the `spectrum` stage's
//!   default): symmetric under `f0`, negative semi-definite and with exact
//!   invariants for every sample, so `f0` is stationary and the relative
//!   entropy cannot rise, by construction.
//!
//! Times are given in `1/Gamma` (`Gamma` = the special particle's variance
//! rate at `u'`, from the same events: `a_n` at `u' = 0`) or in ns for a gas;
//! every table carries both and the scaled time `t rho^2 l v_th`.
//!
//! The evolution itself lives in `evolve::early` and `evolve::processes`;
//! this stage reads the events, calls them and writes the tables.

use serde_json::Value;

use crate::binning::Bins;
use crate::config::EvolveParams;
use crate::contract::instances;
use crate::contract::readers::collision_events;
use crate::contract::{self, Rows};
use crate::evolve::convolution;
use crate::evolve::early::EarlyEvolution;
use crate::evolve::grid::VelocityGrid;
use crate::evolve::operator::balanced_generators;
use crate::evolve::processes::{GridEvolution, Process, ProcessMoments};
use crate::kernel::equilibrium::self_rates;
use crate::kernel::{Draws, Event};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Cost, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `evolve` stage.
pub struct EvolveStage {
    params: EvolveParams,
    /// The collisions instance of the grid kernel.
    wide_collisions: String,
}

/// One output time in its three units.
#[derive(Clone, Copy, Debug)]
struct Moment {
    /// `t Gamma`.
    gamma: f64,
    /// `t rho^2 l v_th`.
    scaled: f64,
    /// ns, NaN when given in `1/Gamma`.
    ns: f64,
}

impl EvolveStage {
    /// An evolve stage with resolved parameters, reading the potential's
    /// main collisions (the early, translation-invariant kernel) and those
    /// named `wide_collisions` (the grid kernel: a launch mixture reaching
    /// the whole grid).
    pub fn new(params: EvolveParams, wide_collisions: String) -> EvolveStage {
        EvolveStage {
            params,
            wide_collisions,
        }
    }

    /// The special particle's variance rate at `u'` (within half the window),
    /// `rho^2 l v_th`: `Gamma` in scaled units.
    fn gamma(&self, events: &[Event], draws: &Draws) -> f64 {
        let target = self.params.kernel.target();
        let rates = self_rates(events, &target, self.params.kernel.edge(), draws);
        Estimate::from_replicates(&rates.variance).mean
    }

    /// Every output time, ascending in scaled time.
    fn schedule(&self, gamma: f64, early: bool) -> Vec<Moment> {
        let given = if early {
            &self.params.early_times
        } else {
            &self.params.times
        };
        let mut moments: Vec<Moment> = given
            .iter()
            .map(|&t| Moment {
                gamma: t,
                scaled: t / gamma,
                ns: f64::NAN,
            })
            .collect();
        if let Some(physical) = &self.params.physical {
            for (&ns, &scaled) in physical.times_ns.iter().zip(&physical.times_scaled) {
                moments.push(Moment {
                    gamma: scaled * gamma,
                    scaled,
                    ns,
                });
            }
        }
        moments.sort_by(|a, b| a.scaled.total_cmp(&b.scaled));
        moments
    }

    /// The `early_evolution` and `early_summary` tables.
    fn early(
        &self,
        events: &[Event],
        draws: &Draws,
        schedule: &[Moment],
    ) -> Result<Vec<Table>, StageError> {
        let kernel = &self.params.kernel;
        let bins = Bins::for_window(kernel.window, kernel.bin_width);
        let rates = convolution::replicated_kernel(events, draws, &kernel.target(), &bins);
        let times: Vec<f64> = schedule.iter().map(|m| m.scaled).collect();
        let rebin = self.params.early_rebin as usize;
        let evolution =
            EarlyEvolution::new(&rates, bins.width, &times, rebin, self.params.early_range);
        let offsets = evolution.offsets();
        let mut h_rows = Vec::new();
        let mut summary = Vec::new();
        for (k, &at) in schedule.iter().enumerate() {
            let density = evolution.density(k);
            h_rows.extend(
                offsets
                    .iter()
                    .zip(density)
                    .map(|(&x, h)| EarlyBin { at, x, h }),
            );
            summary.push((at, evolution.moments(k, at.scaled)));
        }
        let h_table = {
            use contract::evolve::early_evolution::*;
            with_times(Rows::new(&h_rows), |r| r.at)
                .with(DU, |r| r.x)
                .with(BIN_CENTRE, |r| r.x + kernel.u_prime)
                .estimate(H, |r| r.h)
                .table(&TABLE)?
        };
        let summary_table = {
            use contract::evolve::early_summary::*;
            with_times(Rows::new(&summary), |r| r.0)
                .estimate(NUMBER, |r| r.1.number)
                .with(NUMBER_CLOSED_FORM, |r| r.1.number_closed.mean)
                .estimate(MEAN, |r| r.1.mean)
                .estimate(VARIANCE, |r| r.1.variance)
                .estimate(VARIANCE_CLOSED_FORM, |r| r.1.variance_closed)
                .estimate(EXCESS_KURTOSIS, |r| r.1.kurtosis)
                .estimate(EXCESS_KURTOSIS_CLOSED_FORM, |r| r.1.kurtosis_closed)
                .table(&TABLE)?
        };
        Ok(vec![h_table, summary_table])
    }

    /// The `evolution` and `evolution_summary` tables.
    fn grid_evolution(
        &self,
        events: &[Event],
        draws: &Draws,
        schedule: &[Moment],
        progress: &Progress,
    ) -> Result<Vec<Table>, StageError> {
        let p = &self.params;
        let grid = VelocityGrid::covering(p.velocity_range, p.grid_step);
        let start = grid.node_of(p.kernel.u_prime).ok_or_else(|| {
            StageError::Input(format!("u' = {} is no grid node", p.kernel.u_prime))
        })?;
        let (generators, _) =
            balanced_generators(events, draws, &grid, p.kernel.kick_floor, start, |done| {
                progress.advance(done as u64);
            });
        let times: Vec<f64> = schedule.iter().map(|m| m.scaled).collect();
        let evolution = GridEvolution::new(&generators, &grid, start, p.kernel.u_prime, &times)
            .map_err(|error| StageError::Input(format!("diagonalizing the generator: {error}")))?;
        progress.advance(1);
        let processes = &evolution.processes;
        Ok(vec![
            self.state_table(&grid, schedule, processes)?,
            self.summary_table(&grid, schedule, processes)?,
        ])
    }

    fn state_table(
        &self,
        grid: &VelocityGrid,
        schedule: &[Moment],
        processes: &[Process; 3],
    ) -> Result<Table, StageError> {
        use contract::evolve::evolution::*;
        let per_node = |e: &Estimate| Estimate {
            mean: e.mean / grid.step,
            stderr: e.stderr / grid.step,
        };
        let mut rows = Vec::new();
        for (k, &at) in schedule.iter().enumerate() {
            let states = processes.each_ref().map(|p| p.states.states(k));
            rows.extend((0..grid.len()).map(|node| GridNode {
                at,
                u: grid.velocity(node),
                h: states.each_ref().map(|state| per_node(&state[node])),
                equilibrium: [0, 1].map(|p| processes[p].equilibrium[node] / grid.step),
            }));
        }
        Ok(with_times(Rows::new(&rows), |r| r.at)
            .with(U, |r| r.u)
            .estimate(H_FULL, |r| r.h[0])
            .estimate(H_TAGGED, |r| r.h[1])
            .estimate(H_FOKKER_PLANCK, |r| r.h[2])
            .with(EQUILIBRIUM_FULL, |r| r.equilibrium[0])
            .with(EQUILIBRIUM_TAGGED, |r| r.equilibrium[1])
            .table(&TABLE)?
            .with_metadata("ternary.grid_step", grid.step.to_string()))
    }

    fn summary_table(
        &self,
        grid: &VelocityGrid,
        schedule: &[Moment],
        processes: &[Process; 3],
    ) -> Result<Table, StageError> {
        use contract::evolve::evolution_summary::*;
        let u_prime = self.params.kernel.u_prime;
        let reach = self.params.kernel.edge();
        let none = Estimate {
            mean: f64::NAN,
            stderr: f64::NAN,
        };
        let names = [FULL, TAGGED, FOKKER_PLANCK];
        let mut rows = Vec::new();
        for (&name, process) in names.iter().zip(processes) {
            let [clipped, asymmetry] = process.diagnostics;
            for (k, &at) in schedule.iter().enumerate() {
                let decay = match k {
                    0 => none,
                    _ => process.entropy_decay(grid, k, at.scaled - schedule[k - 1].scaled),
                };
                rows.push(ProcessRow {
                    process: name,
                    at,
                    moments: process.moments(grid, k, u_prime, reach),
                    decay,
                    clipped,
                    asymmetry,
                });
            }
        }
        let rows = Rows::new(&rows).with(PROCESS, |r| r.process.to_string());
        Ok(with_times(rows, |r| r.at)
            .with(GRID_STEP, |_| grid.step)
            .with(WINDOW_HALF_WIDTH, |_| reach)
            .estimate(NUMBER, |r| r.moments.number)
            .estimate(MOMENTUM, |r| r.moments.momentum)
            .estimate(SECOND_MOMENT, |r| r.moments.second_moment)
            .estimate(VARIANCE, |r| r.moments.variance)
            .estimate(WINDOW_VARIANCE, |r| r.moments.window_variance)
            .estimate(DISTANCE_TO_EQUILIBRIUM, |r| r.moments.distance)
            .estimate(ENTROPY, |r| r.moments.entropy)
            .estimate(ENTROPY_DECAY_RATE, |r| r.decay)
            .estimate(LARGEST_CLIPPED_RATE, |r| r.clipped)
            .estimate(ASYMMETRY, |r| r.asymmetry)
            .table(&TABLE)?)
    }
}

/// One output bin of the early-time `h` at one time (`h` per `v_th`).
struct EarlyBin {
    at: Moment,
    x: f64,
    h: Estimate,
}

/// `h` of the three processes at one grid node and time, and the limits of
/// the first two (per `v_th`).
struct GridNode {
    at: Moment,
    u: f64,
    h: [Estimate; 3],
    equilibrium: [f64; 2],
}

/// The moments of one process's `h` at one time, and the diagnostics of
/// its generator.
struct ProcessRow {
    process: &'static str,
    at: Moment,
    moments: ProcessMoments,
    /// The entropy's decay rate since the previous time (NaN at the first).
    decay: Estimate,
    clipped: Estimate,
    asymmetry: Estimate,
}

/// Adds the three time columns of every evolve table.
fn with_times<'r, R>(rows: Rows<'r, R>, at: impl Fn(&R) -> Moment) -> Rows<'r, R> {
    use contract::evolve::*;
    rows.with(TIME_GAMMA, |r| at(r).gamma)
        .with(TIME_SCALED, |r| at(r).scaled)
        .with(TIME_NS, |r| at(r).ns)
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for EvolveStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(
            contract::evolve::STAGE,
            &instances::target(&self.params.kernel),
        )
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::evolve::*;
        &[
            early_evolution::TABLE.name,
            early_summary::TABLE.name,
            evolution::TABLE.name,
            evolution_summary::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        instances::collisions_of(&self.params.kernel.potential.id(), &self.wide_collisions)
    }

    fn work_units(&self) -> u64 {
        3
    }

    /// Every event read, 8 us each on the default study's grid (its three
    /// generators built and propagated, 2026-12-01); a row per node and time.
    fn cost(&self, inputs: &[Cost]) -> Cost {
        Cost::reading(inputs, 8e-6, 4e3, 100.0)
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let (events, draws, _) = collision_events(&inputs[0])?;
        let wide = match inputs.get(1) {
            Some(input) => Some(collision_events(input)?),
            None => None,
        };
        let (wide_events, wide_draws) = match &wide {
            Some((e, d, _)) => (e.as_slice(), d),
            None => (events.as_slice(), &draws),
        };
        progress.set_total(2 + wide_events.len() as u64);
        let gamma = self.gamma(&events, &draws);
        let mut tables = self.early(&events, &draws, &self.schedule(gamma, true))?;
        progress.advance(1);
        tables.extend(self.grid_evolution(
            wide_events,
            wide_draws,
            &self.schedule(gamma, false),
            progress,
        )?);
        Ok(tables)
    }
}
