//! `md`: molecular dynamics of one ring (physics.md §7): independent runs in
//! parallel, each from its own seeded initial state, advanced by cluster
//! stepping; `h(u, t_f)` by the published estimator and by the tagged-velocity
//! estimator, averaged over a short window around `t_f`, with standard errors
//! from the spread of runs; conservation diagnostics per run. The `n = 2`
//! (Sutherland) ring runs as a whole with all pairs, its lineages being its
//! conserved rapidities. Lennard-Jones rings also report their bound pairs,
//! sampled and after the dynamics, against the dilute limit.

use rayon::prelude::*;
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::binning::Bins;
use crate::config::MdParams;
use crate::physics::md::{RunResult, RunSettings, run};
use crate::physics::potential::{PairPotential, PotentialVisitor};
use crate::physics::ring::{Reach, RingForces};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;

/// The `md` stage for one ring.
pub struct MdStage {
    params: MdParams,
}

/// Step budget of one cluster over one macro step.
const MAX_STEPS: u64 = 10_000_000;

impl MdStage {
    /// An md stage with resolved parameters.
    pub fn new(params: MdParams) -> MdStage {
        MdStage { params }
    }

    fn settings(&self) -> RunSettings {
        let p = &self.params;
        RunSettings {
            particles: p.particles as usize,
            u_prime: p.u_prime,
            tolerance: p.tolerance,
            sample_times: p.sample_times.clone(),
            bins: Bins::for_window(p.window, p.bin_width),
            start_band: p.start_band,
            max_steps: MAX_STEPS,
        }
    }

    /// Seed of run `k`: the study's seed mixed with the ring's name and the
    /// run index, so that rings of a study draw independent initial states
    /// (correlated rings would correlate the errors of a finite-size trend).
    fn seed(&self, run: u32) -> u64 {
        let digest = Sha256::digest(self.params.name.as_bytes());
        let name = u64::from_le_bytes(digest[..8].try_into().unwrap_or([0; 8]));
        self.params.seed ^ name ^ u64::from(run + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    }
}

/// Runs every seed with the concrete potential.
struct Runs<'a> {
    stage: &'a MdStage,
    progress: &'a Progress,
}

impl PotentialVisitor for Runs<'_> {
    type Output = Result<Vec<RunResult>, StageError>;

    fn visit<P: PairPotential>(self, potential: P) -> Self::Output {
        let p = &self.stage.params;
        let reach = if p.potential.is_integrable() {
            Reach::All
        } else {
            Reach::Neighbours(p.neighbours as usize)
        };
        let forces = RingForces {
            potential,
            circumference: p.circumference,
            reach,
        };
        let settings = self.stage.settings();
        (0..p.runs)
            .into_par_iter()
            .map(|k| {
                let result = run(&forces, &settings, self.stage.seed(k))
                    .map_err(|e| StageError::Input(format!("md[{}] run {k}: {e}", p.name)));
                self.progress.advance(1);
                result
            })
            .collect()
    }
}

/// Mean and standard error over runs of bin `k` of `part`. A bin where every
/// run has the same value (no run counted anything there, say) has no spread
/// to estimate an error from: exactly 0, not the rounding residue of the
/// mean, so that chi-square tests can leave it out.
fn per_bin(results: &[RunResult], k: usize, part: fn(&RunResult) -> &Vec<f64>) -> Estimate {
    let values: Vec<f64> = results.iter().map(|r| part(r)[k]).collect();
    let estimate = Estimate::from_replicates(&values);
    if values.iter().all(|v| *v == values[0]) {
        Estimate {
            stderr: 0.0,
            ..estimate
        }
    } else {
        estimate
    }
}

