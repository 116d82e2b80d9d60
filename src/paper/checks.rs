//! Ours for each published number: a [`Check`] names what to compute from
//! which instances (the plan chooses the checks a study's instances allow),
//! and [`Check::row`] computes it from those instances' tables, with the
//! relative difference and the z-score under the paper's definition and ours
//! under our own where the two differ.
//!
//! Definitions: the paper's kernel moments count `|u - u'| <= 0.04 v_th` only
//! (its Table I; `kernel.truncations`), while our `a_n` takes the whole window
//! (`X = window / 2`), where the self variance rate has converged; `Gamma =
//! a_n rho^2 l v_th` follows whichever `a_n` is used.

use arrow_array::RecordBatch;
use serde::Serialize;

use super::published::{Column, Published, SYMMETRIC_LAUNCH};
use crate::binning::Bins;
use crate::config::{KernelParams, PAPER_TRUNCATION};
use crate::contract;
use crate::contract::instances;
use crate::contract::readers::{collision_events, self_variance_at};
use crate::kernel::equilibrium::{balance_between, self_rates};
use crate::kernel::{Target, self_bin_feeders};
use crate::physics::potential::Potential;
use crate::pipeline::{Input, InstanceId, StageError};
use crate::scaling::{MeasuredRate, fit_power_law};
use crate::stats::{ChiSquare, Estimate};

/// How ours is computed for one published number.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Check {
    /// A self variance rate at `X = 0.04` (converged: the window edge).
    Rate {
        /// The published number.
        published: Published,
        /// The `u' = 0`, dilute moments.
        moments: KernelParams,
    },
    /// A parameter of the shape fit of the `u' = 0`, dilute kernel.
    Shape {
        /// The published number.
        published: Published,
        /// The fitted kernel.
        kernel: KernelParams,
        /// `alpha`, `beta` or `sigma`.
        column: Column,
    },
    /// `|u1f,max|` of the symmetric launch (`u2 = 1`, `u3 = -1`) from the scan.
    KickMax {
        /// The published number.
        published: Published,
        /// The scanned potential.
        potential: Potential,
    },
    /// The detailed-balance ratio `G(a -> b) / G(b -> a)` from launches
    /// drawn for `u' = a` (the sweep's own row, from its launch mixture, in
    /// the note).
    Balance {
        /// The published number.
        published: Published,
        /// The sweep instance.
        sweep: String,
        /// The collisions drawn for `u' = a`.
        collisions: String,
        /// `a`, `v_th`.
        a: f64,
        /// `b - a` in bins of `bin_width`.
        steps: usize,
        /// The sweep's balance bin width, `v_th`.
        bin_width: f64,
        /// The kernel settings (`L`, kick floor).
        kernel: KernelParams,
    },
    /// `Gamma t_f = a_n rho^2 l v_th t_f` of the compared rings.
    RingTime {
        /// The published number.
        published: Published,
        /// The rings' `u' = 0`, dilute moments.
        moments: KernelParams,
    },
    /// `Gamma` of the hot ring over the cold one (same density), from the
    /// self variance rates at each ring's own `rho l` with the literal
    /// algorithm's finite-density factor, paired over the randomizations
    /// (one set of scenes gives both).
    ScalingKernel {
        /// The published number.
        published: Published,
        /// The colder ring and its moments' parameters at its `rho l`.
        cold: ScalingRing,
        /// The hotter ring.
        hot: ScalingRing,
    },
    /// The same ratio from MD: each ring's tagged window variance at `t_f`
    /// over `t_f` (independent runs).
    ScalingMd {
        /// The published number.
        published: Published,
        /// The colder ring.
        cold: ScalingRing,
        /// The hotter ring.
        hot: ScalingRing,
    },
    /// An exponent of `Gamma ~ rho^p T^q` fitted to the MD rings' thermal
    /// window variance rates (`scaling::fit_power_law`).
    ScalingExponent {
        /// The published number.
        published: Published,
        /// The density exponent (else the temperature exponent).
        density: bool,
        /// The rings: at least two densities and two temperatures.
        rings: Vec<ScalingRing>,
    },
    /// `1 / Gamma` of a gas, in seconds.
    GasTime {
        /// The published number.
        published: Published,
        /// The gas's name.
        gas: String,
        /// Its `u' = 0`, dilute moments.
        moments: KernelParams,
    },
}

