//! `pulls`: every cross-check of the study as a pull `(a - b) / combined
//! error`, and whether the pulls spread as N(0, 1) (`calibration`). The
//! checks: for a potential with a well, the recombination rate of the atom
//! at rest from the kernel's scenes and from the sweep's against the one
//! detailed balance gives from the dissociating scenes, and the sweep's
//! thermal rate against `3 K_b k_d` (independent scene sets); for every
//! sweep, the joint detailed-balance test of each separation against 0
//! (exact), where no single randomization carries its spread; where the
//! study runs `near_integrable`, every fitted exponent against perturbation
//! theory's (exact; the error the statistical one and the law's
//! truncation's). Left out: the stationarity residual (a jump process
//! differs from a Fokker-Planck one by a few percent, so 0 is not exact).

use serde_json::Value;

use crate::calibration::{Pull, calibration};
use crate::config::KernelParams;
use crate::contract::instances;
use crate::contract::{self, Rows};
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::stats::Estimate;
use crate::thresholds::DOMINATED_SHARE;

/// The `pulls` stage.
pub struct PullsStage {
    /// The `sweep` instances the study runs.
    sweeps: Vec<InstanceId>,
    /// The dilute `u' = 0` moments of every potential whose sweep and
    /// dissociation the study runs (a potential with a well).
    recombinations: Vec<KernelParams>,
    /// Whether the study runs `near_integrable`.
    near_integrable: bool,
}

/// Unit of a rate's pulls.
const RATE_UNIT: &str = "rho^2 l v_th";

/// The checks of the recombination rate.
const KERNEL_AT_REST: &str = "recombination at u' = 0: kernel's scenes against detailed balance";
const SWEEP_AT_REST: &str = "recombination at u' = 0: sweep's scenes against detailed balance";
const THERMAL: &str = "thermal recombination: sweep's scenes against 3 K_b k_d";
/// The check of detailed balance.
const BALANCE: &str = "detailed balance of the self kernel: joint imbalance against 0";
/// The check of the near-integrable law.
const NEAR_INTEGRABLE: &str =
    "near-integrable exponent p of rate ~ (n - 2)^p against perturbation theory";

impl PullsStage {
    /// The pulls of these sweeps, of the recombination rates of these
    /// potentials (their moments; each with a planned sweep and
    /// dissociation) and, if `near_integrable`, of its fits.
    pub fn new(
        sweeps: Vec<InstanceId>,
        recombinations: Vec<KernelParams>,
        near_integrable: bool,
    ) -> PullsStage {
        PullsStage {
            sweeps,
            recombinations,
            near_integrable,
        }
    }

    /// The three recombination pulls of the potential of `moments`.
    fn recombination(inputs: &[Input], moments: &KernelParams) -> Result<[Pull; 3], StageError> {
        use contract::sweep::recombination as sweep;
        let potential = &moments.potential;
        let table = contract::moments::TABLE.find(inputs, &instances::moments(moments))?;
        let kernel = contract::moments::RECOMBINATION_RATE.read(table)?[0];
        let swept = sweep::TABLE.find(inputs, &instances::sweep(potential))?;
        let swept = at_rest_and_thermal(
            sweep::U_PRIME.optional(swept)?,
            sweep::RATE_COLUMN.read(swept)?,
        )?;
        let balanced = {
            use contract::dissociation::recombination::*;
            let table = TABLE.find(inputs, &instances::dissociation(potential))?;
            at_rest_and_thermal(U_PRIME.optional(table)?, RATE_COLUMN.read(table)?)?
        };
        let pull = |check, first, second| Pull {
            check,
            subject: potential.id(),
            unit: RATE_UNIT,
            first,
            second,
        };
        Ok([
            pull(KERNEL_AT_REST, kernel, balanced[0]),
            pull(SWEEP_AT_REST, swept[0], balanced[0]),
            pull(THERMAL, swept[1], balanced[1]),
        ])
    }

    /// The joint detailed-balance pulls of `sweep` that are evidence.
    fn balance(inputs: &[Input], sweep: &InstanceId) -> Result<Vec<Pull>, StageError> {
        use contract::sweep::balance_tests::*;
        let table = TABLE.find(inputs, sweep)?;
        let separations = SEPARATION.read(table)?;
        let imbalances = JOINT_IMBALANCE.read(table)?;
        let shares = JOINT_LARGEST_SHARE.read(table)?;
        Ok(separations
            .iter()
            .zip(imbalances)
            .zip(shares)
            .filter(|(_, share)| *share <= DOMINATED_SHARE)
            .map(|((separation, imbalance), _)| Pull {
                check: BALANCE,
                subject: format!("{}, separation {separation}", sweep.instance),
                unit: "1",
                first: imbalance,
                second: EXACT_ZERO,
            })
            .collect())
    }

