//! `compare`: molecular dynamics against the Boltzmann evolution (physics.md
//! §7, §8). For every `md` ring, `h(u, t_f)` of the master equation with the
//! translation-invariant kernel (exact in Fourier space at the ring's `t_f`
//! in units of its own `rho^2 l v_th`; at `Gamma t_f ~ 2e-4` the kernel's `u'`
//! dependence is negligible) on the ring's bins, with jackknife errors, and the
//! chi-square of both MD estimators against it. The scaling collapse: the
//! tagged `h` of every ring against the first one's. The finite-size and
//! density study: the tagged window variance of every ring against
//! Boltzmann's, with the ring's `N` and `rho l`.

use serde::Serialize;
use serde_json::Value;

use super::collisions::CollisionsStage;
use super::kernel::{collision_events, target_of};
use crate::analysis::{
    FiniteSize, RingBins, boltzmann_on_bins, finite_size, thermal_window_variance_rates,
};
use crate::binning::Bins;
use crate::config::{KernelParams, MdParams};
use crate::evolve::convolution;
use crate::pipeline::table::{f64_values, text_values};
use crate::pipeline::{Column, Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::{ChiSquare, Estimate, Replicated, chi_square};

/// Resolved parameters of the `compare` stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareParams {
    /// The kernel (potential, `u' = 0`, dilute, bins).
    pub kernel: KernelParams,
    /// The collisions instance that reweights to every thermal start
    /// (`|u'| <= 3`): the thermal estimator's reference.
    pub thermal_collisions: String,
    /// The rings compared.
    pub systems: Vec<MdParams>,
}

/// The `compare` stage.
pub struct CompareStage {
    params: CompareParams,
}

/// One ring's MD estimators, read from its `h` and `summary` tables.
struct MdEstimates {
    du: Vec<f64>,
    published: Vec<Estimate>,
    tagged: Vec<Estimate>,
    /// Window variance `sum (u - u')^2 h du` of the tagged estimator.
    tagged_variance: Estimate,
    /// Window variance of the thermal estimator (every lineage).
    thermal_variance: Estimate,
}

fn read_md(input: &Input) -> Result<MdEstimates, StageError> {
    let batch = input
        .tables
        .get("h")
        .ok_or_else(|| StageError::Input(format!("{} has no h table", input.id)))?;
    let pair = |mean: &str, error: &str| -> Result<Vec<Estimate>, StageError> {
        Ok(f64_values(batch, mean)?
            .into_iter()
            .zip(f64_values(batch, error)?)
            .map(|(mean, stderr)| Estimate { mean, stderr })
            .collect())
    };
    let summary = input
        .tables
        .get("summary")
        .ok_or_else(|| StageError::Input(format!("{} has no summary table", input.id)))?;
    let estimators = text_values(summary, "estimator")?;
    let (means, errors) = (
        f64_values(summary, "window_variance")?,
        f64_values(summary, "window_variance_stderr")?,
    );
    let variance = |name: &str| -> Result<Estimate, StageError> {
        let row = estimators
            .iter()
            .position(|e| e == name)
            .ok_or_else(|| StageError::Input(format!("{} summary has no {name} row", input.id)))?;
        Ok(Estimate {
            mean: means[row],
            stderr: errors[row],
        })
    };
    Ok(MdEstimates {
        du: f64_values(batch, "du")?,
        published: pair("h_published", "h_published_stderr")?,
        tagged: pair("h_tagged", "h_tagged_stderr")?,
        tagged_variance: variance("tagged")?,
        thermal_variance: variance("thermal")?,
    })
}

/// Half-width of a ring's estimator window (the outer edges of its bins), `v_th`.
fn half_window(system: &MdParams) -> f64 {
    Bins::for_window(system.window, system.bin_width).half_width()
}

/// A ring's estimator bins.
fn ring_bins<'a>(system: &MdParams, ring: &'a MdEstimates) -> RingBins<'a> {
    RingBins {
        du: &ring.du,
        width: system.bin_width,
        window: system.window,
    }
}

