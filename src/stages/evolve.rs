//! `evolve`: `h(u, t)` from `delta(u - u')` (physics.md §4) three ways, with
//! jackknife uncertainties over the Monte Carlo randomizations:
//!
//! * early times: the translation-invariant kernel `G(u' -> u' + x)` on the
//!   kernel's fine bins, evolved exactly in Fourier space (`early_evolution`,
//!   `early_summary`, with the closed-form cumulants `t kappa_p` as a check);
//! * up to several `1/Gamma`: the full `u'`-dependent master equation on a
//!   velocity grid spanning the Maxwellian (`evolution`, `evolution_summary`),
//!   for the linearized operator (`full`: conserves number, momentum and
//!   energy, relaxes to `f0 (1 + u u' + (u'^2 - 1)(u^2 - 1)/2)`; its estimate
//!   is projected onto detailed balance and dissipation, which removes the
//!   growing noise modes of the raw estimate, see `evolve::spectral`), for the
//!   special particle alone (`tagged`: a Markov generator, relaxes to `f0`),
//!   and for the Fokker-Planck equation of the tagged drift and variance rates;
//! * what the projection of the full operator does to `h_full`, against its
//!   statistical error (`projection`).
//!
//! Times are given in `1/Gamma` (`Gamma` = the special particle's variance
//! rate at `u'`, from the same events: `a_n` at `u' = 0`) or in ns for a gas;
//! every table carries both and the scaled time `t rho^2 l v_th`.

use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::{collision_events, target_of};
use crate::binning::Bins;
use crate::config::EvolveParams;
use crate::contract::{self, Rows};
use crate::evolve::convolution::{
    self, closed_form_excess_kurtosis, closed_form_number, closed_form_variance, excess_kurtosis,
    kernel_moments, state_mean, state_moment, state_variance,
};
use crate::evolve::grid::VelocityGrid;
use crate::evolve::operator::{Generators, column_rates, fokker_planck, kernel_generators};
use crate::evolve::propagate::Generator;
use crate::evolve::spectral::Dissipative;
use crate::kernel::equilibrium::self_rates;
use crate::kernel::{Draws, Event};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::{Estimate, Replicated, replicate_means};

/// The `evolve` stage.
pub struct EvolveStage {
    params: EvolveParams,
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
    /// An evolve stage with resolved parameters.
    pub fn new(params: EvolveParams) -> EvolveStage {
        EvolveStage { params }
    }

