//! `near_integrable`: how the relaxation rates of the inverse power law
//! `r^-n` vanish at the Calogero point `n = 2` (issue 35). Reads the
//! `spectrum_summary` of every planned inverse power law with `2 < n <=
//! spectrum.near_integrable_max_n`, tabulates `Gamma` and the two gaps
//! against `n - 2`, and fits each (and the gaps over `Gamma`) with
//! `rate = A (n - 2)^p exp(q (n - 2))` (`scaling::fit_near_integrable`)
//! over the rates the spectrum resolves. Every potential draws its scenes
//! from the same random stream, so the rates' errors are correlated: the
//! fits are generalized least squares with the covariance of `ln rate`
//! across potentials, the jackknife's over the randomizations
//! (`spectrum_jackknife`), inflated so that its inverse is unbiased
//! (`stats::estimated_covariance_inflation`). Rates in `rho^2 l v_th`.

use serde_json::Value;

use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::physics::potential::Potential;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::scaling::{LogRates, NearIntegrableLaw, fit_near_integrable};
use crate::stats::{Estimate, estimated_covariance_inflation, jackknife_covariance};

/// The `near_integrable` stage.
pub struct NearIntegrableStage {
    /// Inverse power laws with `n > 2`, each with a planned spectrum.
    potentials: Vec<Potential>,
}

impl NearIntegrableStage {
    /// The stage over these inverse power laws with `n > 2` (each with a
    /// planned spectrum; [`crate::plan`] picks them).
    pub fn new(potentials: Vec<Potential>) -> NearIntegrableStage {
        NearIntegrableStage { potentials }
    }
}

/// Rates a fit needs: three coefficients and one degree of freedom.
const FITTED_RATES_MIN: usize = 4;

/// A quantity of the spectrum with its values on the randomizations with
/// each one left out.
struct Jackknifed {
    estimate: Estimate,
    left_out: Vec<f64>,
}

/// One generator's gap (the gas's linearized operator or one particle's
/// tagged generator).
struct GeneratorGap {
    /// The slowest non-conserved relaxation rate, `rho^2 l v_th`.
    gap: Jackknifed,
    /// `gap / Gamma`, per replicate.
    ratio: Jackknifed,
    /// Modes of the estimated generator that grow (noise).
    growing_modes: u32,
}

/// One potential's rates.
struct NearIntegrableRates {
    potential: String,
    /// `n - 2`.
    excess: f64,
    /// `Gamma`, `rho^2 l v_th`.
    variance_rate: Jackknifed,
    /// The gas's gap.
    gas: GeneratorGap,
    /// One particle's gap.
    particle: GeneratorGap,
}