/// One goodness-of-fit row.
struct Fit {
    ring: String,
    reference: String,
    estimator: String,
    chi: ChiSquare,
}

impl CompareStage {
    /// The kernel's collisions, then the thermal reference's when they differ.
    fn collision_inputs(&self) -> Vec<InstanceId> {
        CollisionsStage::instances(
            &self.params.kernel.potential.id(),
            &self.params.thermal_collisions,
        )
    }

    /// A compare stage with resolved parameters.
    pub fn new(params: CompareParams) -> CompareStage {
        CompareStage { params }
    }

    /// Boltzmann `h` of every ring on its MD bins, on all kernel replicates
    /// and with each left out (jackknife).
    fn boltzmann(
        &self,
        collisions: &Input,
        rings: &[MdEstimates],
    ) -> Result<Vec<Replicated<Vec<f64>>>, StageError> {
        let (events, draws, _) = collision_events(collisions)?;
        let kernel = &self.params.kernel;
        let bins = Bins::for_window(kernel.window, kernel.bin_width);
        let rates = convolution::replicated_kernel(&events, &draws, &target_of(kernel), &bins);
        Ok(self
            .params
            .systems
            .iter()
            .zip(rings)
            .map(|(system, ring)| {
                let time = self.scaled_time(system);
                boltzmann_on_bins(&rates, bins.width, time, ring_bins(system, ring))
            })
            .collect())
    }

    /// A ring's final time `t_f` in units of its own `1 / (rho^2 l v_th)`.
    fn scaled_time(&self, system: &MdParams) -> f64 {
        let exponent = self.params.kernel.potential.length_exponent();
        system.final_time_ns * system.gas.rate_per_ns(1.0, exponent)
    }

    /// Per ring, per kernel replicate: the self kernel's window variance rate
    /// (truncated at the ring's half window) averaged over thermal starts,
    /// `rho^2 l v_th` (`analysis::thermal_window_variance_rates`).
    fn thermal_rates(&self, collisions: &Input) -> Result<Vec<Vec<f64>>, StageError> {
        let (events, draws, _) = collision_events(collisions)?;
        let edges: Vec<f64> = self.params.systems.iter().map(half_window).collect();
        let target = target_of(&self.params.kernel);
        Ok(thermal_window_variance_rates(
            &events, &draws, &target, &edges,
        ))
    }

