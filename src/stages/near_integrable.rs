//! `near_integrable`: how the relaxation rates of the inverse power law
//! `r^-n` vanish at the Calogero point `n = 2` (issue 35). Reads the
//! `spectrum_summary` of every planned inverse power law with `2 < n <=
//! spectrum.near_integrable_max_n`, tabulates `Gamma` and the two gaps
//! against `n - 2`, and fits each (and the gaps over `Gamma`) with
//! `rate = A (n - 2)^p exp(q (n - 2))` (`scaling::fit_near_integrable`)
//! over the rates the spectrum resolves. Rates in `rho^2 l v_th`.

use serde_json::Value;

use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::physics::potential::Potential;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::scaling::{NearIntegrableLaw, fit_near_integrable};
use crate::stats::Estimate;

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

/// One generator's gap (the gas's linearized operator or one particle's
/// tagged generator).
struct GeneratorGap {
    /// The slowest non-conserved relaxation rate, `rho^2 l v_th`.
    gap: Estimate,
    /// `gap / Gamma`, per replicate.
    ratio: Estimate,
    /// Modes of the estimated generator that grow (noise).
    growing_modes: u32,
}

/// One potential's rates.
struct NearIntegrableRates {
    potential: String,
    /// `n - 2`.
    excess: f64,
    /// `Gamma`, `rho^2 l v_th`.
    variance_rate: Estimate,
    /// The gas's gap.
    gas: GeneratorGap,
    /// One particle's gap.
    particle: GeneratorGap,
}

/// A fitted quantity: its name, how it is read from a potential's rates,
/// and the exponent perturbation theory predicts.
type Quantity = (&'static str, fn(&NearIntegrableRates) -> Estimate, f64);

/// The quantities fitted.
const QUANTITIES: [Quantity; 5] = [
    ("variance_rate", |r| r.variance_rate, 2.0),
    ("gap", |r| r.gas.gap, 2.0),
    ("particle_gap", |r| r.particle.gap, 2.0),
    ("gap_over_variance_rate", |r| r.gas.ratio, 0.0),
    ("particle_gap_over_variance_rate", |r| r.particle.ratio, 0.0),
];

/// One fitted quantity.
struct QuantityFit {
    quantity: &'static str,
    fitted: Vec<String>,
    law: Option<NearIntegrableLaw>,
    expected_exponent: f64,
}

impl NearIntegrableStage {
    /// The rates of `potential` from its spectrum summary.
    fn rates(inputs: &[Input], potential: &Potential) -> Result<NearIntegrableRates, StageError> {
        use contract::spectrum::summary::{
            GAP, GAP_OVER_VARIANCE_RATE, GENERATOR, GROWING_MODES, TABLE, VARIANCE_RATE,
        };
        use contract::spectrum::{FULL, TAGGED};
        let table = TABLE.find(inputs, &instances::spectrum(potential))?;
        let (gaps, ratios) = (GAP.read(table)?, GAP_OVER_VARIANCE_RATE.read(table)?);
        let growing = GROWING_MODES.read(table)?;
        let of = |generator: &str| -> Result<GeneratorGap, StageError> {
            let row = GENERATOR.row_of(table, generator)?;
            Ok(GeneratorGap {
                gap: gaps[row],
                ratio: ratios[row],
                growing_modes: growing[row],
            })
        };
        Ok(NearIntegrableRates {
            potential: potential.id(),
            excess: potential.family().length_exponent().unwrap_or(f64::NAN) - 2.0,
            variance_rate: VARIANCE_RATE.read(table)?[GENERATOR.row_of(table, TAGGED)?],
            gas: of(FULL)?,
            particle: of(TAGGED)?,
        })
    }
}

/// The near-integrable law of `quantity` over the rates that resolve it.
fn quantity_fit(
    rates: &[NearIntegrableRates],
    (quantity, value, expected_exponent): Quantity,
) -> QuantityFit {
    let resolved: Vec<&NearIntegrableRates> = rates
        .iter()
        .filter(|r| contract::near_integrable::resolved(value(r)))
        .collect();
    let points: Vec<(f64, Estimate)> = resolved.iter().map(|r| (r.excess, value(r))).collect();
    QuantityFit {
        quantity,
        fitted: resolved.iter().map(|r| r.potential.clone()).collect(),
        law: (points.len() >= FITTED_RATES_MIN)
            .then(|| fit_near_integrable(&points))
            .flatten(),
        expected_exponent,
    }
}

/// The rates table.
fn rates_table(rates: &[NearIntegrableRates]) -> Result<Table, StageError> {
    use contract::near_integrable::rates::*;
    Ok(Rows::new(rates)
        .with(POTENTIAL, |r| r.potential.clone())
        .with(EXCESS, |r| r.excess)
        .estimate(VARIANCE_RATE, |r| r.variance_rate)
        .estimate(GAP, |r| r.gas.gap)
        .estimate(PARTICLE_GAP, |r| r.particle.gap)
        .estimate(GAP_OVER_VARIANCE_RATE, |r| r.gas.ratio)
        .estimate(PARTICLE_GAP_OVER_VARIANCE_RATE, |r| r.particle.ratio)
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
        .with(EXPECTED_EXPONENT, |f| f.expected_exponent)
        .optional(EXPONENT_Z, |f| {
            f.law
                .map(|l| (l.exponent.mean - f.expected_exponent) / l.exponent.stderr)
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
        let fits: Vec<QuantityFit> = QUANTITIES
            .iter()
            .map(|&quantity| quantity_fit(&rates, quantity))
            .collect();
        Ok(vec![rates_table(&rates)?, fits_table(&fits)?])
    }
}
