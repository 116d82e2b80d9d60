//! `paper`: the published numbers of Phys. Rev. E 110, 014114 (2024) next to
//! ours under the paper's definition, with the relative difference and the
//! z-score, and ours under our own definition where the two differ. One row per
//! published number whose inputs the study computes.
//!
//! Definitions: the paper's kernel moments count `|u - u'| <= 0.04 v_th` only
//! (its Table I; `kernel.truncations`), while our `a_n` takes the whole window
//! (`X = window / 2`), where the self variance rate has converged; `Gamma =
//! a_n rho^2 l v_th` follows whichever `a_n` is used.

use std::borrow::Cow;
use std::collections::HashSet;

use arrow::array::RecordBatch;
use serde::Serialize;
use serde_json::Value;

use crate::binning::Bins;
use crate::config::{CollisionsParams, KernelParams, MdParams, PAPER_TRUNCATION, Study};
use crate::contract::instances;
use crate::contract::readers::{collision_events, self_variance_at};
use crate::contract::{self, Rows};
use crate::kernel::equilibrium::{balance_between, self_rates};
use crate::kernel::{Target, self_bin_feeders};
use crate::physics::potential::Potential;
use crate::physics::units::PhysicalGas;
use crate::pipeline::code::{self, Code};
use crate::pipeline::{Input, InstanceId, Progress, Stage, StageError, Table};
use crate::scaling::{MeasuredRate, fit_power_law};
use crate::stats::{ChiSquare, Estimate};

/// A number as the paper prints it.
#[derive(Clone, Debug, Serialize)]
pub struct Published {
    /// What it is.
    pub quantity: Cow<'static, str>,
    /// Where the paper gives it.
    pub source: Cow<'static, str>,
    /// Unit.
    pub unit: &'static str,
    /// Value.
    pub value: f64,
    /// Uncertainty: as printed, else half a unit of the last printed digit.
    pub uncertainty: f64,
    /// Whether the paper prints the uncertainty.
    pub printed_uncertainty: bool,
    /// Its cell of Table I, if it is one.
    pub table_i: Option<Cell>,
}

/// A cell of Table I: the exponent `n` and the column.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// The exponent of the inverse power law.
    pub n: u32,
    /// The column.
    pub column: Column,
}

/// The columns of Table I.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Column {
    /// `a_n`, the self variance rate at `X = 0.04`.
    RateConstant,
    /// The shape fit's amplitude `alpha`.
    Alpha,
    /// The shape fit's exponent `beta`.
    Beta,
    /// The shape fit's cut-off `sigma`.
    Sigma,
    /// `|u1f,max|` of the symmetric launch.
    KickMax,
}

impl Column {
    /// The column's name in the `paper` table and the summary.
    pub fn name(self) -> &'static str {
        match self {
            Column::RateConstant => "a_n",
            Column::Alpha => "alpha",
            Column::Beta => "beta",
            Column::Sigma => "sigma",
            Column::KickMax => "|u1f,max|",
        }
    }
}

/// One row of Table I as printed: `(value, uncertainty)` per column, `None`
/// where the cell is blank. Uncertainties: the caption's +-0.001 for the
/// shape, else half a unit of the last printed digit.
struct TableIRow {
    n: u32,
    rate_constant: (f64, f64),
    shape: Option<[f64; 3]>,
    kick_max: (f64, f64),
}

/// The caption's uncertainty of `alpha`, `beta` and `sigma`.
const SHAPE_UNCERTAINTY: f64 = 0.001;