/// A fitted quantity: its name, how it is read from a potential's rates,
/// and the exponent perturbation theory predicts.
type Quantity = (&'static str, fn(&NearIntegrableRates) -> &Jackknifed, f64);

/// The quantities fitted.
const QUANTITIES: [Quantity; 5] = [
    ("variance_rate", |r| &r.variance_rate, 2.0),
    ("gap", |r| &r.gas.gap, 2.0),
    ("particle_gap", |r| &r.particle.gap, 2.0),
    ("gap_over_variance_rate", |r| &r.gas.ratio, 0.0),
    (
        "particle_gap_over_variance_rate",
        |r| &r.particle.ratio,
        0.0,
    ),
];

/// One fitted quantity.
struct QuantityFit {
    quantity: &'static str,
    fitted: Vec<String>,
    law: Option<NearIntegrableLaw>,
    expected_exponent: f64,
}

impl NearIntegrableStage {
    /// The rates of `potential` from its spectrum summary, and their
    /// leave-one-out values from its jackknife table.
    fn rates(inputs: &[Input], potential: &Potential) -> Result<NearIntegrableRates, StageError> {
        use contract::spectrum::summary::{
            GAP, GAP_OVER_VARIANCE_RATE, GENERATOR, GROWING_MODES, TABLE, VARIANCE_RATE,
        };
        use contract::spectrum::{FULL, TAGGED, jackknife};
        let instance = instances::spectrum(potential);
        let table = TABLE.find(inputs, &instance)?;
        let (gaps, ratios) = (GAP.read(table)?, GAP_OVER_VARIANCE_RATE.read(table)?);
        let growing = GROWING_MODES.read(table)?;
        let left_out = jackknife::TABLE.find(inputs, &instance)?;
        let generators = jackknife::GENERATOR.read(left_out)?;
        let (gammas, gaps_left_out) = (
            jackknife::VARIANCE_RATE.read(left_out)?,
            jackknife::GAP.read(left_out)?,
        );
        let of_generator = |values: &[f64], generator: &str| -> Vec<f64> {
            let rows = generators.iter().zip(values);
            rows.filter(|(g, _)| g.as_str() == generator)
                .map(|(_, v)| *v)
                .collect()
        };
        let gamma_left_out = of_generator(&gammas, TAGGED);
        let of = |generator: &str| -> Result<GeneratorGap, StageError> {
            let row = GENERATOR.row_of(table, generator)?;
            let gap_left_out = of_generator(&gaps_left_out, generator);
            let ratio_left_out = gap_left_out
                .iter()
                .zip(&gamma_left_out)
                .map(|(gap, gamma)| gap / gamma)
                .collect();
            Ok(GeneratorGap {
                gap: Jackknifed {
                    estimate: gaps[row],
                    left_out: gap_left_out,
                },
                ratio: Jackknifed {
                    estimate: ratios[row],
                    left_out: ratio_left_out,
                },
                growing_modes: growing[row],
            })
        };
        Ok(NearIntegrableRates {
            potential: potential.id(),
            excess: potential.family().length_exponent().unwrap_or(f64::NAN) - 2.0,
            variance_rate: Jackknifed {
                estimate: VARIANCE_RATE.read(table)?[GENERATOR.row_of(table, TAGGED)?],
                left_out: gamma_left_out.clone(),
            },
            gas: of(FULL)?,
            particle: of(TAGGED)?,
        })
    }
}

/// An error unless every potential's spectrum has as many randomizations
/// as the first's: the covariance pairs randomization `r` of one potential
/// with `r` of another.
fn same_randomizations(rates: &[NearIntegrableRates]) -> Result<(), StageError> {
    let count = |r: &NearIntegrableRates| r.variance_rate.left_out.len();
    match rates.iter().find(|r| count(r) != count(&rates[0])) {
        Some(other) => Err(StageError::Input(format!(
            "the spectra of {} and {} have {} and {} randomizations: the near-integrable fits pair them one by one",
            rates[0].potential,
            other.potential,
            count(&rates[0]),
            count(other)
        ))),
        None => Ok(()),
    }
}

/// The near-integrable law of `quantity` over the rates that resolve it,
/// with their covariance.
fn quantity_fit(
    rates: &[NearIntegrableRates],
    (quantity, value, expected_exponent): Quantity,
) -> QuantityFit {
    let resolved: Vec<&NearIntegrableRates> = rates
        .iter()
        .filter(|r| contract::near_integrable::resolved(value(r).estimate))
        .collect();
    let excess: Vec<f64> = resolved.iter().map(|r| r.excess).collect();
    let law = (resolved.len() >= FITTED_RATES_MIN)
        .then(|| correlated(&resolved, value))
        .flatten()
        .and_then(|rates| fit_near_integrable(&excess, &rates));
    QuantityFit {
        quantity,
        fitted: resolved.iter().map(|r| r.potential.clone()).collect(),
        law,
        expected_exponent,
    }
}

/// The rates of `value` with the covariance of their logarithms from the
/// leave-one-out values, inflated for its estimation from the
/// randomizations; `None` when there are too few randomizations for it.
fn correlated(
    resolved: &[&NearIntegrableRates],
    value: fn(&NearIntegrableRates) -> &Jackknifed,
) -> Option<LogRates> {
    let randomizations = value(resolved[0]).left_out.len();
    let inflation = estimated_covariance_inflation(randomizations, resolved.len())?;
    let logs: Vec<Vec<f64>> = resolved
        .iter()
        .map(|r| value(r).left_out.iter().map(|&x| libm::log(x)).collect())
        .collect();
    Some(LogRates {
        rates: resolved.iter().map(|r| value(r).estimate.mean).collect(),
        log_covariance: jackknife_covariance(&logs)
            .into_iter()
            .map(|c| c * inflation)
            .collect(),
    })
}

/// The rates table.
fn rates_table(rates: &[NearIntegrableRates]) -> Result<Table, StageError> {
    use contract::near_integrable::rates::*;
    Ok(Rows::new(rates)
        .with(POTENTIAL, |r| r.potential.clone())
        .with(EXCESS, |r| r.excess)
        .estimate(VARIANCE_RATE, |r| r.variance_rate.estimate)
        .estimate(GAP, |r| r.gas.gap.estimate)
        .estimate(PARTICLE_GAP, |r| r.particle.gap.estimate)
        .estimate(GAP_OVER_VARIANCE_RATE, |r| r.gas.ratio.estimate)
        .estimate(PARTICLE_GAP_OVER_VARIANCE_RATE, |r| {
            r.particle.ratio.estimate
        })
        .with(GROWING_MODES, |r| r.gas.growing_modes)
        .with(PARTICLE_GROWING_MODES, |r| r.particle.growing_modes)
        .table(&TABLE)?)
}

/// The fits table.
fn fits_table(fits: &[QuantityFit]) -> Result<Table, StageError> {
    use contract::near_integrable::fits::*;
    let not_fitted = Estimate {
        mean: f64::NAN,
        stderr: f64::NAN,
    };
    let law = |f: &QuantityFit, part: fn(&NearIntegrableLaw) -> Estimate| {
        f.law.as_ref().map_or(not_fitted, part)
    };
    Ok(Rows::new(fits)
        .with(QUANTITY, |f| f.quantity.to_string())
        .with(FITTED, |f| f.fitted.join(", "))
        .with(POINTS, |f| f.fitted.len() as u32)
        .estimate(EXPONENT, |f| law(f, |l| l.exponent))
        .estimate(NEXT_ORDER_EXPONENT, |f| {
            f.law
                .and_then(|l| l.next_order_exponent)
                .unwrap_or(not_fitted)
        })
        .with(EXPECTED_EXPONENT, |f| f.expected_exponent)
        .optional(EXPONENT_ERROR, |f| {
            f.law.map(|l| l.exponent_with_truncation().stderr)
        })
        .optional(EXPONENT_Z, |f| {
            f.law.map(|l| {
                let exponent = l.exponent_with_truncation();
                (exponent.mean - f.expected_exponent) / exponent.stderr
            })
        })
        .estimate(AMPLITUDE, |f| law(f, |l| l.amplitude))
        .estimate(CORRECTION, |f| law(f, |l| l.correction))
        .optional(CHI2, |f| f.law.map(|l| l.goodness.chi2))
        .with(DOF, |f| f.law.map_or(0, |l| l.goodness.dof as u32))
        .optional(P_VALUE, |f| f.law.map(|l| l.goodness.p_value()))
        .table(&TABLE)?)
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for NearIntegrableStage {
    fn id(&self) -> InstanceId {
        instances::near_integrable()
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::json!({ "potentials": self.potentials })
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::near_integrable::{fits, rates};
        &[rates::TABLE.name, fits::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.potentials.iter().map(instances::spectrum).collect()
    }

    fn work_units(&self) -> u64 {
        self.potentials.len() as u64
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let rates = self
            .potentials
            .iter()
            .map(|potential| {
                let rates = Self::rates(inputs, potential)?;
                progress.advance(1);
                Ok(rates)
            })
            .collect::<Result<Vec<_>, StageError>>()?;
        same_randomizations(&rates)?;
        let fits: Vec<QuantityFit> = QUANTITIES
            .iter()
            .map(|&quantity| quantity_fit(&rates, quantity))
            .collect();
        Ok(vec![rates_table(&rates)?, fits_table(&fits)?])
    }
}