/// One ring of the scaling check.
#[derive(Clone, Debug, Serialize)]
pub struct ScalingRing {
    /// The ring (`[[md.system]]` name).
    pub name: String,
    /// `t_f`, ns.
    pub final_time_ns: f64,
    /// `rho^2 l v_th` of its gas, 1/ns.
    pub rate_unit_per_ns: f64,
    /// Its gas's density `rho`, 1/um.
    pub density_per_um: f64,
    /// Its gas's `kT`, eV.
    pub kt_ev: f64,
    /// The `u' = 0` moments at its `rho l`.
    pub moments: KernelParams,
}

/// One row of the table.
pub struct PaperRow {
    /// The published number.
    pub published: Published,
    /// Ours under the paper's definition.
    pub ours: Estimate,
    /// Ours under our own.
    pub converged: Converged,
    /// How ours is computed, and what the published uncertainty means.
    pub note: String,
    /// Whether ours is a measurement of the published number (else it
    /// holds by construction, and the row has no z).
    comparable: bool,
}

impl PaperRow {
    /// A row whose inputs the study lacks, saying why in `note`.
    fn missing(published: Published, note: &str) -> PaperRow {
        PaperRow {
            published,
            ours: MISSING,
            converged: Converged::Missing,
            note: note.to_string(),
            comparable: true,
        }
    }

    /// `(ours - published) / sqrt(ours_stderr^2 + published_uncertainty^2)`,
    /// zero when both are exact and equal; NaN when ours holds by
    /// construction.
    pub fn z(&self) -> f64 {
        if !self.comparable {
            return f64::NAN;
        }
        let difference = self.ours.mean - self.published.value;
        if difference == 0.0 {
            return 0.0;
        }
        difference / libm::hypot(self.ours.stderr, self.published.uncertainty)
    }

    /// `ours / published - 1`, when finite.
    pub fn relative_difference(&self) -> Option<f64> {
        Some(self.ours.mean / self.published.value - 1.0).filter(|d| d.is_finite())
    }
}

/// Ours under our own definition.
#[derive(Clone, Copy, Debug)]
pub enum Converged {
    /// Our definition is the paper's.
    Same,
    /// Ours, where the definitions differ.
    Differs(Estimate),
    /// What it is computed from is not in the study.
    Missing,
}

impl Converged {
    /// The estimate, when there is one, else NaN.
    pub fn estimate(self) -> Estimate {
        match self {
            Converged::Differs(estimate) => estimate,
            _ => MISSING,
        }
    }

    /// The estimate transformed by `f`.
    fn map(self, f: impl Fn(Estimate) -> Estimate) -> Converged {
        match self {
            Converged::Differs(estimate) => Converged::Differs(f(estimate)),
            other => other,
        }
    }

    /// How the `paper` table states it.
    pub fn state(self) -> &'static str {
        match self {
            Converged::Same => "same",
            Converged::Differs(_) => "differs",
            Converged::Missing => "missing",
        }
    }
}

/// No estimate.
const MISSING: Estimate = Estimate {
    mean: f64::NAN,
    stderr: f64::NAN,
};

/// `a_n` at the paper's truncation; ours converged (the rate without
/// truncation: kicks reach past the window's edge, a well's free atoms' to
/// O(v_th)); and a note with the window's rate.
fn rates(
    inputs: &[Input],
    params: &KernelParams,
) -> Result<(Estimate, Converged, String), StageError> {
    let moments = contract::moments::TABLE.find(inputs, &instances::moments(params))?;
    let paper = self_variance_at(moments, PAPER_TRUNCATION)?;
    let untruncated = self_variance_at(moments, f64::INFINITY)?;
    let edge = params.edge();
    let window = self_variance_at(moments, edge)?;
    let truncated = "ours counts |u - u'| <= 0.04 like the paper";
    let converged = format!(
        "converged: the rate without truncation (X = {edge}, the window's edge, gives {:.4e} +- {:.1e})",
        window.mean, window.stderr
    );
    let note = if params.potential.family().has_well() {
        let recombination = contract::moments::RECOMBINATION_RATE.read(moments)?[0];
        format!(
            "{truncated}, from scenes whose three atoms leave free; {converged}; scenes leaving a bound pair and a free atom are no part of it (recombination rate {:.4e} +- {:.1e})",
            recombination.mean, recombination.stderr
        )
    } else {
        format!("{truncated}; {converged}, our a_n")
    };
    Ok((paper, Converged::Differs(untruncated), note))
}