/// Table I of the paper ("Rate constants a_n and fitting parameters for
/// different potential powers n"), transcribed from the paper's text. `n = 2`
/// prints `a_2 = 0`, `alpha = 0.000`, blank `beta` and `sigma`, and
/// `|u1f,max| = 1e-7`, which the paper says is zero within its integrator's
/// errors (the `n = 2` problem is integrable), so that cell is read as an
/// upper bound: `0 +- 1e-7`.
const TABLE_I: [TableIRow; 6] = [
    TableIRow {
        n: 2,
        rate_constant: (0.0, 0.0),
        shape: None,
        kick_max: (0.0, 1e-7),
    },
    TableIRow {
        n: 4,
        rate_constant: (3.49e-4, 0.005e-4),
        shape: Some([0.237, 1.182, 0.022]),
        kick_max: (2.69e-2, 0.005e-2),
    },
    TableIRow {
        n: 6,
        rate_constant: (2.58e-4, 0.005e-4),
        shape: Some([0.182, 1.117, 0.027]),
        kick_max: (3.06e-2, 0.005e-2),
    },
    TableIRow {
        n: 8,
        rate_constant: (1.62e-4, 0.005e-4),
        shape: Some([0.148, 1.076, 0.025]),
        kick_max: (2.76e-2, 0.005e-2),
    },
    TableIRow {
        n: 10,
        rate_constant: (1.02e-4, 0.005e-4),
        shape: Some([0.129, 1.046, 0.021]),
        kick_max: (2.37e-2, 0.005e-2),
    },
    TableIRow {
        n: 12,
        rate_constant: (6.55e-5, 0.005e-5),
        shape: Some([0.115, 1.023, 0.018]),
        kick_max: (2.04e-2, 0.005e-2),
    },
];

impl TableIRow {
    /// The cell of `column`, as a published number (`None`: blank).
    fn published(&self, column: Column) -> Option<Published> {
        let n = self.n;
        let (quantity, unit, (value, uncertainty), printed) = match column {
            Column::RateConstant => (
                format!("a_{n}: self variance rate, n = {n}, u' = 0, dilute, |u - u'| <= 0.04"),
                "rho^2 l v_th",
                self.rate_constant,
                false,
            ),
            Column::Alpha | Column::Beta | Column::Sigma => {
                let k = [Column::Alpha, Column::Beta, Column::Sigma]
                    .iter()
                    .position(|c| *c == column)?;
                let unit = [contract::ALPHA_UNIT, "1", "v_th"][k];
                (
                    format!("{}: shape fit, n = {n}", column.name()),
                    unit,
                    (self.shape?[k], SHAPE_UNCERTAINTY),
                    true,
                )
            }
            Column::KickMax => (
                format!("|u1f,max|, n = {n}: largest kick, symmetric launch u2 = 1, u3 = -1"),
                "v_th",
                self.kick_max,
                n == 2,
            ),
        };
        Some(Published {
            quantity: Cow::Owned(quantity),
            source: Cow::Borrowed("Table I"),
            unit,
            value,
            uncertainty,
            printed_uncertainty: printed,
            table_i: Some(Cell { n, column }),
        })
    }
}

/// The Lennard-Jones rate at `kT = 0.1 eps`.
pub const A_LJ: Published = Published {
    quantity: Cow::Borrowed(
        "a: self variance rate, Lennard-Jones theta = kT/eps = 0.1, u' = 0, dilute",
    ),
    source: Cow::Borrowed("Lennard-Jones section (16% above n = 6)"),
    unit: "rho^2 l v_th",
    value: 3.00e-4,
    uncertainty: 0.005e-4,
    printed_uncertainty: false,
    table_i: None,
};

/// The detailed-balance ratio at `u' = -3`.
pub const BALANCE: Published = Published {
    quantity: Cow::Borrowed("G(-3.00 -> -2.96) / G(-2.96 -> -3.00), n = 6"),
    source: Cow::Borrowed("detailed-balance check"),
    unit: "1",
    value: 1.12,
    uncertainty: 0.04,
    printed_uncertainty: true,
    table_i: None,
};

