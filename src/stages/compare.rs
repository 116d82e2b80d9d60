//! `compare`: molecular dynamics against the Boltzmann evolution (physics.md
//! §7, §8). For every `md` ring, `h(u, t_f)` of the master equation with the
//! translation-invariant kernel (exact in Fourier space at the ring's `t_f`
//! in units of its own `rho^2 l v_th`; at `Gamma t_f ~ 2e-4` the kernel's `u'`
//! dependence is negligible) on the ring's bins, with jackknife errors, and the
//! chi-square of both MD estimators against it, beside the ratio of each
//! estimator's window variance to Boltzmann's (the test with power against a
//! broadening) and the verdict of both (`analysis::agreement`). The scaling
//! collapse: the tagged `h` of every ring against the first one's. The
//! finite-size and density study: the window variances of every ring against
//! Boltzmann's, with the ring's `N` and `rho l`. Rings of other potentials
//! that kick (Lennard-Jones) are set against their own potential's kernel:
//! `h` and the goodness of fit only. A Lennard-Jones kernel holds three-body
//! recombination (a pair leaving bound) among its outcomes, while the ring's
//! lineages of bound pairs swing through the window as they oscillate: its
//! chi-square measures how far the dilute kernel describes such a ring, not
//! a check it must pass.

use serde::Serialize;
use serde_json::Value;

use crate::analysis::{
    CollapseRing, FiniteSize, Goodness, RingBins, RingH, VarianceRatio, WindowVariances, agreement,
    boltzmann_on_bins, finite_size, goodness, ratio_z, scaling_collapse,
    thermal_window_variance_rates,
};
use crate::binning::Bins;
use crate::config::{KernelParams, MdParams};
use crate::contract::instances;
use crate::contract::readers::collision_events;
use crate::contract::{self, Rows};
use crate::evolve::convolution;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::{ChiSquare, Estimate, MIN_TEST_DOF, Replicated};

/// Resolved parameters of the `compare` stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareParams {
    /// The kernel (potential, `u' = 0`, dilute, bins).
    pub kernel: KernelParams,
    /// The collisions instance that reweights to every thermal start
    /// (`|u'| <= 3`): the thermal estimator's reference.
    pub thermal_collisions: String,
    /// The rings compared (the kernel's potential, `u' = 0`).
    pub systems: Vec<MdParams>,
    /// Dilute kernels at `u' = 0` of other potentials, one per potential.
    pub other_kernels: Vec<KernelParams>,
    /// Rings of those potentials at `u' = 0`, each against its potential's
    /// kernel: `h` and the goodness of fit against Boltzmann only.
    pub other_systems: Vec<MdParams>,
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
    /// Window variances `sum (u - u')^2 h du` of the three estimators.
    variances: WindowVariances,
    /// Tagged lineages of each run.
    lineages: Vec<f64>,
}

fn read_md(input: &Input) -> Result<MdEstimates, StageError> {
    use contract::estimator::{PUBLISHED, TAGGED, THERMAL};
    use contract::md::{h, runs, summary};
    let batch = h::TABLE.of(input)?;
    let moments = summary::TABLE.of(input)?;
    let variances = summary::WINDOW_VARIANCE.read(moments)?;
    let variance = |estimator: &str| -> Result<Estimate, StageError> {
        Ok(variances[summary::ESTIMATOR.row_of(moments, estimator)?])
    };
    Ok(MdEstimates {
        du: h::DU.read(batch)?,
        published: h::H_PUBLISHED.read(batch)?,
        tagged: h::H_TAGGED.read(batch)?,
        variances: WindowVariances {
            published: variance(PUBLISHED)?,
            tagged: variance(TAGGED)?,
            thermal: variance(THERMAL)?,
        },
        lineages: runs::LINEAGES.read(runs::TABLE.of(input)?)?,
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

/// A ring's estimates as the goodness of fit takes them.
fn ring_h<'a>(system: &MdParams, ring: &'a MdEstimates) -> RingH<'a> {
    RingH {
        bins: Bins::for_window(system.window, system.bin_width),
        u_prime: system.u_prime,
        particles: system.particles as usize,
        published: &ring.published,
        tagged: &ring.tagged,
        lineages: &ring.lineages,
    }
}

/// A ring's estimates, Boltzmann `h` and scaled time as the scaling collapse
/// takes them.
fn collapse_ring<'a>(
    system: &MdParams,
    ring: &'a MdEstimates,
    predicted: &'a [Estimate],
) -> CollapseRing<'a> {
    CollapseRing {
        h: ring_h(system, ring),
        du: &ring.du,
        predicted,
        time: system.scaled_final_time(),
    }
}