    /// The fitted exponents of `near_integrable` against their prediction.
    fn near_integrable(inputs: &[Input]) -> Result<Vec<Pull>, StageError> {
        use contract::near_integrable::fits::*;
        let table = TABLE.find(inputs, &instances::near_integrable())?;
        let (quantities, exponents) = (QUANTITY.read(table)?, EXPONENT.read(table)?);
        let (errors, expected) = (
            EXPONENT_ERROR.optional(table)?,
            EXPECTED_EXPONENT.read(table)?,
        );
        let rows = quantities
            .into_iter()
            .zip(exponents)
            .zip(errors)
            .zip(expected);
        Ok(rows
            .filter_map(|(((quantity, exponent), error), expected)| {
                Some(Pull {
                    check: NEAR_INTEGRABLE,
                    subject: quantity,
                    unit: "1",
                    first: Estimate {
                        mean: exponent.mean,
                        stderr: error?,
                    },
                    second: Estimate {
                        mean: expected,
                        stderr: 0.0,
                    },
                })
            })
            .collect())
    }

    /// Every pull, in the order of the study's potentials.
    fn pulls(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Pull>, StageError> {
        let mut pulls = Vec::new();
        for moments in &self.recombinations {
            pulls.extend(Self::recombination(inputs, moments)?);
            progress.advance(1);
        }
        for sweep in &self.sweeps {
            pulls.extend(Self::balance(inputs, sweep)?);
            progress.advance(1);
        }
        if self.near_integrable {
            pulls.extend(Self::near_integrable(inputs)?);
        }
        Ok(pulls)
    }
}

/// The value 0, exactly.
const EXACT_ZERO: Estimate = Estimate {
    mean: 0.0,
    stderr: 0.0,
};

/// The rows at `u' = 0` and the thermal average (null `u'`) of a
/// recombination table.
fn at_rest_and_thermal(
    u_prime: Vec<Option<f64>>,
    rates: Vec<Estimate>,
) -> Result<[Estimate; 2], StageError> {
    let row = |wanted: Option<f64>| {
        u_prime
            .iter()
            .position(|&u| u == wanted)
            .map(|k| rates[k])
            .ok_or_else(|| {
                StageError::Input(format!(
                    "a recombination table without the row u' = {wanted:?}"
                ))
            })
    };
    Ok([row(Some(0.0))?, row(None)?])
}

/// The pulls, one row each.
fn pulls_table(pulls: &[Pull]) -> Result<Table, StageError> {
    use contract::pulls::checks::*;
    Ok(Rows::new(pulls)
        .with(CHECK, |p| p.check.to_string())
        .with(SUBJECT, |p| p.subject.clone())
        .with(UNIT, |p| p.unit.to_string())
        .estimate(FIRST, |p| p.first)
        .estimate(SECOND, |p| p.second)
        .with(PULL, Pull::value)
        .table(&TABLE)?)
}

/// Their distribution against N(0, 1).
fn summary_table(pulls: &[Pull]) -> Result<Table, StageError> {
    use contract::pulls::summary::*;
    let calibration = [calibration(pulls)];
    let worst = |c: &crate::calibration::Calibration| c.worst.map(|k| &pulls[k]);
    Ok(Rows::new(&calibration)
        .with(PULLS, |c| c.count as u32)
        .estimate(MEAN, |c| c.mean)
        .with(SPREAD, |c| c.spread)
        .with(WORST_CHECK, |c| {
            worst(c).map_or(String::new(), |p| p.check.to_string())
        })
        .with(WORST_SUBJECT, |c| {
            worst(c).map_or(String::new(), |p| p.subject.clone())
        })
        .with(WORST_PULL, |c| worst(c).map_or(f64::NAN, Pull::value))
        .with(VERDICT, crate::calibration::Calibration::verdict)
        .table(&TABLE)?)
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for PullsStage {
    fn id(&self) -> InstanceId {
        instances::pulls()
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::json!({
            "sweeps": self.sweeps.iter().map(ToString::to_string).collect::<Vec<_>>(),
            "recombinations": self.recombinations,
            "near_integrable": self.near_integrable,
        })
    }

    fn tables(&self) -> &'static [&'static str] {
        use contract::pulls::{checks, summary};
        &[checks::TABLE.name, summary::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        self.recombinations
            .iter()
            .flat_map(|moments| {
                [
                    instances::moments(moments),
                    instances::sweep(&moments.potential),
                    instances::dissociation(&moments.potential),
                ]
            })
            .chain(self.sweeps.iter().cloned())
            .chain(self.near_integrable.then(instances::near_integrable))
            .fold(Vec::new(), |mut unique, id| {
                if !unique.contains(&id) {
                    unique.push(id);
                }
                unique
            })
    }

    fn work_units(&self) -> u64 {
        (self.recombinations.len() + self.sweeps.len()) as u64
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        let pulls = self.pulls(inputs, progress)?;
        Ok(vec![pulls_table(&pulls)?, summary_table(&pulls)?])
    }
}