/// A shape parameter under the paper's protocol with its statistical and
/// systematic errors combined; ours converged: the study's protocol; a note
/// with both fits' goodness and the errors apart.
fn shape_row(
    fit: &RecordBatch,
    column: Column,
) -> Result<(Estimate, Converged, String), StageError> {
    use contract::fit::*;
    let (pair, systematic) = match column {
        Column::Alpha => (ALPHA, ALPHA_SYSTEMATIC),
        Column::Beta => (BETA, BETA_SYSTEMATIC),
        _ => (SIGMA, SIGMA_SYSTEMATIC),
    };
    let paper = PROTOCOL.row_of(fit, PAPER_PROTOCOL)?;
    let study = PROTOCOL.row_of(fit, STUDY_PROTOCOL)?;
    let values = pair.read(fit)?;
    let systematic = systematic.read(fit)?[paper];
    let (ranges, bins, chi2) = (
        RANGE_MAX.read(fit)?,
        BINS.read(fit)?,
        CHI2_PER_DOF.read(fit)?,
    );
    // Three parameters fitted to the groups.
    let goodness = |row: usize| {
        let dof = (bins[row] as usize).saturating_sub(3);
        let test = ChiSquare {
            chi2: chi2[row] * dof as f64,
            dof,
        };
        format!(
            "chi2/dof = {:.1} with {dof} degrees of freedom, {}",
            chi2[row],
            test.p_phrase()
        )
    };
    let varied = PROTOCOL
        .read(fit)?
        .iter()
        .filter(|p| *p == VARIED_PROTOCOL)
        .count();
    let note = format!(
        "ours: g = alpha |x|^-beta exp(-x^2 / 2 sigma^2) fitted to the mean kernel over {} <= |x| <= {} with statistical weights (the paper states only its truncation 0.04, not its fit's range or weights; {}, groups treated as independent); error: statistical {:.1e} (refits of each randomization) and systematic {systematic:.1e} (half the spread over the {varied} protocols of the fit table varying range and weights) combined; converged: the study's range up to {} ({})",
        RANGE_MIN.read(fit)?[paper],
        ranges[paper],
        goodness(paper),
        values[paper].stderr,
        ranges[study],
        goodness(study),
    );
    let ours = Estimate {
        mean: values[paper].mean,
        stderr: libm::hypot(values[paper].stderr, systematic),
    };
    let study = Estimate {
        mean: values[study].mean,
        stderr: libm::hypot(values[study].stderr, systematic),
    };
    Ok((ours, Converged::Differs(study), note))
}