    /// The finite-size and density study: per ring, its size, density and
    /// scaled time, and the window variances of MD against Boltzmann's: of
    /// the tagged estimator (starts near `u'`, against the Boltzmann `h`) and
    /// of the thermal one (every start, against `t` times the thermal rate;
    /// first order in `Gamma t`).
    fn finite_size(
        &self,
        rings: &[MdEstimates],
        boltzmann: &[Replicated<Vec<f64>>],
        thermal_rates: &[Vec<f64>],
    ) -> Result<Table, StageError> {
        let mut columns: [Vec<f64>; 14] = Default::default();
        for (((system, ring), predicted), rates) in self
            .params
            .systems
            .iter()
            .zip(rings)
            .zip(boltzmann)
            .zip(thermal_rates)
        {
            let time = self.scaled_time(system);
            let FiniteSize { tagged, thermal } = finite_size(
                ring.tagged_variance,
                ring.thermal_variance,
                predicted,
                ring_bins(system, ring),
                rates,
                time,
            );
            let row = [
                f64::from(system.particles - 1) / system.circumference,
                time,
                tagged.md.mean,
                tagged.md.stderr,
                tagged.boltzmann.mean,
                tagged.boltzmann.stderr,
                tagged.ratio.mean,
                tagged.ratio.stderr,
                thermal.md.mean,
                thermal.md.stderr,
                thermal.boltzmann.mean,
                thermal.boltzmann.stderr,
                thermal.ratio.mean,
                thermal.ratio.stderr,
            ];
            columns.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
        }
        let [
            density,
            time,
            md,
            md_err,
            b,
            b_err,
            ratio,
            ratio_err,
            thermal_md,
            thermal_md_err,
            thermal_b,
            thermal_b_err,
            thermal_ratio,
            thermal_ratio_err,
        ] = columns;
        let names = self.params.systems.iter().map(|s| s.name.clone()).collect();
        let particles = self.params.systems.iter().map(|s| s.particles).collect();
        let variance = "v_th^2";
        Ok(Table::new(
            "finite_size",
            vec![
                Column::text("ring", "md system", names),
                Column::u32("particles", "1", "N", particles),
                Column::f64("density", "1", "rho l = (N - 1) l / (2 pi R)", density),
                Column::f64(
                    "scaled_time",
                    "1",
                    "rho^2 l v_th t_f (Gamma t_f = a_n times this)",
                    time,
                ),
                Column::f64(
                    "md_variance",
                    variance,
                    "tagged estimator: window variance sum (u - u')^2 h du at t_f",
                    md,
                ),
                Column::f64(
                    "md_variance_stderr",
                    variance,
                    "standard error over runs",
                    md_err,
                ),
                Column::f64(
                    "boltzmann_variance",
                    variance,
                    "the same of the Boltzmann h (dilute kernel) on the ring's bins",
                    b,
                ),
                Column::f64(
                    "boltzmann_variance_stderr",
                    variance,
                    "jackknife over the kernel's randomizations",
                    b_err,
                ),
                Column::f64(
                    "ratio",
                    "1",
                    "md_variance / boltzmann_variance: 1 at large N and small rho l",
                    ratio,
                ),
                Column::f64(
                    "ratio_stderr",
                    "1",
                    "propagated from both standard errors",
                    ratio_err,
                ),
                Column::f64("thermal_md_variance", variance, "thermal estimator: mean over every lineage starting with |u| <= 3 of its squared change within the window", thermal_md),
                Column::f64("thermal_md_variance_stderr", variance, "standard error over runs", thermal_md_err),
                Column::f64("thermal_boltzmann_variance", variance, "t_f times the self kernel's window variance rate averaged over thermal starts (f0 on [-3, 3]); first order in Gamma t_f", thermal_b),
                Column::f64("thermal_boltzmann_variance_stderr", variance, "standard error over the kernel's randomizations", thermal_b_err),
                Column::f64("thermal_ratio", "1", "thermal_md_variance / thermal_boltzmann_variance", thermal_ratio),
                Column::f64("thermal_ratio_stderr", "1", "propagated from both standard errors", thermal_ratio_err),
            ],
        )?
        .with_metadata(
            "ternary.description",
            "finite-size and density study: MD window variance against Boltzmann per ring".into(),
        ))
    }
}

impl Stage for CompareStage {
    fn id(&self) -> InstanceId {
        InstanceId::new("compare", "study")
    }