impl MdStage {
    fn h_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        let bins = self.settings().bins;
        let mut columns: [Vec<f64>; 6] = Default::default();
        let mut ratios = Vec::new();
        for k in 0..bins.len() {
            let published = per_bin(results, k, |r| &r.published);
            let tagged = per_bin(results, k, |r| &r.tagged);
            if tagged.stderr > 0.0 {
                ratios.push(published.stderr / tagged.stderr);
            }
            let x = bins.centre(k);
            let row = [
                x,
                self.params.u_prime + x,
                published.mean,
                published.stderr,
                tagged.mean,
                tagged.stderr,
            ];
            columns.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
        }
        ratios.sort_by(f64::total_cmp);
        let median_ratio = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
        let [du, u, published, published_err, tagged, tagged_err] = columns;
        let density = "1/v_th";
        Ok(Table::new(
            "h",
            vec![
                Column::f64("du", "v_th", "bin centre relative to u'", du),
                Column::f64("u", "v_th", "bin centre", u),
                Column::f64("h_published", density, "published estimator: velocities in the bin minus (N - 1) f0, per bin width, averaged over the sample times", published),
                Column::f64("h_published_stderr", density, "standard error over runs", published_err),
                Column::f64("h_tagged", density, "tagged-velocity estimator: change of every velocity lineage starting within start_band of u', per lineage and bin width", tagged),
                Column::f64("h_tagged_stderr", density, "standard error over runs", tagged_err),
            ],
        )?
        .with_metadata("ternary.description", "h(u, t_f) of a ring by molecular dynamics".into())
        .with_metadata("ternary.noise_ratio", median_ratio.to_string())
        .with_metadata("ternary.circumference_l", self.params.circumference.to_string()))
    }

    /// Per estimator: the mass `sum h dx` and variance `sum x^2 h dx` within
    /// the window (x = u - u'), per run, averaged with standard errors.
    fn summary_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        let bins = self.settings().bins;
        let moment = |h: &[f64], p: i32| -> f64 {
            h.iter()
                .enumerate()
                .map(|(k, v)| v * bins.centre(k).powi(p) * bins.width)
                .sum()
        };
        let mut columns: [Vec<f64>; 4] = Default::default();
        let names = ["published", "tagged", "thermal"]
            .map(String::from)
            .to_vec();
        let parts: [fn(&RunResult) -> &Vec<f64>; 2] = [|r| &r.published, |r| &r.tagged];
        let per_run = |value: &dyn Fn(&RunResult) -> f64| {
            Estimate::from_replicates(&results.iter().map(value).collect::<Vec<f64>>())
        };
        for part in parts {
            for p in [0, 2] {
                let estimate = per_run(&|r| moment(part(r), p));
                let slot = if p == 0 { 0 } else { 2 };
                columns[slot].push(estimate.mean);
                columns[slot + 1].push(estimate.stderr);
            }
        }
        for (slot, estimate) in [
            (0, per_run(&|r| r.thermal.number)),
            (2, per_run(&|r| r.thermal.window_variance)),
        ] {
            columns[slot].push(estimate.mean);
            columns[slot + 1].push(estimate.stderr);
        }
        let [mass, mass_err, variance, variance_err] = columns;
        Ok(Table::new(
            "summary",
            vec![
                Column::text(
                    "estimator",
                    "published (background subtracted), tagged (velocity lineages starting within start_band of u'), or thermal (every lineage starting with |u| <= 3: number = fraction whose change stays within the window, window_variance = mean of its square there)",
                    names,
                ),
                Column::f64("number", "1", "sum h dx over the window", mass),
                Column::f64("number_stderr", "1", "standard error over runs", mass_err),
                Column::f64(
                    "window_variance",
                    "v_th^2",
                    "sum (u - u')^2 h dx over the window",
                    variance,
                ),
                Column::f64(
                    "window_variance_stderr",
                    "v_th^2",
                    "standard error over runs",
                    variance_err,
                ),
            ],
        )?
        .with_metadata(
            "ternary.description",
            "moments of h(u, t_f) within the window".into(),
        ))
    }

    /// Fraction of neighbour gaps bound (`w^2/4 + U < 0`) in the initial
    /// states (the sampler's equilibrium) and at the last sample time (after
    /// the dynamics), with standard errors over runs, against the dilute
    /// limit `rho K_b` (0 for purely repulsive potentials).
    fn pairs_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        let p = &self.params;
        let gaps = f64::from(p.particles);
        let fraction = |k: usize| {
            let values: Vec<f64> = results
                .iter()
                .map(|r| r.bound_pairs[k] as f64 / gaps)
                .collect();
            Estimate::from_replicates(&values)
        };
        let (start, end) = (fraction(0), fraction(1));
        let density = f64::from(p.particles - 1) / p.circumference;
        let dilute = density * p.potential.bound_pair_length();
        Ok(Table::new(
            "pairs",
            vec![
                Column::text(
                    "state",
                    "initial (sampled), final (after MD), or dilute_limit (rho K_b)",
                    vec!["initial".into(), "final".into(), "dilute_limit".into()],
                ),
                Column::f64(
                    "bound_fraction",
                    "1",
                    "bound neighbour pairs per gap",
                    vec![start.mean, end.mean, dilute],
                ),
                Column::f64(
                    "bound_fraction_stderr",
                    "1",
                    "standard error over runs (0 for the closed form; its O(rho l) correction is not included)",
                    vec![start.stderr, end.stderr, 0.0],
                ),
            ],
        )?
        .with_metadata(
            "ternary.description",
            "bound neighbour pairs of the ring: sampler, dynamics and dilute limit".into(),
        ))
    }

    fn runs_table(&self, results: &[RunResult]) -> Result<Table, StageError> {
        let seeds: Vec<String> = (0..self.params.runs)
            .map(|k| self.seed(k).to_string())
            .collect();
        let pick = |f: fn(&RunResult) -> f64| results.iter().map(f).collect::<Vec<f64>>();
        Ok(Table::new(
            "runs",
            vec![
                Column::u32("run", "1", "run index", (0..self.params.runs).collect()),
                Column::text("seed", "seed of the run's initial state", seeds),
                Column::f64(
                    "lineages",
                    "1",
                    "lineages in the tagged estimator",
                    pick(|r| r.lineages as f64),
                ),
                Column::f64(
                    "thermal_lineages",
                    "1",
                    "lineages in the thermal estimator (|u| <= 3 at the start)",
                    pick(|r| r.thermal.lineages as f64),
                ),
                Column::f64(
                    "energy_error",
                    "1",
                    "|E(t_end) - E(0)| / E(0)",
                    pick(|r| r.energy_error),
                ),
                Column::f64(
                    "momentum_error",
                    "v_th",
                    "|P(t_end) - P(0)|",
                    pick(|r| r.momentum_error),
                ),
                Column::f64(
                    "macro_steps",
                    "1",
                    "macro steps of the cluster stepping (accepted steps of a whole ring)",
                    pick(|r| r.macro_steps as f64),
                ),
                Column::f64(
                    "pair_forces",
                    "1",
                    "pair-force evaluations",
                    pick(|r| r.pair_forces as f64),
                ),
                Column::u32(
                    "bound_pairs_start",
                    "1",
                    "bound neighbour pairs (w^2/4 + U < 0) in the initial state",
                    results.iter().map(|r| r.bound_pairs[0] as u32).collect(),
                ),
                Column::u32(
                    "bound_pairs_end",
                    "1",
                    "bound neighbour pairs at the last sample time",
                    results.iter().map(|r| r.bound_pairs[1] as u32).collect(),
                ),
                Column::f64(
                    "invariant_drift",
                    "v_th",
                    "largest change of a Lax eigenvalue (rapidity) over the run: the n = 2 Sutherland ring's conservation check (NaN otherwise)",
                    pick(|r| r.invariant_drift),
                ),
            ],
        )?
        .with_metadata(
            "ternary.description",
            "conservation diagnostics and work per run".into(),
        ))
    }
}

impl Stage for MdStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("md", &self.params.name)
    }

    fn version(&self) -> u32 {
        7
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["h", "summary", "runs", "pairs"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        Vec::new()
    }

    fn work_units(&self) -> u64 {
        u64::from(self.params.runs)
    }

    fn run(&self, _inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let results = self.params.potential.visit(Runs {
            stage: self,
            progress,
        })?;
        Ok(vec![
            self.h_table(&results)?,
            self.summary_table(&results)?,
            self.runs_table(&results)?,
            self.pairs_table(&results)?,
        ])
    }
}