/// An exponent of `Gamma ~ rho^p T^q` from the rings' thermal window
/// variance rates `V(t_f) / t_f` (1/ns; independent runs per ring), with the
/// fit's chi-square in the note.
fn exponent_row(
    inputs: &[Input],
    rings: &[ScalingRing],
    density: bool,
) -> Result<(Estimate, Converged, String), StageError> {
    use contract::compare::finite_size::{RING, TABLE, THERMAL_MD_VARIANCE};
    let table = TABLE.find(inputs, &instances::compare())?;
    let variances = THERMAL_MD_VARIANCE.read(table)?;
    let rates = rings
        .iter()
        .map(|ring| {
            Ok(MeasuredRate {
                density: ring.density_per_um,
                temperature: ring.kt_ev,
                rate: variances[RING.row_of(table, &ring.name)?].scaled(1.0 / ring.final_time_ns),
            })
        })
        .collect::<Result<Vec<_>, StageError>>()?;
    let law = fit_power_law(&rates).ok_or_else(|| {
        StageError::Input("the rings' thermal variances admit no power-law fit".into())
    })?;
    let described: Vec<String> = rings
        .iter()
        .zip(&rates)
        .map(|(ring, rate)| {
            format!(
                "{} (rho = {:.4e}/um, kT = {} eV: {:.3e} +- {:.1e}/ns)",
                ring.name, ring.density_per_um, ring.kt_ev, rate.rate.mean, rate.rate.stderr
            )
        })
        .collect();
    let fit = if law.goodness.dof == 0 {
        "three rates fix the three parameters (no chi-square)".to_string()
    } else {
        let dof = law.goodness.dof;
        format!(
            "chi2 = {:.2} on {dof} degree{} of freedom, p = {} (the power law's test)",
            law.goodness.chi2,
            if dof == 1 { "" } else { "s" },
            law.goodness.p_digits()
        )
    };
    let note = format!(
        "ln Gamma = c + p ln rho + q ln T fitted to the thermal MD window variance rate V(t_f)/t_f of {} (independent runs; weights from their errors); {fit}; MD assumes no scaling",
        described.join(", ")
    );
    let exponent = if density {
        law.density_exponent
    } else {
        law.temperature_exponent
    };
    Ok((exponent, Converged::Same, note))
}

impl Check {
    /// The published number it checks.
    fn published(&self) -> &Published {
        match self {
            Check::Rate { published, .. }
            | Check::Shape { published, .. }
            | Check::KickMax { published, .. }
            | Check::Balance { published, .. }
            | Check::RingTime { published, .. }
            | Check::ScalingKernel { published, .. }
            | Check::ScalingMd { published, .. }
            | Check::ScalingExponent { published, .. }
            | Check::GasTime { published, .. } => published,
        }
    }

    /// The instances it reads.
    pub fn inputs(&self) -> Vec<InstanceId> {
        match self {
            Check::Rate { moments, .. } => vec![instances::moments(moments)],
            Check::Shape { kernel, .. } => vec![instances::fit(kernel)],
            Check::KickMax { potential, .. } => vec![instances::scan(potential)],
            Check::Balance {
                sweep, collisions, ..
            } => vec![
                InstanceId::new(contract::sweep::STAGE, sweep),
                instances::collisions(collisions),
            ],
            Check::RingTime { moments, .. } => {
                vec![instances::moments(moments), instances::compare()]
            }
            Check::ScalingKernel { cold, .. } => {
                vec![instances::collisions(&cold.moments.potential.id())]
            }
            Check::ScalingMd { .. } | Check::ScalingExponent { .. } => {
                vec![instances::compare()]
            }
            Check::GasTime { moments, .. } => vec![
                instances::moments(moments),
                InstanceId::new(contract::gases::STAGE, "study"),
            ],
        }
    }

    /// The row of this check from its `inputs`.
    pub fn row(&self, inputs: &[Input]) -> Result<PaperRow, StageError> {
        let published = self.published().clone();
        let (ours, converged, note) = match self {
            Check::Rate { moments, .. } => rates(inputs, moments)?,
            Check::Shape { kernel, column, .. } => {
                let fit = contract::fit::TABLE.find(inputs, &instances::fit(kernel))?;
                shape_row(fit, *column)?
            }
            Check::KickMax { potential, .. } => kick_max(inputs, potential)?,
            Check::Balance {
                sweep,
                collisions,
                a,
                steps,
                bin_width,
                kernel,
                ..
            } => balance(
                inputs,
                (sweep, collisions),
                (*a, *steps, *bin_width),
                kernel,
            )?,
            Check::RingTime { moments, .. } => match ring_time(inputs, moments)? {
                Some(row) => row,
                None => return Ok(PaperRow::missing(published, NO_RING)),
            },
            Check::ScalingKernel { cold, hot, .. } => {
                return scaling_kernel(inputs, cold, hot, published);
            }
            Check::ScalingMd { cold, hot, .. } => scaling_md(inputs, cold, hot)?,
            Check::ScalingExponent { density, rings, .. } => exponent_row(inputs, rings, *density)?,
            Check::GasTime { gas, moments, .. } => gas_time(inputs, gas, moments)?,
        };
        let note = with_published_note(&published, note);
        Ok(PaperRow {
            published,
            ours,
            converged,
            note,
            comparable: true,
        })
    }
}

