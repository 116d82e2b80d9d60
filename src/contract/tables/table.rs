//! The `table` stage: `table.parquet`, one row per potential.

pub use super::POTENTIAL;
use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "table";
use crate::pipeline::Column;

/// Error of a shape parameter.
const REFITS: &str = "the study's fit: its standard error from refitting each randomization and its systematic error over the fit protocols (the fit table's half-spread) combined";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "table",
    description: "thermalization constants a_n, kernel shapes, relaxation gaps and scan maxima per potential",
};
/// Exponent.
pub const N: Col<f64> = Col::f64(
    "n",
    "1",
    "exponent of the inverse power law (6 for Lennard-Jones: sets the length unit)",
)
.or_null("a family whose length unit does not scale with kT (Morse: l = 1/a)");
/// Temperature of a family with a well.
pub const THETA: Col<f64> = Col::f64("theta", "1", "kT/eps of Lennard-Jones")
    .or_null("an inverse power law: no Lennard-Jones temperature");
/// `a_n`.
pub const A_N: Pair = Pair {
    value: Col::f64(
        super::A_N,
        RATE,
        "self variance rate at u' = 0, dilute limit, of scenes whose three atoms leave free, untruncated (where it has converged: an inverse power law's kicks reach past the window's edge, n = 6 up to ~0.12 v_th from launches near 4 v_th; a well's, O(v_th))",
    ),
    stderr: Col::f64(
        "a_n_stderr",
        RATE,
        "standard error of a_n (spread of randomizations)",
    ),
};
/// The recombination rate at `u' = 0`.
pub const RECOMBINATION_RATE: Pair = pair!(
    "recombination_rate",
    RATE,
    "rate at which the special particle at u' = 0 (dilute limit) takes part in a three-body encounter that leaves a bound pair and a free atom; 0 without a well",
    "standard error of recombination_rate (spread of randomizations)"
);
/// Amplitude of the shape.
pub const ALPHA: Pair = Pair {
    value: Col::f64(
        super::ALPHA,
        ALPHA_UNIT,
        "amplitude of the kernel shape fit alpha |x|^-beta exp(-x^2/2 sigma^2) at u' = 0",
    ),
    stderr: Col::f64("alpha_stderr", ALPHA_UNIT, REFITS),
}
.or_null("the study's fit did not converge, or its error is not estimable");
/// Exponent of the shape.
pub const BETA: Pair = Pair {
    value: Col::f64(super::BETA, "1", "power-law exponent of the kernel near u'"),
    stderr: Col::f64("beta_stderr", "1", REFITS),
}
.or_null("the study's fit did not converge, or its error is not estimable");
/// Cut-off of the shape.
pub const SIGMA: Pair = Pair {
    value: Col::f64(
        super::SIGMA,
        "v_th",
        "Gaussian cut-off of the kernel (largest momentum transfer), v_th",
    ),
    stderr: Col::f64("sigma_stderr", "v_th", REFITS),
}
.or_null("the study's fit did not converge, or its error is not estimable");
/// Scenes drawn.
pub const EVENTS: Col<u32> = Col::u32(super::EVENTS, "1", "scenes drawn for the kernel");
/// Scenes failed.
pub const FAILED_EVENTS: Col<u32> = Col::u32(super::FAILED_EVENTS, "1", "scenes that failed");

/// What `ternary run` and the HTML report print of the table, first.
pub const HEADLINE: Printout = Printout {
    table: TABLE,
    title: "thermalization constants a_n = self variance rate at u' = 0, dilute limit, of scenes whose three atoms leave free, untruncated (converged) [rho^2 l v_th]; recombination: rate of encounters leaving a bound pair [rho^2 l v_th]; dissociation: rate at which atoms break a bound pair, per pair; kernel shape near u' (+- standard errors; shape: statistical and fit-protocol errors combined); relaxation gap of the gas (linearized operator) and of one particle over Gamma (a_n)",
    layout: Layout::Joined,
    rows: Selection::All,
    columns: &[
        Printed::new(POTENTIAL.name, Shown::Text(POTENTIAL)),
        Printed::new("a_n (converged)", Shown::Estimate(A_N, "-")),
        Printed::new("rel.err", Shown::Relative(A_N)),
        Printed::new(
            "recombination",
            Shown::Unless(
                RECOMBINATION_RATE,
                "-",
                &Shown::Estimate(RECOMBINATION_RATE, "-"),
            ),
        ),
        Printed::new(
            "dissociation [rho v_th]",
            Shown::Estimate(super::dissociation::study::DISSOCIATION_RATE, "-"),
        ),
        Printed::new(
            BETA.value.name,
            Shown::Unless(A_N, "no kicks", &Shown::Estimate(BETA, "no fit")),
        ),
        Printed::new(
            "sigma [v_th]",
            Shown::Unless(A_N, "no kicks", &Shown::Estimate(SIGMA, "no fit")),
        ),
        Printed::new(
            "gap/Gamma gas",
            Shown::Estimate(super::spectrum::study::GAP_OVER_VARIANCE_RATE, "-"),
        ),
        Printed::new(
            "1 particle",
            Shown::Estimate(super::spectrum::study::PARTICLE_GAP_OVER_VARIANCE_RATE, "-"),
        ),
        Printed::new(
            "failed",
            Shown::Composite(
                "{}/{}",
                &[Shown::Count(FAILED_EVENTS), Shown::Count(EVENTS)],
            ),
        ),
    ],
    footnote: Footnote::None,
};

/// `u1f_max_<launch>` and `u1f_max_<launch>_error`: the scan maximum of
/// a launch pair per potential, with its error bound.
pub fn scan_maximum(launch: &str, maxima: Vec<f64>, errors: Vec<f64>) -> [Column; 2] {
    let name = format!("u1f_max_{launch}");
    let null = super::scan::peak::U1_FINAL_MAX_ABS.value.null;
    [
        Column::f64(
            &name,
            "v_th",
            "largest |u1f| of the mono-energetic scan of this launch pair",
            null,
            maxima,
        ),
        Column::f64(
            &format!("{name}_error"),
            "v_th",
            "error bound of the scan maximum",
            null,
            errors,
        ),
    ]
}