/// The MD rings' final time in units of `1 / Gamma`.
pub const RING_TIME: Published = Published {
    quantity: Cow::Borrowed("Gamma t_f of the MD rings, n = 6"),
    source: Cow::Borrowed("MD section: t_f = 1.6e-4 / Gamma"),
    unit: "1",
    value: 1.6e-4,
    uncertainty: 0.05e-4,
    printed_uncertainty: false,
    table_i: None,
};

/// The nitrogen example's thermalization time.
pub const NITROGEN: Published = Published {
    quantity: Cow::Borrowed("1/Gamma of 1D N2, one molecule per 10 um at 10 K"),
    source: Cow::Borrowed("N2 example: about 10 s to thermalize"),
    unit: "s",
    value: 10.0,
    uncertainty: 5.0,
    printed_uncertainty: false,
    table_i: None,
};

/// `Gamma ~ rho^2 T^(1/2 - 1/n)` checked from the kernels: the ring at
/// `(2 rho, 800 meV)` against the one at `(2 rho, 100 meV)`, `n = 6`.
pub const SCALING_KERNEL: Published = Published {
    quantity: Cow::Borrowed(
        "Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, scaled kernel (dilute)",
    ),
    source: Cow::Borrowed(
        "rho^2 T^(1/2 - 1/n) scaling checked from kernels at two temperatures: 8^(1/2 - 1/6) = 2",
    ),
    unit: "1",
    value: 2.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The same ratio measured by MD, which does not assume the scaling.
pub const SCALING_MD: Published = Published {
    quantity: Cow::Borrowed("Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, MD"),
    source: Cow::Borrowed("rho^2 T^(1/2 - 1/n) scaling (MD collapse): 8^(1/2 - 1/6) = 2"),
    unit: "1",
    value: 2.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The density exponent of `Gamma ~ rho^2 T^(1/2 - 1/n)` measured by MD.
pub const DENSITY_EXPONENT: Published = Published {
    quantity: Cow::Borrowed(
        "p in Gamma ~ rho^p T^q, n = 6, MD (thermal estimator): density exponent",
    ),
    source: Cow::Borrowed("rho^2 T^(1/2 - 1/n) scaling: three-body collisions, p = 2"),
    unit: "1",
    value: 2.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The temperature exponent, `1/2 - 1/6` for `n = 6`.
pub const TEMPERATURE_EXPONENT: Published = Published {
    quantity: Cow::Borrowed(
        "q in Gamma ~ rho^p T^q, n = 6, MD (thermal estimator): temperature exponent",
    ),
    source: Cow::Borrowed("rho^2 T^(1/2 - 1/n) scaling: q = 1/2 - 1/6 = 1/3"),
    unit: "1",
    value: 1.0 / 3.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The temperature ratio of the paper's two rings at `2 rho` (800 / 100 meV).
const SCALING_TEMPERATURES: f64 = 8.0;

/// The gas of the nitrogen example in a study (`[[gas]]` name).
pub const NITROGEN_GAS: &str = "N2_10K";

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
    name: String,
    /// `t_f`, ns.
    final_time_ns: f64,
    /// `rho^2 l v_th` of its gas, 1/ns.
    rate_unit_per_ns: f64,
    /// Its gas's density `rho`, 1/um.
    density_per_um: f64,
    /// Its gas's `kT`, eV.
    kt_ev: f64,
    /// The `u' = 0` moments at its `rho l`.
    moments: KernelParams,
}

/// One row of the table.
struct PaperRow {
    published: Published,
    ours: Estimate,
    converged: Converged,
    note: String,
    /// Whether ours is a measurement of the published number (else it
    /// holds by construction, and the row has no z).
    comparable: bool,
}

/// Ours under our own definition.
#[derive(Clone, Copy, Debug)]
enum Converged {
    /// Our definition is the paper's.
    Same,
    /// Ours, where the definitions differ.
    Differs(Estimate),
    /// Our definition has no converged value yet (Lennard-Jones).
    NotYet,
    /// What it is computed from is not in the study.
    Missing,
}

impl Converged {
    /// The estimate, when there is one, else NaN.
    fn estimate(self) -> Estimate {
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
    fn state(self) -> &'static str {
        match self {
            Converged::Same => "same",
            Converged::Differs(_) => "differs",
            Converged::NotYet => "not converged",
            Converged::Missing => "missing",
        }
    }
}

/// No estimate.
const MISSING: Estimate = Estimate {
    mean: f64::NAN,
    stderr: f64::NAN,
};

/// The `paper` stage.
pub struct PaperStage {
    checks: Vec<Check>,
}

/// The paper's `n = 6` and Lennard-Jones `theta = 0.1` potentials.
const IPP_6: Potential = Potential::inverse_power(6.0);
const LJ_0_1: Potential = Potential::lennard_jones(0.1);

/// The paper's detailed-balance pair `(a, b)`.
const BALANCE_PAIR: (f64, f64) = (-3.0, -2.96);

/// The `paper` stage of a study: every published number whose inputs `plan`
/// computes (none: no stage).
pub fn paper_stage(study: &Study, plan: &[Box<dyn Stage>]) -> Option<PaperStage> {
    let planned: HashSet<InstanceId> = plan.iter().map(|stage| stage.id()).collect();
    let present = |id: &InstanceId| planned.contains(id);
    let dilute = |p: Potential| study.kernel_params(p, 0.0, 0.0);
    let has = |p: Potential| present(&instances::moments(&dilute(p)));
    let mut checks = table_i_checks(study, &planned);
    if has(LJ_0_1) {
        checks.push(Check::Rate {
            published: A_LJ,
            moments: dilute(LJ_0_1),
        });
    }
    if let Some((collisions, _)) = balance_collisions(study) {
        let (a, b) = BALANCE_PAIR;
        let bin_width = study.config.sweep.balance_bin_width;
        checks.push(Check::Balance {
            published: BALANCE,
            sweep: IPP_6.id(),
            collisions,
            a,
            steps: ((b - a) / bin_width).round() as usize,
            bin_width,
            kernel: dilute(IPP_6),
        });
    }
    let compared = study.md_params().first().map(|ring| ring.potential);
    if present(&instances::compare()) && compared == Some(IPP_6) {
        checks.push(Check::RingTime {
            published: RING_TIME,
            moments: dilute(IPP_6),
        });
    }
    if let Some((cold, hot)) = scaling_rings(study) {
        checks.push(Check::ScalingKernel {
            published: SCALING_KERNEL,
            cold: cold.clone(),
            hot: hot.clone(),
        });
        if present(&instances::compare()) {
            checks.push(Check::ScalingMd {
                published: SCALING_MD,
                cold,
                hot,
            });
        }
    }
    if let Some(rings) = exponent_rings(study).filter(|_| present(&instances::compare())) {
        for (published, density) in [(DENSITY_EXPONENT, true), (TEMPERATURE_EXPONENT, false)] {
            checks.push(Check::ScalingExponent {
                published,
                density,
                rings: rings.clone(),
            });
        }
    }
    if let Some(gas) = study.gases().into_iter().find(|g| g.name == NITROGEN_GAS) {
        checks.push(Check::GasTime {
            published: NITROGEN,
            gas: gas.name,
            moments: dilute(gas.potential),
        });
    }
    (!checks.is_empty()).then_some(PaperStage { checks })
}

/// The symmetric launch of Table I's `|u1f,max|`.
const SYMMETRIC_LAUNCH: (f64, f64) = (1.0, -1.0);

/// Every Table I cell whose inputs are `planned`, column by column.
fn table_i_checks(study: &Study, planned: &HashSet<InstanceId>) -> Vec<Check> {
    let present = |id: &InstanceId| planned.contains(id);
    let scans_symmetric = study
        .config
        .scan
        .launch
        .iter()
        .any(|launch| (launch.u2, launch.u3) == SYMMETRIC_LAUNCH);
    let mut checks = Vec::new();
    for column in [
        Column::RateConstant,
        Column::Alpha,
        Column::Beta,
        Column::Sigma,
        Column::KickMax,
    ] {
        for row in &TABLE_I {
            let potential = Potential::inverse_power(f64::from(row.n));
            let kernel = study.kernel_params(potential, 0.0, 0.0);
            let Some(published) = row.published(column) else {
                continue;
            };
            let check = match column {
                Column::RateConstant => {
                    present(&instances::moments(&kernel)).then_some(Check::Rate {
                        published,
                        moments: kernel,
                    })
                }
                Column::Alpha | Column::Beta | Column::Sigma => present(&instances::fit(&kernel))
                    .then_some(Check::Shape {
                        published,
                        kernel,
                        column,
                    }),
                Column::KickMax => (scans_symmetric && present(&instances::scan(&potential)))
                    .then_some(Check::KickMax {
                        published,
                        potential,
                    }),
            };
            checks.extend(check);
        }
    }
    checks
}

/// The collisions the paper's detailed-balance pair is computed from, when
/// the study offers the pair (`n = 6`, a sweep from `u' = -3` with the
/// separation 0.04): launches drawn for `u' = -3` itself. The sweep's own
/// scenes, a launch mixture for its whole grid, leave the ratio at +-0.044 with
/// the default study's 2560 pairs; drawn for `-3`, 4096 pairs reach +-0.015
/// (docs/benchmarks.md, `bench balance`).
pub fn balance_collisions(study: &Study) -> Option<(String, CollisionsParams)> {
    let sweep = study.sweep_params(IPP_6)?;
    let (a, b) = BALANCE_PAIR;
    let width = sweep.balance_bin_width;
    let offers = sweep.u_prime_min == a
        && sweep
            .balance_separations
            .iter()
            .any(|s| ((s / width).round() * width - (b - a)).abs() < 1e-9);
    offers.then(|| study.tuned_collisions(IPP_6, a))
}

/// The first two collapse rings of `n = 6` at one density whose
/// temperatures differ by the paper's factor 8 (the rest of the gas equal),
/// colder first.
fn scaling_ring(study: &Study, r: &MdParams) -> ScalingRing {
    ScalingRing {
        name: r.name.clone(),
        final_time_ns: r.final_time_ns,
        rate_unit_per_ns: r
            .gas
            .rate_per_ns(1.0, r.potential.family().length_exponent()),
        density_per_um: r.gas.density_per_um,
        kt_ev: r.gas.kt_ev,
        moments: study.kernel_params(r.potential, 0.0, r.scaled_density()),
    }
}

/// The `n = 6` rings of the scaling collapse (the same `N` and
/// `rho^2 l v_th t_f`) when they span two densities and two temperatures.
fn exponent_rings(study: &Study) -> Option<Vec<ScalingRing>> {
    let rings: Vec<MdParams> = study
        .collapse_rings()
        .into_iter()
        .filter(|r| r.potential == IPP_6)
        .collect();
    let distinct = |value: fn(&MdParams) -> f64| {
        rings
            .iter()
            .any(|r| (value(r) / value(&rings[0]) - 1.0).abs() > 1e-9)
    };
    (rings.len() >= 3 && distinct(|r| r.gas.density_per_um) && distinct(|r| r.gas.kt_ev))
        .then(|| rings.iter().map(|r| scaling_ring(study, r)).collect())
}

fn scaling_rings(study: &Study) -> Option<(ScalingRing, ScalingRing)> {
    let rings = study.collapse_rings();
    let ring = |r: &MdParams| scaling_ring(study, r);
    let pair = |cold: &MdParams, hot: &MdParams| {
        let apart_from_temperature = PhysicalGas {
            kt_ev: hot.gas.kt_ev,
            ..cold.gas
        } == hot.gas;
        cold.potential == IPP_6
            && hot.potential == IPP_6
            && apart_from_temperature
            && (hot.gas.kt_ev / cold.gas.kt_ev / SCALING_TEMPERATURES - 1.0).abs() < 1e-9
    };
    rings.iter().find_map(|cold| {
        rings
            .iter()
            .find(|hot| pair(cold, hot))
            .map(|hot| (ring(cold), ring(hot)))
    })
}

/// `a_n` at the paper's truncation; ours converged (the window edge; for
/// Lennard-Jones, whose rate has not converged there, none); and a note
/// saying which.
fn rates(
    inputs: &[Input],
    params: &KernelParams,
) -> Result<(Estimate, Converged, String), StageError> {
    let moments = contract::moments::TABLE.find(inputs, &instances::moments(params))?;
    let paper = self_variance_at(moments, PAPER_TRUNCATION)?;
    let window = self_variance_at(moments, 0.5 * params.window)?;
    let truncated = "ours counts |u - u'| <= 0.04 like the paper";
    if params.potential.family().has_well() {
        let untruncated = self_variance_at(moments, f64::INFINITY)?;
        let note = format!(
            "{truncated}; converged: none yet, since for Lennard-Jones the rate has not converged at the window edge (X = {}: {:.4e} +- {:.1e}; without truncation {:.4e} +- {:.1e}): bound-pair events (recombination, break-up) kick beyond any window",
            0.5 * params.window,
            window.mean,
            window.stderr,
            untruncated.mean,
            untruncated.stderr
        );
        return Ok((paper, Converged::NotYet, note));
    }
    let note = format!(
        "{truncated}; converged: the whole window (X = {}), our a_n",
        0.5 * params.window
    );
    Ok((paper, Converged::Differs(window), note))
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
            "chi2/dof = {:.1} with {dof} degrees of freedom, p = {:.1e}",
            chi2[row],
            test.p_value()
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
                rate: scaled(
                    variances[RING.row_of(table, &ring.name)?],
                    1.0 / ring.final_time_ns,
                ),
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
        format!(
            "chi2/dof = {:.2} with {} degrees of freedom, p = {:.2}",
            law.goodness.per_dof(),
            law.goodness.dof,
            law.goodness.p_value()
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

fn scaled(estimate: Estimate, factor: f64) -> Estimate {
    Estimate {
        mean: estimate.mean * factor,
        stderr: estimate.stderr * factor.abs(),
    }
}

impl Check {
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
    fn inputs(&self) -> Vec<InstanceId> {
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

    fn row(&self, inputs: &[Input]) -> Result<PaperRow, StageError> {
        let published = self.published().clone();
        let (ours, converged, note) = match self {
            Check::Rate { moments, .. } => rates(inputs, moments)?,
            Check::Shape { kernel, column, .. } => {
                let fit = contract::fit::TABLE.find(inputs, &instances::fit(kernel))?;
                shape_row(fit, *column)?
            }
            Check::KickMax { potential, .. } => {
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
                (U1_FINAL_MAX_ABS.read(peaks)?[row], Converged::Same, note)
            }
            Check::Balance {
                sweep,
                collisions,
                a,
                steps,
                bin_width,
                kernel,
                ..
            } => {
                use contract::sweep::detailed_balance::{A, B, RATIO, TABLE};
                let id = InstanceId::new(contract::sweep::STAGE, sweep);
                let table = TABLE.find(inputs, &id)?;
                let b = a + *steps as f64 * bin_width;
                let close = |x: f64, y: f64| (x - y).abs() < 1e-9;
                let row = A
                    .read(table)?
                    .iter()
                    .zip(B.read(table)?)
                    .position(|(x, y)| close(*x, *a) && close(y, b))
                    .ok_or_else(|| {
                        StageError::Input(format!(
                            "{id} has no pair ({a}, {b}): add b - a to sweep.balance_separations"
                        ))
                    })?;
                let grid = RATIO.read(table)?[row];
                let id = instances::collisions(collisions);
                let input = inputs
                    .iter()
                    .find(|input| input.id == id)
                    .ok_or_else(|| StageError::Input(format!("no input {id}")))?;
                let (events, draws, _) = collision_events(input)?;
                let bins = Bins::for_window(2.0 * (b - a) + 4.0 * bin_width, *bin_width);
                let target = |u_prime: f64| Target {
                    u_prime,
                    ..kernel.target()
                };
                let kick_floor = kernel.target().kick_floor;
                let fed = [bins.half_bins + steps, bins.half_bins - steps]
                    .map(|k| self_bin_feeders(&events, &bins, k, kick_floor));
                let balance =
                    balance_between((&fed[0], &fed[1]), &draws, &bins, (*a, *steps), target);
                let note = format!(
                    "launches drawn for u' = {a} ({id}), bins of {bin_width}, error paired over the randomizations; the sweep's own row (its launch mixture): {:.3} +- {:.3}; f0(b)/f0(a) = {:.4} (detailed balance)",
                    grid.mean, grid.stderr, balance.expected_ratio
                );
                (balance.ratio, Converged::Same, note)
            }
            Check::RingTime { moments, .. } => {
                use contract::compare::finite_size::{SCALED_TIME, TABLE};
                let (paper, window, truncated) = rates(inputs, moments)?;
                let times = SCALED_TIME.read(TABLE.find(inputs, &instances::compare())?)?;
                let Some(&time) = times.first() else {
                    let note = "no ring: no [[md.system]] of the first ring's potential is at u' = 0, which this row compares";
                    return Ok(PaperRow {
                        published,
                        ours: MISSING,
                        converged: Converged::Missing,
                        note: note.to_string(),
                        comparable: true,
                    });
                };
                let sharing = times
                    .iter()
                    .filter(|t| (*t / time - 1.0).abs() <= 1e-9)
                    .count();
                let note = format!(
                    "rho^2 l v_th t_f = {time:.5} of the first ring ({sharing} of {} compared rings end there); {truncated}",
                    times.len()
                );
                (scaled(paper, time), window.map(|w| scaled(w, time)), note)
            }
            Check::ScalingKernel { cold, hot, .. } => {
                let collisions = instances::collisions(&cold.moments.potential.id());
                let input = inputs
                    .iter()
                    .find(|input| input.id == collisions)
                    .ok_or_else(|| StageError::Input(format!("no input {collisions}")))?;
                let (events, draws, _) = collision_events(input)?;
                let rate = |ring: &ScalingRing| {
                    let edge = 0.5 * ring.moments.window;
                    self_rates(&events, &ring.moments.target(), edge, &draws).variance
                };
                let units = hot.rate_unit_per_ns / cold.rate_unit_per_ns;
                let at_density = scaled(Estimate::paired_ratio(&rate(hot), &rate(cold)), units);
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
                let dilute = Estimate {
                    mean: units,
                    stderr: 0.0,
                };
                return Ok(PaperRow {
                    published,
                    ours: dilute,
                    converged: Converged::Same,
                    note: format!("published: an exact prediction; {note}"),
                    comparable: false,
                });
            }
            Check::ScalingMd { cold, hot, .. } => {
                use contract::compare::finite_size::{MD_VARIANCE, RING, TABLE};
                let table = TABLE.find(inputs, &instances::compare())?;
                let variance = |ring: &ScalingRing| -> Result<Estimate, StageError> {
                    Ok(MD_VARIANCE.read(table)?[RING.row_of(table, &ring.name)?])
                };
                let ratio = scaled(
                    variance(hot)?.ratio(variance(cold)?),
                    cold.final_time_ns / hot.final_time_ns,
                );
                let note = format!(
                    "tagged MD window variance at t_f over t_f: {} ({} ns) over {} ({} ns), independent runs; MD does not assume the scaling, and includes whatever its rings' own rho l does",
                    hot.name, hot.final_time_ns, cold.name, cold.final_time_ns
                );
                (ratio, Converged::Same, note)
            }
            Check::ScalingExponent { density, rings, .. } => exponent_row(inputs, rings, *density)?,
            Check::GasTime { gas, moments, .. } => {
                use contract::gases::{A_N, GAMMA, GAS, TABLE};
                let table =
                    TABLE.find(inputs, &InstanceId::new(contract::gases::STAGE, "study"))?;
                let row = GAS
                    .read(table)?
                    .iter()
                    .position(|name| name == gas)
                    .ok_or_else(|| {
                        StageError::Input(format!("no gas `{gas}` in the gases table"))
                    })?;
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
                (seconds(paper), window.map(seconds), note)
            }
        };
        let note = if published.uncertainty == 0.0 {
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
        };
        Ok(PaperRow {
            published,
            ours,
            converged,
            note,
            comparable: true,
        })
    }
}

/// The code this stage runs (fingerprinted by the build script).
const CODE: &Code = code::of(file!());

impl Stage for PaperStage {
    fn id(&self) -> InstanceId {
        InstanceId::new(contract::paper::STAGE, "study")
    }

    fn code(&self) -> &'static Code {
        CODE
    }

    fn params(&self) -> Value {
        serde_json::to_value(&self.checks).unwrap_or(Value::Null)
    }

    fn tables(&self) -> &'static [&'static str] {
        &[contract::paper::TABLE.name]
    }

    fn inputs(&self) -> Vec<InstanceId> {
        let mut ids: Vec<InstanceId> = Vec::new();
        for id in self.checks.iter().flat_map(Check::inputs) {
            if !ids.contains(&id) {
                ids.push(id);
            }
        }
        ids
    }

    fn work_units(&self) -> u64 {
        1
    }

    fn run(&self, inputs: &[Input], progress: &Progress) -> Result<Vec<Table>, StageError> {
        use contract::paper::*;
        let rows = self
            .checks
            .iter()
            .map(|check| check.row(inputs))
            .collect::<Result<Vec<_>, _>>()?;
        progress.advance(1);
        let table = Rows::new(&rows)
            .with(QUANTITY, |r| r.published.quantity.to_string())
            .with(SOURCE, |r| r.published.source.to_string())
            .with(TABLE_I_N, |r| {
                r.published
                    .table_i
                    .map_or(f64::NAN, |cell| f64::from(cell.n))
            })
            .with(TABLE_I_COLUMN, |r| {
                r.published
                    .table_i
                    .map_or(String::new(), |cell| cell.column.name().to_string())
            })
            .with(UNIT, |r| r.published.unit.to_string())
            .estimate(PUBLISHED, |r| Estimate {
                mean: r.published.value,
                stderr: r.published.uncertainty,
            })
            .estimate(OURS, |r| r.ours)
            .optional(RELATIVE_DIFFERENCE, |r| {
                Some(r.ours.mean / r.published.value - 1.0).filter(|d| d.is_finite())
            })
            .with(Z, |r| {
                if r.comparable {
                    z_score(r.ours, &r.published)
                } else {
                    f64::NAN
                }
            })
            .estimate(OURS_CONVERGED, |r| r.converged.estimate())
            .with(CONVERGED, |r| r.converged.state().to_string())
            .with(NOTE, |r| r.note.clone())
            .table(&TABLE)?;
        Ok(vec![table])
    }
}

/// `(ours - published) / sqrt(ours_stderr^2 + published_uncertainty^2)`;
/// zero when both are exact and equal.
fn z_score(ours: Estimate, published: &Published) -> f64 {
    let difference = ours.mean - published.value;
    if difference == 0.0 {
        return 0.0;
    }
    difference / libm::hypot(ours.stderr, published.uncertainty)
}