/// The note of a row, led by what the published uncertainty means.
fn with_published_note(published: &Published, note: String) -> String {
    if published.uncertainty == 0.0 {
        format!("published: an exact prediction; {note}")
    } else if published.value == 0.0 {
        format!(
            "published: zero within the paper's integrator errors (printed as {:e}, read as 0 +- that); {note}",
            published.uncertainty
        )
    } else if published.printed_uncertainty {
        note
    } else {
        format!("published uncertainty: rounding of the printed digits; {note}")
    }
}

/// Ours, ours converged and a note: what each check computes.
type Computed = (Estimate, Converged, String);

/// `|u1f,max|` of the symmetric launch from the scan's peak table.
fn kick_max(inputs: &[Input], potential: &Potential) -> Result<Computed, StageError> {
    use contract::scan::U3;
    use contract::scan::peak::{TABLE, U1_FINAL_MAX_ABS, U2};
    let id = instances::scan(potential);
    let peaks = TABLE.find(inputs, &id)?;
    let row = U2
        .read(peaks)?
        .iter()
        .zip(U3.read(peaks)?)
        .position(|(&u2, u3)| (u2, u3) == SYMMETRIC_LAUNCH)
        .ok_or_else(|| {
            StageError::Input(format!("{id} has no symmetric launch u2 = 1, u3 = -1"))
        })?;
    let note = "ours: the largest |u1f| of the scan's offset grid, refined between grid points; its error is a bound (tolerance sensitivity plus bracket spread), not a standard error".to_string();
    Ok((U1_FINAL_MAX_ABS.read(peaks)?[row], Converged::Same, note))
}

/// The detailed-balance ratio `G(a -> a + steps bin_width) / G(back)` from
/// the collisions drawn for `u' = a`, with the sweep's own row (`names`:
/// the sweep and those collisions) in the note.
fn balance(
    inputs: &[Input],
    (sweep, collisions): (&str, &str),
    (a, steps, bin_width): (f64, usize, f64),
    kernel: &KernelParams,
) -> Result<Computed, StageError> {
    use contract::sweep::detailed_balance::{A, B, RATIO, TABLE};
    let id = InstanceId::new(contract::sweep::STAGE, sweep);
    let table = TABLE.find(inputs, &id)?;
    let b = a + steps as f64 * bin_width;
    let close = |x: f64, y: f64| (x - y).abs() < 1e-9;
    let row = A
        .read(table)?
        .iter()
        .zip(B.read(table)?)
        .position(|(x, y)| close(*x, a) && close(y, b))
        .ok_or_else(|| {
            StageError::Input(format!(
                "{id} has no pair ({a}, {b}): add b - a to sweep.balance_separations"
            ))
        })?;
    let grid = RATIO.read(table)?[row];
    let id = instances::collisions(collisions);
    let (events, draws, _) = collision_events(input(inputs, &id)?)?;
    let bins = Bins::for_window(2.0 * (b - a) + 4.0 * bin_width, bin_width);
    let target = |u_prime: f64| Target {
        u_prime,
        ..kernel.target()
    };
    let kick_floor = kernel.target().kick_floor;
    let fed = [bins.half_bins + steps, bins.half_bins - steps]
        .map(|k| self_bin_feeders(&events, &bins, k, kick_floor));
    let balance = balance_between((&fed[0], &fed[1]), &draws, &bins, (a, steps), target);
    let note = format!(
        "launches drawn for u' = {a} ({id}), bins of {bin_width}, error paired over the randomizations; the sweep's own row (its launch mixture): {:.3} +- {:.3}; f0(b)/f0(a) = {:.4} (detailed balance)",
        grid.mean, grid.stderr, balance.expected_ratio
    );
    Ok((balance.ratio, Converged::Same, note))
}

