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
//!   and for the Fokker-Planck equation of the tagged drift and variance rates.
//!
//! Times are given in `1/Gamma` (`Gamma` = the special particle's variance
//! rate at `u'`, from the same events: `a_n` at `u' = 0`) or in ns for a gas;
//! every table carries both and the scaled time `t rho^2 l v_th`.

use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::{collision_events, target_of};
use crate::binning::Bins;
use crate::config::EvolveParams;
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
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};
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
        let mut h_rows: [Vec<f64>; 7] = Default::default();
        let mut summary: [Vec<f64>; 16] = Default::default();
        for (k, at) in schedule.iter().enumerate() {
            let binned = states.map(|s| convolution::rebin(&s[k], centre, rebin, half_out));
            for (m, estimate) in binned.values().iter().enumerate() {
                let x = (m as f64 - half_out as f64) * out_width;
                let row = [
                    at.gamma,
                    at.scaled,
                    at.ns,
                    x,
                    x + kernel.u_prime,
                    estimate.mean / out_width,
                    estimate.stderr / out_width,
                ];
                h_rows.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
            }
            let mass = states.estimate(k, |h| state_moment(h, width, 0));
            let mean = states.estimate(k, |h| state_mean(h, width));
            let variance = states.estimate(k, |h| state_variance(h, width));
            let kurtosis = states.estimate(k, |h| excess_kurtosis(h, width));
            let t = at.scaled;
            let mass_closed = cumulants.scalar(|c| closed_form_number(c, t));
            let variance_closed = cumulants.scalar(|c| closed_form_variance(c, t));
            let kurtosis_closed = cumulants.scalar(|c| closed_form_excess_kurtosis(c, t));
            let row = [
                at.gamma,
                at.scaled,
                at.ns,
                mass.mean,
                mass.stderr,
                mass_closed.mean,
                mean.mean,
                mean.stderr,
                variance.mean,
                variance.stderr,
                variance_closed.mean,
                variance_closed.stderr,
                kurtosis.mean,
                kurtosis.stderr,
                kurtosis_closed.mean,
                kurtosis_closed.stderr,
            ];
            summary.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
        }
        let [gamma, scaled, ns, x, u, h, h_err] = h_rows;
        let density = "1/v_th";
        let h_table = Table::new(
            "early_evolution",
            vec![
                time_gamma_column(gamma),
                time_scaled_column(scaled),
                time_ns_column(ns),
                Column::f64("du", "v_th", "bin centre relative to u'", x),
                Column::f64("u", "v_th", "bin centre", u),
                Column::f64("h", density, "h(u, t) from delta(u - u') under the translation-invariant kernel (self plus bath, within the kernel window), exact in Fourier space", h),
                Column::f64("h_stderr", density, "jackknife standard error over randomizations", h_err),
            ],
        )?
        .with_metadata("ternary.description", "early-time h(u, t): convolution semigroup of the kernel at u'".into());
        let [
            g,
            s,
            ns,
            mass,
            mass_err,
            mass_closed,
            mean,
            mean_err,
            var,
            var_err,
            var_closed,
            var_closed_err,
            kurt,
            kurt_err,
            kurt_closed,
            kurt_closed_err,
        ] = summary;
        let rate = "rho^2 l v_th";
        let summary_table = Table::new(
            "early_summary",
            vec![
                time_gamma_column(g),
                time_scaled_column(s),
                time_ns_column(ns),
                Column::f64("number", "1", "integral of h (the window loses what leaves it)", mass),
                Column::f64("number_stderr", "1", "jackknife standard error", mass_err),
                Column::f64("number_closed_form", "1", "exp(t kappa_0), kappa_p = sum_k g_k x_k^p of the kernel", mass_closed),
                Column::f64("mean", "v_th", "<u - u'>_h (normalized)", mean),
                Column::f64("mean_stderr", "v_th", "jackknife standard error", mean_err),
                Column::f64("variance", "v_th^2", "variance of h (normalized): grows as t kappa_2 (kappa_2: the window variance rate, ~a_n)", var),
                Column::f64("variance_stderr", "v_th^2", "jackknife standard error", var_err),
                Column::f64("variance_closed_form", "v_th^2", "t kappa_2", var_closed),
                Column::f64("variance_closed_form_stderr", "v_th^2", "jackknife standard error", var_closed_err),
                Column::f64("excess_kurtosis", "1", "of h: the cusp's non-Gaussianity, decaying as 1/t (central limit)", kurt),
                Column::f64("excess_kurtosis_stderr", "1", "jackknife standard error", kurt_err),
                Column::f64("excess_kurtosis_closed_form", "1", "kappa_4 / (t kappa_2^2)", kurt_closed),
                Column::f64("excess_kurtosis_closed_form_stderr", "1", "jackknife standard error", kurt_closed_err),
            ],
        )?
        .with_metadata("ternary.description", format!("early-time moments of h; kernel rates in {rate}"));
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
        let full = replicate_means(&pick(|g| &g.full));
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
        let full = full.map(|m| Dissipative::project(m, &maxwellian, &invariants));
        let mut h0 = vec![0.0; grid.len()];
        h0[start] = 1.0;
        let times: Vec<f64> = schedule.iter().map(|m| m.scaled).collect();
        let diagnostics = |d: &Replicated<Dissipative>| {
            [d.scalar(|d| d.largest_clipped), d.scalar(|d| d.asymmetry)]
        };
        let processes = [
            Process {
                name: "full",
                states: full.map(|m| m.propagate(&h0, &times)),
                equilibrium: grid.conserving_equilibrium(p.kernel.u_prime),
                diagnostics: Some(diagnostics(&full)),
            },
            Process {
                name: "tagged",
                states: tagged.map(|m| m.propagate(&h0, &times)),
                equilibrium: maxwellian.clone(),
                diagnostics: None,
            },
            Process {
                name: "fokker_planck",
                states: diffusion.map(|m| m.propagate(&h0, &times)),
                equilibrium: maxwellian,
                diagnostics: None,
            },
        ];
        progress.advance(1);
        Ok(vec![
            self.state_table(&grid, schedule, &processes)?,
            self.summary_table(&grid, schedule, &processes)?,
        ])
    }

    fn state_table(
        &self,
        grid: &VelocityGrid,
        schedule: &[Moment],
        processes: &[Process; 3],
    ) -> Result<Table, StageError> {
        let mut columns: [Vec<f64>; 12] = Default::default();
        for (k, at) in schedule.iter().enumerate() {
            let states: Vec<Vec<Estimate>> = processes.iter().map(|p| p.states.states(k)).collect();
            for i in 0..grid.len() {
                let mut row = vec![at.gamma, at.scaled, at.ns, grid.velocity(i)];
                for state in &states {
                    row.extend([state[i].mean / grid.step, state[i].stderr / grid.step]);
                }
                row.extend([
                    processes[0].equilibrium[i] / grid.step,
                    processes[1].equilibrium[i] / grid.step,
                ]);
                columns.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
            }
        }
        let [
            gamma,
            scaled,
            ns,
            u,
            full,
            full_err,
            tagged,
            tagged_err,
            fp,
            fp_err,
            eq_full,
            eq_tagged,
        ] = columns;
        let density = "1/v_th";
        Ok(Table::new(
            "evolution",
            vec![
                time_gamma_column(gamma),
                time_scaled_column(scaled),
                time_ns_column(ns),
                Column::f64("u", "v_th", "grid node", u),
                Column::f64("h_full", density, "h(u, t) from delta(u - u') under the linearized three-body operator (all three particles' velocity changes)", full),
                Column::f64("h_full_stderr", density, "jackknife standard error over randomizations", full_err),
                Column::f64("h_tagged", density, "distribution of the special particle's own velocity (its kicks alone)", tagged),
                Column::f64("h_tagged_stderr", density, "jackknife standard error", tagged_err),
                Column::f64("h_fokker_planck", density, "Fokker-Planck evolution with the tagged drift and variance rates", fp),
                Column::f64("h_fokker_planck_stderr", density, "jackknife standard error", fp_err),
                Column::f64("equilibrium_full", density, "f0 (1 + u u' + (u'^2 - 1)(u^2 - 1)/2): the limit of h_full (number, momentum, energy conserved)", eq_full),
                Column::f64("equilibrium_tagged", density, "f0: the limit of h_tagged and h_fokker_planck", eq_tagged),
            ],
        )?
        .with_metadata("ternary.description", "h(u, t) by the master equation on a velocity grid (node masses / step)".into())
        .with_metadata("ternary.grid_step", grid.step.to_string()))
    }

    fn summary_table(
        &self,
        grid: &VelocityGrid,
        schedule: &[Moment],
        processes: &[Process; 3],
    ) -> Result<Table, StageError> {
        let u_prime = self.params.kernel.u_prime;
        let reach = 0.5 * self.params.kernel.window;
        let mut names = Vec::new();
        let mut columns: [Vec<f64>; 21] = Default::default();
        for process in processes {
            let none = Estimate {
                mean: f64::NAN,
                stderr: f64::NAN,
            };
            let [clipped, asymmetry] = process.diagnostics.unwrap_or([none, none]);
            for (k, at) in schedule.iter().enumerate() {
                let all = |h: &[f64]| grid.moments(h, 0.0, f64::INFINITY);
                let estimates = [
                    process.states.estimate(k, |h| all(h)[0]),
                    process.states.estimate(k, |h| all(h)[1]),
                    process.states.estimate(k, |h| all(h)[2]),
                    process
                        .states
                        .estimate(k, |h| grid.moments(h, u_prime, f64::INFINITY)[2]),
                    process
                        .states
                        .estimate(k, |h| grid.moments(h, u_prime, reach)[2]),
                    process.states.estimate(k, |h| {
                        h.iter()
                            .zip(&process.equilibrium)
                            .map(|(a, b)| (a - b).abs())
                            .sum()
                    }),
                ];
                let mut row = vec![
                    at.gamma,
                    at.scaled,
                    at.ns,
                    grid.step,
                    0.5 * self.params.kernel.window,
                ];
                for e in estimates.into_iter().chain([clipped, asymmetry]) {
                    row.extend([e.mean, e.stderr]);
                }
                names.push(process.name.to_string());
                columns.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
            }
        }
        let [
            gamma,
            scaled,
            ns,
            step,
            window,
            number,
            number_err,
            momentum,
            momentum_err,
            energy,
            energy_err,
            spread,
            spread_err,
            window_spread,
            window_spread_err,
            distance,
            distance_err,
            clipped,
            clipped_err,
            asymmetry,
            asymmetry_err,
        ] = columns;
        Ok(Table::new(
            "evolution_summary",
            vec![
                Column::text("process", "full (linearized operator), tagged (special particle alone), fokker_planck", names),
                time_gamma_column(gamma),
                time_scaled_column(scaled),
                time_ns_column(ns),
                Column::f64("grid_step", "v_th", "node spacing", step),
                Column::f64("window_half_width", "v_th", "X of window_variance", window),
                Column::f64("number", "1", "sum of h: 1 for every process (exact up to rounding and the grid's ends)", number),
                Column::f64("number_stderr", "1", "jackknife standard error", number_err),
                Column::f64("momentum", "v_th", "sum u h: u' for full (momentum conservation)", momentum),
                Column::f64("momentum_stderr", "v_th", "jackknife standard error", momentum_err),
                Column::f64("second_moment", "v_th^2", "sum u^2 h: u'^2 for full (energy conservation), 1 in equilibrium for tagged", energy),
                Column::f64("second_moment_stderr", "v_th^2", "jackknife standard error", energy_err),
                Column::f64("variance", "v_th^2", "<(u - u')^2>_h over the whole grid", spread),
                Column::f64("variance_stderr", "v_th^2", "jackknife standard error", spread_err),
                Column::f64("window_variance", "v_th^2", "<(u - u')^2>_h within |u - u'| <= X (the published window): slope a_n at early times", window_spread),
                Column::f64("window_variance_stderr", "v_th^2", "jackknife standard error", window_spread_err),
                Column::f64("distance_to_equilibrium", "1", "sum |h - h_eq| over the nodes (L1), h_eq the process's limit", distance),
                Column::f64("distance_to_equilibrium_stderr", "1", "jackknife standard error", distance_err),
                Column::f64("largest_clipped_rate", "rho^2 l v_th", "largest positive eigenvalue of the estimated generator (symmetrized, invariants projected out), set to zero: Monte Carlo noise (NaN: not projected)", clipped),
                Column::f64("largest_clipped_rate_stderr", "rho^2 l v_th", "jackknife standard error", clipped_err),
                Column::f64("asymmetry", "1", "||S - S^T|| / ||S + S^T|| of S = f0^(-1/2) M f0^(1/2): detailed-balance violation of the raw estimate, removed", asymmetry),
                Column::f64("asymmetry_stderr", "1", "jackknife standard error", asymmetry_err),
            ],
        )?
        .with_metadata("ternary.description", "conservation laws, spread and approach to equilibrium of h(u, t)".into()))
    }
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

fn time_gamma_column(values: Vec<f64>) -> Column {
    Column::f64(
        "time_gamma",
        "1/Gamma",
        "time t Gamma, Gamma = the special particle's variance rate at u' (a_n rho^2 l v_th at u' = 0)",
        values,
    )
}

fn time_scaled_column(values: Vec<f64>) -> Column {
    Column::f64(
        "time_scaled",
        "1/(rho^2 l v_th)",
        "time t rho^2 l v_th",
        values,
    )
}

fn time_ns_column(values: Vec<f64>) -> Column {
    Column::f64(
        "time_ns",
        "ns",
        "physical time of the configured gas (NaN when given in 1/Gamma)",
        values,
    )
}

impl Stage for EvolveStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(
            "evolve",
            &super::kernel::target_instance(&self.params.kernel),
        )
    }

    fn version(&self) -> u32 {
        1
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[
            "early_evolution",
            "early_summary",
            "evolution",
            "evolution_summary",
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