/// A ring, its MD estimates and its Boltzmann `h` (jackknife estimates).
type Compared<'a> = (&'a MdParams, &'a MdEstimates, Vec<Estimate>);

/// One goodness-of-fit row.
struct Fit {
    ring: String,
    reference: String,
    estimator: String,
    /// The shape's chi-squares (none for the thermal estimator, whose
    /// reference is a rate, not an `h`).
    shape: Option<Goodness>,
    /// The window variance against the reference's (rings in the
    /// finite-size study, against Boltzmann).
    variance: Option<VarianceRatio>,
}

/// A ring's finite-size comparison at its scaled time.
type Sized<'a> = (&'a MdParams, f64, FiniteSize);

impl CompareStage {
    /// The kernel's collisions, then the thermal reference's when they
    /// differ, then those of each other kernel.
    fn collision_inputs(&self) -> Vec<InstanceId> {
        let mut ids = instances::collisions_of(
            &self.params.kernel.potential.id(),
            &self.params.thermal_collisions,
        );
        ids.extend(
            self.params
                .other_kernels
                .iter()
                .map(|kernel| instances::collisions(&kernel.potential.id())),
        );
        ids
    }

    /// A compare stage with resolved parameters.
    pub fn new(params: CompareParams) -> CompareStage {
        CompareStage { params }
    }

    /// Boltzmann `h` of `rings` under `kernel` (from its `collisions`) on
    /// their MD bins, on all kernel replicates and with each left out
    /// (jackknife).
    fn boltzmann(
        collisions: &Input,
        kernel: &KernelParams,
        rings: &[(&MdParams, &MdEstimates)],
    ) -> Result<Vec<Replicated<Vec<f64>>>, StageError> {
        let (events, draws, _) = collision_events(collisions)?;
        let bins = Bins::for_window(kernel.window, kernel.bin_width);
        let rates = convolution::replicated_kernel(&events, &draws, &kernel.target(), &bins);
        Ok(rings
            .iter()
            .map(|(system, ring)| {
                let time = system.scaled_final_time();
                boltzmann_on_bins(&rates, bins.width, time, ring_bins(system, ring))
            })
            .collect())
    }

    /// Boltzmann `h` (jackknife estimates) of every other ring under its
    /// potential's kernel, in ring order; `collisions` those of the other
    /// kernels, in kernel order.
    fn other_boltzmann(
        &self,
        collisions: &[Input],
        rings: &[MdEstimates],
    ) -> Result<Vec<Vec<Estimate>>, StageError> {
        let systems = &self.params.other_systems;
        let mut predicted = vec![Vec::new(); systems.len()];
        for (kernel, input) in self.params.other_kernels.iter().zip(collisions) {
            let members: Vec<usize> = (0..systems.len())
                .filter(|&k| systems[k].potential == kernel.potential)
                .collect();
            let pairs: Vec<(&MdParams, &MdEstimates)> =
                members.iter().map(|&k| (&systems[k], &rings[k])).collect();
            for (k, h) in members.iter().zip(Self::boltzmann(input, kernel, &pairs)?) {
                predicted[*k] = h.values();
            }
        }
        Ok(predicted)
    }

    /// Per ring, per kernel replicate: the self kernel's window variance rate
    /// (truncated at the ring's half window) averaged over thermal starts,
    /// `rho^2 l v_th` (`analysis::thermal_window_variance_rates`).
    fn thermal_rates(&self, collisions: &Input) -> Result<Vec<Vec<f64>>, StageError> {
        let (events, draws, _) = collision_events(collisions)?;
        let edges: Vec<f64> = self.params.systems.iter().map(half_window).collect();
        let target = self.params.kernel.target();
        Ok(thermal_window_variance_rates(
            &events, &draws, &target, &edges,
        ))
    }