/// The input named `id`.
fn input<'a>(inputs: &'a [Input], id: &InstanceId) -> Result<&'a Input, StageError> {
    inputs
        .iter()
        .find(|input| input.id == *id)
        .ok_or_else(|| StageError::Input(format!("no input {id}")))
}

/// The note of the ring-time row when the study has no ring to compare.
const NO_RING: &str =
    "no ring: no [[md.system]] of the first ring's potential is at u' = 0, which this row compares";

/// `Gamma t_f` of the first compared ring (`None`: no compared ring).
fn ring_time(inputs: &[Input], moments: &KernelParams) -> Result<Option<Computed>, StageError> {
    use contract::compare::finite_size::{SCALED_TIME, TABLE};
    let (paper, window, truncated) = rates(inputs, moments)?;
    let times = SCALED_TIME.read(TABLE.find(inputs, &instances::compare())?)?;
    let Some(&time) = times.first() else {
        return Ok(None);
    };
    let sharing = times
        .iter()
        .filter(|t| (*t / time - 1.0).abs() <= 1e-9)
        .count();
    let note = format!(
        "rho^2 l v_th t_f = {time:.5} of the first ring ({sharing} of {} compared rings end there); {truncated}",
        times.len()
    );
    Ok(Some((
        paper.scaled(time),
        window.map(|w| w.scaled(time)),
        note,
    )))
}

/// The kernel's scaling ratio: exact by construction in the dilute limit
/// (no z), with the literal algorithm's finite-density ratio in the note.
fn scaling_kernel(
    inputs: &[Input],
    cold: &ScalingRing,
    hot: &ScalingRing,
    published: Published,
) -> Result<PaperRow, StageError> {
    let collisions = instances::collisions(&cold.moments.potential.id());
    let (events, draws, _) = collision_events(input(inputs, &collisions)?)?;
    let rate = |ring: &ScalingRing| {
        let edge = ring.moments.edge();
        self_rates(&events, &ring.moments.target(), edge, &draws).variance
    };
    let units = hot.rate_unit_per_ns / cold.rate_unit_per_ns;
    let at_density = Estimate::paired_ratio(&rate(hot), &rate(cold)).scaled(units);
    let note = format!(
        "by construction, so no z: {} over {} from the scaled kernel (the same a_6 times each gas's rho^2 l v_th) gives exactly {units:.6}; the kernels at each ring's own rho l ({:.4e} and {:.4e}) give {:.7} +- {:.1e} (paired over the randomizations), the paper's launch-rule finite-density factor exp(-r |delay|) in a box of L = {}: an artifact of that algorithm, not the gas's (the MD row measures the ratio independently)",
        hot.name,
        cold.name,
        hot.moments.density,
        cold.moments.density,
        at_density.mean,
        at_density.stderr,
        hot.moments.launch_length
    );
    Ok(PaperRow {
        published,
        ours: Estimate {
            mean: units,
            stderr: 0.0,
        },
        converged: Converged::Same,
        note: format!("published: an exact prediction; {note}"),
        comparable: false,
    })
}

/// The scaling ratio from MD: each ring's tagged window variance at `t_f`
/// over `t_f`.
fn scaling_md(
    inputs: &[Input],
    cold: &ScalingRing,
    hot: &ScalingRing,
) -> Result<Computed, StageError> {
    use contract::compare::finite_size::{MD_VARIANCE, RING, TABLE};
    let table = TABLE.find(inputs, &instances::compare())?;
    let variance = |ring: &ScalingRing| -> Result<Estimate, StageError> {
        Ok(MD_VARIANCE.read(table)?[RING.row_of(table, &ring.name)?])
    };
    let ratio = variance(hot)?
        .ratio(variance(cold)?)
        .scaled(cold.final_time_ns / hot.final_time_ns);
    let note = format!(
        "tagged MD window variance at t_f over t_f: {} ({} ns) over {} ({} ns), independent runs; MD does not assume the scaling, and includes whatever its rings' own rho l does",
        hot.name, hot.final_time_ns, cold.name, cold.final_time_ns
    );
    Ok((ratio, Converged::Same, note))
}