    /// The special particle's variance rate at `u'` (within half the window),
    /// `rho^2 l v_th`: `Gamma` in scaled units.
    fn gamma(&self, events: &[Event], draws: &Draws) -> f64 {
        let target = target_of(&self.params.kernel);
        let rates = self_rates(events, &target, 0.5 * self.params.kernel.window, draws);
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

    fn early(
        &self,
        events: &[Event],
        draws: &Draws,
        schedule: &[Moment],
    ) -> Result<Vec<Table>, StageError> {
        let kernel = &self.params.kernel;
        let bins = Bins::for_window(kernel.window, kernel.bin_width);
        let rates = convolution::replicated_kernel(events, draws, &target_of(kernel), &bins);
        let times: Vec<f64> = schedule.iter().map(|m| m.scaled).collect();
        let t_max = times.last().copied().unwrap_or(0.0);
        let rebin = self.params.early_rebin as usize;
        let out_width = rebin as f64 * bins.width;
        let half_out = (self.params.early_range / out_width).round() as usize;
        let size = convolution::periodic_size(&rates.full, bins.width, t_max)
            .max((2 * (half_out + 1) * rebin).next_power_of_two());
        let states = rates.map(|g| convolution::evolve(g, size, &times));
        let (centre, width) = (size / 2, bins.width);
        let cumulants = rates.map(|g| kernel_moments(g, width));
        let mut h_rows = Vec::new();
        let mut summary = Vec::new();
        for (k, &at) in schedule.iter().enumerate() {
            let binned = states.map(|s| convolution::rebin(&s[k], centre, rebin, half_out));
            for (m, estimate) in binned.values().iter().enumerate() {
                h_rows.push(EarlyBin {
                    at,
                    x: (m as f64 - half_out as f64) * out_width,
                    h: Estimate {
                        mean: estimate.mean / out_width,
                        stderr: estimate.stderr / out_width,
                    },
                });
            }
            let t = at.scaled;
            summary.push(EarlyMoments {
                at,
                number: states.estimate(k, |h| state_moment(h, width, 0)),
                number_closed: cumulants.scalar(|c| closed_form_number(c, t)),
                mean: states.estimate(k, |h| state_mean(h, width)),
                variance: states.estimate(k, |h| state_variance(h, width)),
                variance_closed: cumulants.scalar(|c| closed_form_variance(c, t)),
                kurtosis: states.estimate(k, |h| excess_kurtosis(h, width)),
                kurtosis_closed: cumulants.scalar(|c| closed_form_excess_kurtosis(c, t)),
            });
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
            with_times(Rows::new(&summary), |r| r.at)
                .estimate(NUMBER, |r| r.number)
                .with(NUMBER_CLOSED_FORM, |r| r.number_closed.mean)
                .estimate(MEAN, |r| r.mean)
                .estimate(VARIANCE, |r| r.variance)
                .estimate(VARIANCE_CLOSED_FORM, |r| r.variance_closed)
                .estimate(EXCESS_KURTOSIS, |r| r.kurtosis)
                .estimate(EXCESS_KURTOSIS_CLOSED_FORM, |r| r.kurtosis_closed)
                .table(&TABLE)?
        };
        Ok(vec![h_table, summary_table])
    }

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
        let placed = std::sync::atomic::AtomicUsize::new(0);
        let generators = kernel_generators(events, draws, &grid, p.kernel.kick_floor, |done| {
            let before = placed.swap(done, std::sync::atomic::Ordering::Relaxed);
            progress.advance((done - before) as u64);
        });
        let pick = |part: fn(&Generators) -> &Generator| -> Vec<Generator> {
            generators.iter().map(|g| part(g).clone()).collect()
        };
        let raw = replicate_means(&pick(|g| &g.full));
        let tagged = replicate_means(&pick(|g| &g.tagged));
        let diffusion = tagged.map(|m| {
            let (drift, variance) = column_rates(m, &grid);
            fokker_planck(&grid, &drift, &variance)
        });
        let maxwellian = grid.maxwellian();
        let velocities = grid.velocities();
        let invariants = [
            vec![1.0; grid.len()],
            velocities.clone(),
            velocities.iter().map(|u| u * u).collect(),
        ];
        let full = raw.map(|m| Dissipative::project(m, &maxwellian, &invariants));
        let mut h0 = vec![0.0; grid.len()];
        h0[start] = 1.0;
        let times: Vec<f64> = schedule.iter().map(|m| m.scaled).collect();
        let full_states = full.map(|m| m.propagate(&h0, &times));
        let effect = ProjectionEffect {
            clipping: full.map(|m| m.clipping_change(&h0, &times)),
            clipped: full.map(|m| m.clipped_part(&h0)),
            projection: full_states.zip(&raw.map(|m| m.propagate(&h0, &times)), |h, raw| {
                h.iter()
                    .zip(raw)
                    .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect())
                    .collect()
            }),
        };
        let diagnostics = |d: &Replicated<Dissipative>| {
            [d.scalar(|d| d.largest_clipped), d.scalar(|d| d.asymmetry)]
        };
        use contract::evolve::evolution_summary::{FOKKER_PLANCK, FULL, TAGGED};
        let processes = [
            Process {
                name: FULL,
                states: full_states,
                equilibrium: grid.conserving_equilibrium(p.kernel.u_prime),
                diagnostics: Some(diagnostics(&full)),
            },
            Process {
                name: TAGGED,
                states: tagged.map(|m| m.propagate(&h0, &times)),
                equilibrium: maxwellian.clone(),
                diagnostics: None,
            },
            Process {
                name: FOKKER_PLANCK,
                states: diffusion.map(|m| m.propagate(&h0, &times)),
                equilibrium: maxwellian,
                diagnostics: None,
            },
        ];
        progress.advance(1);
        Ok(vec![
            self.state_table(&grid, schedule, &processes)?,
            self.summary_table(&grid, schedule, &processes)?,
            projection_table(&grid, schedule, &processes[0].states, &effect)?,
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
        let reach = 0.5 * self.params.kernel.window;
        let none = Estimate {
            mean: f64::NAN,
            stderr: f64::NAN,
        };
        let mut rows = Vec::new();
        for process in processes {
            let [clipped, asymmetry] = process.diagnostics.unwrap_or([none, none]);
            for (k, &at) in schedule.iter().enumerate() {
                let all = |h: &[f64]| grid.moments(h, 0.0, f64::INFINITY);
                let estimate = |f: &dyn Fn(&[f64]) -> f64| process.states.estimate(k, f);
                rows.push(ProcessMoments {
                    process: process.name,
                    at,
                    number: estimate(&|h| all(h)[0]),
                    momentum: estimate(&|h| all(h)[1]),
                    second_moment: estimate(&|h| all(h)[2]),
                    variance: estimate(&|h| grid.moments(h, u_prime, f64::INFINITY)[2]),
                    window_variance: estimate(&|h| grid.moments(h, u_prime, reach)[2]),
                    distance: estimate(&|h| {
                        h.iter()
                            .zip(&process.equilibrium)
                            .map(|(a, b)| (a - b).abs())
                            .sum()
                    }),
                    clipped,
                    asymmetry,
                });
            }
        }
        let rows = Rows::new(&rows).with(PROCESS, |r| r.process.to_string());
        Ok(with_times(rows, |r| r.at)
            .with(GRID_STEP, |_| grid.step)
            .with(WINDOW_HALF_WIDTH, |_| reach)
            .estimate(NUMBER, |r| r.number)
            .estimate(MOMENTUM, |r| r.momentum)
            .estimate(SECOND_MOMENT, |r| r.second_moment)
            .estimate(VARIANCE, |r| r.variance)
            .estimate(WINDOW_VARIANCE, |r| r.window_variance)
            .estimate(DISTANCE_TO_EQUILIBRIUM, |r| r.distance)
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

/// The moments of the early-time `h` at one time, and their closed forms.
struct EarlyMoments {
    at: Moment,
    number: Estimate,
    number_closed: Estimate,
    mean: Estimate,
    variance: Estimate,
    variance_closed: Estimate,
    kurtosis: Estimate,
    kurtosis_closed: Estimate,
}

/// `h` of the three processes at one grid node and time, and the limits of
/// the first two (per `v_th`).
struct GridNode {
    at: Moment,
    u: f64,
    h: [Estimate; 3],
    equilibrium: [f64; 2],
}

/// The moments of one process's `h` at one time.
struct ProcessMoments {
    process: &'static str,
    at: Moment,
    number: Estimate,
    momentum: Estimate,
    second_moment: Estimate,
    variance: Estimate,
    window_variance: Estimate,
    distance: Estimate,
    clipped: Estimate,
    asymmetry: Estimate,
}

/// What projecting the full operator's estimate does to `h_full`, for the
/// full and every leave-one-out estimate (node masses).
struct ProjectionEffect {
    /// `h(t) - h_unclipped(t)` per time (`Dissipative::clipping_change`).
    clipping: Replicated<Vec<Vec<f64>>>,
    /// The part of `h` frozen in the clipped modes (`Dissipative::clipped_part`).
    clipped: Replicated<Vec<f64>>,
    /// `h(t) - exp(t M) h(0)` per time, `M` the raw estimate.
    projection: Replicated<Vec<Vec<f64>>>,
}

/// `sum_i |x_i|`.
fn l1(x: &[f64]) -> f64 {
    x.iter().map(|v| v.abs()).sum()
}

/// The `projection` table: per time the L1 sizes of the clipping's change of
/// `h_full`, of the weight frozen in the clipped modes and of the whole
/// projection's change, with jackknife errors; the moments of the clipping's
/// change (0 to rounding); and each size's largest value over the full and
/// leave-one-out estimates against `sum_i sigma_i`, the L1 size of `h_full`'s
/// statistical error (jackknife `sigma_i` of node `i`'s mass). A ratio below 1
/// means the projection moves `h` by less than its error in every replicate.
fn projection_table(
    grid: &VelocityGrid,
    schedule: &[Moment],
    states: &Replicated<Vec<Vec<f64>>>,
    effect: &ProjectionEffect,
) -> Result<Table, StageError> {
    use contract::evolve::projection::*;
    let rows: Vec<ProjectionRow> = schedule
        .iter()
        .enumerate()
        .map(|(k, &at)| {
            let error: f64 = states.states(k).iter().map(|e| e.stderr).sum();
            let moment = |p: usize| {
                effect
                    .clipping
                    .estimate(k, |d| grid.moments(d, 0.0, f64::INFINITY)[p])
            };
            ProjectionRow {
                at,
                clipping: effect.clipping.estimate(k, l1),
                clipped: effect.clipped.scalar(|part| l1(part)),
                moments: [0, 1, 2].map(moment),
                projection: effect.projection.estimate(k, l1),
                error,
                over_error: [
                    effect.clipping.largest(|d| l1(&d[k])),
                    effect.clipped.largest(|part| l1(part)),
                    effect.projection.largest(|d| l1(&d[k])),
                ]
                .map(|change| Some(change / error).filter(|ratio| ratio.is_finite())),
            }
        })
        .collect();
    Ok(with_times(Rows::new(&rows), |r| r.at)
        .estimate(CLIPPING_CHANGE, |r| r.clipping)
        .estimate(CLIPPED_WEIGHT, |r| r.clipped)
        .estimate(CLIPPING_NUMBER, |r| r.moments[0])
        .estimate(CLIPPING_MOMENTUM, |r| r.moments[1])
        .estimate(CLIPPING_SECOND_MOMENT, |r| r.moments[2])
        .estimate(PROJECTION_CHANGE, |r| r.projection)
        .with(H_ERROR_L1, |r| r.error)
        .optional(CLIPPING_CHANGE_OVER_ERROR, |r| r.over_error[0])
        .optional(CLIPPED_WEIGHT_OVER_ERROR, |r| r.over_error[1])
        .optional(PROJECTION_CHANGE_OVER_ERROR, |r| r.over_error[2])
        .table(&TABLE)?)
}

/// One row of the `projection` table.
struct ProjectionRow {
    at: Moment,
    clipping: Estimate,
    clipped: Estimate,
    /// Number, momentum and second moment of the clipping's change.
    moments: [Estimate; 3],
    projection: Estimate,
    /// `sum_i sigma_i` of `h_full`.
    error: f64,
    /// Largest clipping change, clipped weight and projection change over
    /// `error` (`None` where the ratio is not finite: at `t = 0`, where `h`
    /// is exact and `error` zero or of rounding size).
    over_error: [Option<f64>; 3],
}

/// Adds the three time columns of every evolve table.
fn with_times<'r, R>(rows: Rows<'r, R>, at: impl Fn(&R) -> Moment) -> Rows<'r, R> {
    use contract::evolve::*;
    rows.with(TIME_GAMMA, |r| at(r).gamma)
        .with(TIME_SCALED, |r| at(r).scaled)
        .with(TIME_NS, |r| at(r).ns)
}

/// One evolved process: its states, its equilibrium (node masses) and, for
/// the projected kernel generators, the largest positive eigenvalue removed
/// and the detailed-balance violation of the raw estimate.
struct Process {
    name: &'static str,
    states: Replicated<Vec<Vec<f64>>>,
    equilibrium: Vec<f64>,
    diagnostics: Option<[Estimate; 2]>,
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for EvolveStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(
            contract::evolve::STAGE,
            &super::kernel::target_instance(&self.params.kernel),
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
            projection::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        CollisionsStage::instances(&self.params.collisions, &self.params.wide_collisions)
    }

    fn work_units(&self) -> u64 {
        3
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
