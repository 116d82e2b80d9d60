//! The `gases` stage: `gases.parquet`, one row per gas.

pub use super::POTENTIAL;
use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "gases";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "gases",
    description: "thermalization rates of gases in physical units",
};
/// Name of the gas.
pub const GAS: Col<String> = Col::text("gas", "name of the gas");
/// Temperature.
pub const KT: Col<f64> = Col::f64("kt", "eV", "temperature");
/// Density.
pub const DENSITY: Col<f64> = Col::f64("density", "1/um", "linear number density rho");
/// `l`.
pub const LENGTH_UNIT: Col<f64> = Col::f64("length_unit", "um", "l = l0 (eps/kT)^(1/n)");
/// `v_th`.
pub const THERMAL_SPEED: Col<f64> = Col::f64("thermal_speed", "um/ns", "v_th = sqrt(kT/m)");
/// `l / v_th`.
pub const TIME_UNIT: Col<f64> = Col::f64("time_unit", "ns", "l / v_th");
/// `rho l`.
pub const RHO_L: Col<f64> = Col::f64("rho_l", "1", "scaled density rho l (dilute when << 1)");
/// `a_n`.
pub const A_N: Pair = Pair {
    value: Col::f64(
        super::A_N,
        RATE,
        "self variance rate at u' = 0, dilute limit",
    ),
    stderr: Col::f64("a_n_stderr", RATE, "standard error"),
};
/// `Gamma`.
pub const GAMMA: Pair = pair!(
    "gamma",
    "1/ns",
    "Gamma = a_n rho^2 l v_th: initial growth rate of <(u - u')^2> (u in v_th) per ns, dilute limit",
    "standard error"
);
/// `Gamma` at the gas's density.
pub const GAMMA_AT_DENSITY: Pair = pair!(
    "gamma_at_density",
    "1/ns",
    "Gamma times the paper's launch rule's finite-density factor exp(-r |delay|) at this rho l (box L = kernel.launch_length): an artifact of that algorithm, which depends on L, not the gas's rate at rho l",
    "standard error"
);
/// `1 / Gamma`.
pub const RELAXATION_TIME: Pair = pair!(
    "relaxation_time",
    "ns",
    "1 / Gamma (dilute)",
    "standard error"
)
.or_null("Gamma is zero (no kicks): the gas never relaxes");

/// What `ternary run --details` and the HTML report print of the table.
pub const PRINTOUT: Printout = Printout {
    table: TABLE,
    title: "thermalization rates in physical units (Gamma = a_n rho^2 l v_th, +- standard error)",
    layout: Layout::Joined,
    rows: Selection::All,
    columns: &[
        Printed::new(GAS.name, Shown::Text(GAS)),
        Printed::new(POTENTIAL.name, Shown::Text(POTENTIAL)),
        Printed::new("kT [eV]", Shown::Scientific(KT, 3)),
        Printed::new("rho l", Shown::Scientific(RHO_L, 3)),
        Printed::new("Gamma [1/ns] (dilute)", Shown::Estimate(GAMMA, "-")),
        Printed::new(
            "paper's rule at rho l *",
            Shown::Estimate(GAMMA_AT_DENSITY, "-"),
        ),
        Printed::new(
            "1/Gamma [ns]",
            Shown::Estimate(RELAXATION_TIME, "never: no kicks"),
        ),
    ],
    footnote: Footnote::Line(
        "* Gamma times the paper's launch rule's finite-density factor exp(-r |delay|) in a box of L = kernel.launch_length: an artifact of that algorithm (it depends on L), not the gas's rate at rho l; MD's finite-density change has the opposite sign (finite_size table)",
    ),
};