/// `1 / Gamma` of the gas named `gas`, in seconds.
fn gas_time(inputs: &[Input], gas: &str, moments: &KernelParams) -> Result<Computed, StageError> {
    use contract::gases::{A_N, GAMMA, GAS, TABLE};
    let table = TABLE.find(inputs, &InstanceId::new(contract::gases::STAGE, "study"))?;
    let row = GAS
        .read(table)?
        .iter()
        .position(|name| name == gas)
        .ok_or_else(|| StageError::Input(format!("no gas `{gas}` in the gases table")))?;
    // Gamma / a_n = rho^2 l v_th (1/ns), exact.
    let rate_unit = GAMMA.value.read(table)?[row] / A_N.value.read(table)?[row];
    let (paper, window, truncated) = rates(inputs, moments)?;
    let seconds = |a: Estimate| {
        let time = 1e-9 / (a.mean * rate_unit);
        Estimate {
            mean: time,
            stderr: time * a.stderr / a.mean,
        }
    };
    let note = format!(
        "gas `{gas}` of the study (its comment cites the Lennard-Jones table); the paper says 'about', read as one significant digit; {truncated}"
    );
    Ok((seconds(paper), window.map(seconds), note))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::published::{A_LJ, SCALING_KERNEL, TABLE_I};

    fn row(ours: Estimate, published: Published, comparable: bool) -> PaperRow {
        PaperRow {
            published,
            ours,
            converged: Converged::Same,
            note: String::new(),
            comparable,
        }
    }

    #[test]
    fn z_divides_the_difference_by_both_errors_in_quadrature() {
        // A_LJ: 3.00e-4 +- 0.005e-4. Ours 3.04e-4 +- 0.012e-4: the
        // difference 4e-6 over hypot(1.2e-6, 0.5e-6) = 1.3e-6.
        let ours = Estimate {
            mean: 3.04e-4,
            stderr: 1.2e-6,
        };
        let z = row(ours, A_LJ, true).z();
        assert!((z - 4e-6 / 1.3e-6).abs() < 1e-9, "z = {z}");
        let below = Estimate {
            mean: 2.96e-4,
            ..ours
        };
        assert!((row(below, A_LJ, true).z() + z).abs() < 1e-9, "mirror");
    }

    #[test]
    fn an_exact_match_has_z_zero_and_a_construction_has_none() {
        let exact = Estimate {
            mean: 2.0,
            stderr: 0.0,
        };
        assert_eq!(row(exact, SCALING_KERNEL, true).z(), 0.0);
        assert!(row(exact, SCALING_KERNEL, false).z().is_nan());
        assert_eq!(
            row(exact, SCALING_KERNEL, true).relative_difference(),
            Some(0.0)
        );
    }

    #[test]
    fn a_published_zero_has_no_relative_difference() {
        let n2 = TABLE_I[0].published(Column::RateConstant).expect("a_2");
        let ours = Estimate {
            mean: 1e-12,
            stderr: 1e-12,
        };
        assert_eq!(n2.value, 0.0);
        assert_eq!(row(ours, n2, true).relative_difference(), None);
    }

    #[test]
    fn the_note_says_what_the_published_uncertainty_is() {
        let note = |p: &Published| with_published_note(p, "ours".into());
        assert!(note(&SCALING_KERNEL).starts_with("published: an exact prediction"));
        let n2 = TABLE_I[0].published(Column::KickMax).expect("|u1f,max|");
        assert!(note(&n2).starts_with("published: zero within"));
        assert!(note(&A_LJ).starts_with("published uncertainty: rounding"));
        let alpha = TABLE_I[2].published(Column::Alpha).expect("alpha");
        assert_eq!(note(&alpha), "ours");
    }

    #[test]
    fn scaling_an_estimate_scales_its_error_by_the_magnitude() {
        let estimate = Estimate {
            mean: 2.0,
            stderr: 0.5,
        };
        let scaled = estimate.scaled(-3.0);
        assert_eq!((scaled.mean, scaled.stderr), (-6.0, 1.5));
        let converged = Converged::Differs(estimate).map(|e| e.scaled(2.0));
        assert_eq!(converged.estimate().mean, 4.0);
        assert!(Converged::Same.map(|e| e).estimate().mean.is_nan());
    }
}