    fn version(&self) -> u32 {
        3
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &["comparison", "goodness", "finite_size"]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let mut ids = self.collision_inputs();
        ids.extend(
            self.params
                .systems
                .iter()
                .map(|s| InstanceId::new("md", &s.name)),
        );
        ids
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let collisions = self.collision_inputs().len();
        let rings: Vec<MdEstimates> = inputs[collisions..]
            .iter()
            .map(read_md)
            .collect::<Result<_, _>>()?;
        let replicated = self.boltzmann(&inputs[0], &rings)?;
        let boltzmann: Vec<Vec<Estimate>> = replicated.iter().map(Replicated::values).collect();
        let mut columns: [Vec<f64>; 7] = Default::default();
        let mut names = Vec::new();
        let mut fits: Vec<Fit> = Vec::new();
        let mut record = |ring: &str, reference: &str, estimator: &str, chi: ChiSquare| {
            fits.push(Fit {
                ring: ring.to_string(),
                reference: reference.to_string(),
                estimator: estimator.to_string(),
                chi,
            });
        };
        for ((system, ring), predicted) in self.params.systems.iter().zip(&rings).zip(&boltzmann) {
            for (k, boltzmann) in predicted.iter().enumerate() {
                names.push(system.name.clone());
                let row = [
                    ring.du[k],
                    boltzmann.mean,
                    boltzmann.stderr,
                    ring.published[k].mean,
                    ring.published[k].stderr,
                    ring.tagged[k].mean,
                    ring.tagged[k].stderr,
                ];
                columns.iter_mut().zip(row).for_each(|(c, v)| c.push(v));
            }
            record(
                &system.name,
                "boltzmann",
                "published",
                chi_square(&ring.published, predicted),
            );
            record(
                &system.name,
                "boltzmann",
                "tagged",
                chi_square(&ring.tagged, predicted),
            );
            if let (Some(first), Some(reference)) = (rings.first(), self.params.systems.first())
                && reference.name != system.name
                && first.du == ring.du
            {
                record(
                    &system.name,
                    &reference.name,
                    "tagged",
                    chi_square(&ring.tagged, &first.tagged),
                );
            }
        }
        progress.advance(1);
        let [
            du,
            h_b,
            h_b_err,
            published,
            published_err,
            tagged,
            tagged_err,
        ] = columns;
        let density = "1/v_th";
        let comparison = Table::new(
            "comparison",
            vec![
                Column::text("ring", "md system", names),
                Column::f64("du", "v_th", "bin centre relative to u'", du),
                Column::f64("h_boltzmann", density, "master equation with the translation-invariant kernel at t_f, exact in Fourier space, on the ring's bins", h_b),
                Column::f64("h_boltzmann_stderr", density, "jackknife standard error over the kernel's randomizations", h_b_err),
                Column::f64("h_published", density, "MD, published estimator", published),
                Column::f64("h_published_stderr", density, "standard error over runs", published_err),
                Column::f64("h_tagged", density, "MD, tagged-velocity estimator", tagged),
                Column::f64("h_tagged_stderr", density, "standard error over runs", tagged_err),
            ],
        )?
        .with_metadata("ternary.description", "h(u, t_f) of every ring: MD against Boltzmann".into());
        let text = |f: fn(&Fit) -> &String| fits.iter().map(|x| f(x).clone()).collect::<Vec<_>>();
        let (system, reference, estimator) = (
            text(|f| &f.ring),
            text(|f| &f.reference),
            text(|f| &f.estimator),
        );
        let chi2: Vec<f64> = fits.iter().map(|f| f.chi.chi2).collect();
        let dof: Vec<u32> = fits.iter().map(|f| f.chi.dof as u32).collect();
        let reduced: Vec<f64> = fits.iter().map(|f| f.chi.per_dof()).collect();
        let goodness = Table::new(
            "goodness",
            vec![
                Column::text("ring", "md system", system),
                Column::text(
                    "reference",
                    "boltzmann, or the ring it is compared with (scaling collapse)",
                    reference,
                ),
                Column::text("estimator", "MD estimator", estimator),
                Column::f64(
                    "chi2",
                    "1",
                    "sum over bins of (difference / combined standard error)^2",
                    chi2,
                ),
                Column::u32(
                    "dof",
                    "1",
                    "bins where the MD estimate has a nonzero error",
                    dof,
                ),
                Column::f64(
                    "chi2_per_dof",
                    "1",
                    "chi2 / dof: ~1 when the two agree within errors",
                    reduced,
                ),
            ],
        )?
        .with_metadata(
            "ternary.description",
            "goodness of fit of MD against Boltzmann, and of the scaling collapse".into(),
        );
        let thermal_rates = self.thermal_rates(&inputs[collisions - 1])?;
        let finite_size = self.finite_size(&rings, &replicated, &thermal_rates)?;
        Ok(vec![comparison, goodness, finite_size])
    }
}