    /// The finite-size and density study: per ring, its scaled time and the
    /// window variances of MD against Boltzmann's: of the published and
    /// tagged estimators (starts near `u'`, against the Boltzmann `h`) and of
    /// the thermal one (every start, against `t` times the thermal rate;
    /// first order in `Gamma t`).
    fn finite_sizes<'a>(
        &'a self,
        rings: &[MdEstimates],
        boltzmann: &[Replicated<Vec<f64>>],
        thermal_rates: &[Vec<f64>],
    ) -> Vec<Sized<'a>> {
        self.params
            .systems
            .iter()
            .zip(rings)
            .zip(boltzmann)
            .zip(thermal_rates)
            .map(|(((system, ring), predicted), rates)| {
                let time = system.scaled_final_time();
                let bins = ring_bins(system, ring);
                let compared = finite_size(ring.variances, predicted, bins, rates, time);
                (system, time, compared)
            })
            .collect()
    }

    /// The finite-size table: per ring its size and density beside the
    /// tagged and thermal comparisons.
    fn finite_size_table(sizes: &[Sized]) -> Result<Table, StageError> {
        use contract::compare::finite_size::*;
        Ok(Rows::new(sizes)
            .with(RING, |(system, ..)| system.name.clone())
            .with(PARTICLES, |(system, ..)| system.particles)
            .with(DENSITY, |(system, ..)| {
                f64::from(system.particles - 1) / system.circumference
            })
            .with(SCALED_TIME, |(_, time, _)| *time)
            .estimate(MD_VARIANCE, |(.., c)| c.tagged.md)
            .estimate(BOLTZMANN_VARIANCE, |(.., c)| c.tagged.boltzmann)
            .estimate(RATIO, |(.., c)| c.tagged.ratio)
            .estimate(THERMAL_MD_VARIANCE, |(.., c)| c.thermal.md)
            .estimate(THERMAL_BOLTZMANN_VARIANCE, |(.., c)| c.thermal.boltzmann)
            .estimate(THERMAL_RATIO, |(.., c)| c.thermal.ratio)
            .table(&TABLE)?)
    }

    /// `h` of every ring, MD against Boltzmann, bin by bin.
    fn comparison(compared: &[Compared]) -> Result<Table, StageError> {
        use contract::compare::comparison::*;
        let rows: Vec<(&str, &MdEstimates, usize, Estimate)> = compared
            .iter()
            .flat_map(|(system, ring, predicted)| {
                predicted
                    .iter()
                    .enumerate()
                    .map(move |(k, h)| (system.name.as_str(), *ring, k, *h))
            })
            .collect();
        Ok(Rows::new(&rows)
            .with(RING, |(name, ..)| name.to_string())
            .with(DU, |(_, ring, k, _)| ring.du[*k])
            .estimate(H_BOLTZMANN, |(.., h)| *h)
            .estimate(H_PUBLISHED, |(_, ring, k, _)| ring.published[*k])
            .estimate(H_TAGGED, |(_, ring, k, _)| ring.tagged[*k])
            .table(&TABLE)?)
    }

    /// Chi-square of both MD estimators against Boltzmann per ring, and of
    /// every later ring's tagged `h` against the first one's on the same
    /// bins at the same scaled time (the scaling collapse); beside each, the
    /// ratio of the estimator's window variance to the reference's where the
    /// finite-size study has it (`sizes`, the first rings of `compared`), a
    /// row of the thermal estimator with its ratio alone.
    fn fits(compared: &[Compared], sizes: &[Sized]) -> Vec<Fit> {
        use contract::compare::goodness::BOLTZMANN;
        use contract::estimator::{PUBLISHED, TAGGED, THERMAL};
        let mut fits: Vec<Fit> = Vec::new();
        let mut record = |ring: &str, reference: &str, estimator: &str, shape, variance| {
            fits.push(Fit {
                ring: ring.to_string(),
                reference: reference.to_string(),
                estimator: estimator.to_string(),
                shape,
                variance,
            });
        };
        let first = compared.first();
        for (k, (system, ring, predicted)) in compared.iter().enumerate() {
            let name = system.name.as_str();
            let h = ring_h(system, ring);
            let [published, tagged] = goodness(&h, predicted);
            let size = sizes.get(k).map(|(.., size)| size);
            record(
                name,
                BOLTZMANN,
                PUBLISHED,
                Some(published),
                size.map(|s| s.published),
            );
            record(
                name,
                BOLTZMANN,
                TAGGED,
                Some(tagged),
                size.map(|s| s.tagged),
            );
            if let Some(size) = size {
                record(name, BOLTZMANN, THERMAL, None, Some(size.thermal));
            }
            if let Some((reference, first, first_predicted)) = first
                && reference.name != system.name
                && reference.potential == system.potential
                && let Some(collapsed) = scaling_collapse(
                    &collapse_ring(system, ring, predicted),
                    &collapse_ring(reference, first, first_predicted),
                )
            {
                record(name, &reference.name, TAGGED, Some(collapsed), None);
            }
        }
        fits
    }

    /// The goodness table of `fits`, with each row's verdict.
    fn goodness_table(fits: &[Fit]) -> Result<Table, StageError> {
        use contract::compare::goodness::*;
        let model = |f: &Fit| f.shape.map(|g| g.model);
        let tested = |f: &Fit| model(f).filter(|m| m.dof >= MIN_TEST_DOF);
        let not_compared = Estimate {
            mean: f64::NAN,
            stderr: f64::NAN,
        };
        let ratio = |f: &Fit| f.variance.map(|v| v.ratio);
        Ok(Rows::new(fits)
            .with(RING, |f| f.ring.clone())
            .with(REFERENCE, |f| f.reference.clone())
            .with(ESTIMATOR, |f| f.estimator.clone())
            .optional(CHI2, |f| model(f).map(|m| m.chi2))
            .with(DOF, |f| model(f).map_or(0, |m| m.dof as u32))
            .optional(CHI2_PER_DOF, |f| tested(f).map(ChiSquare::per_dof))
            .optional(P_VALUE, |f| tested(f).map(ChiSquare::p_value))
            .optional(SAMPLE_CHI2_PER_DOF, |f| f.shape.map(|g| g.sample.per_dof()))
            .with(SAMPLE_DOF, |f| f.shape.map_or(0, |g| g.sample.dof as u32))
            .estimate(VARIANCE_RATIO, |f| ratio(f).unwrap_or(not_compared))
            .optional(VARIANCE_Z, |f| ratio(f).map(ratio_z))
            .with(VERDICT, |f| {
                agreement(model(f), ratio(f)).label().to_string()
            })
            .table(&TABLE)?)
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for CompareStage {
    fn id(&self) -> InstanceId {
        instances::compare()
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.params).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::compare::*;
        &[
            comparison::TABLE.name,
            goodness::TABLE.name,
            finite_size::TABLE.name,
        ]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let mut ids = self.collision_inputs();
        ids.extend(
            self.params
                .systems
                .iter()
                .chain(&self.params.other_systems)
                .map(|s| instances::md(&s.name)),
        );
        ids
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let main = instances::collisions_of(
            &self.params.kernel.potential.id(),
            &self.params.thermal_collisions,
        )
        .len();
        let collisions = self.collision_inputs().len();
        let read = |inputs: &[Input]| inputs.iter().map(read_md).collect::<Result<Vec<_>, _>>();
        let (rings, other_rings) = inputs[collisions..].split_at(self.params.systems.len());
        let (rings, other_rings) = (read(rings)?, read(other_rings)?);
        let pairs: Vec<(&MdParams, &MdEstimates)> =
            self.params.systems.iter().zip(&rings).collect();
        let replicated = Self::boltzmann(&inputs[0], &self.params.kernel, &pairs)?;
        let other_predicted = self.other_boltzmann(&inputs[main..collisions], &other_rings)?;
        let compared: Vec<Compared> = pairs
            .iter()
            .zip(&replicated)
            .map(|((system, ring), h)| (*system, *ring, h.values()))
            .chain(
                self.params
                    .other_systems
                    .iter()
                    .zip(&other_rings)
                    .zip(other_predicted)
                    .map(|((system, ring), h)| (system, ring, h)),
            )
            .collect();
        let comparison = Self::comparison(&compared)?;
        progress.advance(1);
        let thermal_rates = self.thermal_rates(&inputs[main - 1])?;
        let sizes = self.finite_sizes(&rings, &replicated, &thermal_rates);
        let goodness = Self::goodness_table(&Self::fits(&compared, &sizes))?;
        Ok(vec![comparison, goodness, Self::finite_size_table(&sizes)?])
    }
}
