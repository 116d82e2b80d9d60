//! The `evolve` stage.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "evolve";

/// Jackknife error of most columns.
const JACKKNIFE: &str = "jackknife standard error";
/// Jackknife error of `h`.
const JACKKNIFE_H: &str = "jackknife standard error over randomizations";

/// Time in `1/Gamma`.
pub const TIME_GAMMA: Col<f64> = Col::f64(
    "time_gamma",
    "1/Gamma",
    "time t Gamma, Gamma = the special particle's variance rate at u' (a_n rho^2 l v_th at u' = 0)",
);
/// Scaled time.
pub const TIME_SCALED: Col<f64> =
    Col::f64("time_scaled", "1/(rho^2 l v_th)", "time t rho^2 l v_th");
/// Physical time.
pub const TIME_NS: Col<f64> = Col::f64("time_ns", "ns", "physical time of the configured gas")
    .or_null("a time given in 1/Gamma: no physical time");

/// `early_evolution.parquet`: one row per time and bin.
pub mod early_evolution {
    pub use super::super::{BIN_CENTRE, DU};
    use super::*;
    pub use super::{TIME_GAMMA, TIME_NS, TIME_SCALED};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "early_evolution",
        description: "early-time h(u, t): convolution semigroup of the kernel at u'",
    };
    /// `h`.
    pub const H: Pair = pair!(
        "h",
        DENSITY,
        "h(u, t) from delta(u - u') under the translation-invariant kernel (self plus bath, within the kernel window), exact in Fourier space",
        JACKKNIFE_H
    );
}

/// `early_summary.parquet`: one row per time.
pub mod early_summary {
    use super::*;
    pub use super::{TIME_GAMMA, TIME_NS, TIME_SCALED};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "early_summary",
        description: "early-time moments of h; kernel rates in rho^2 l v_th",
    };
    /// Integral of `h`.
    pub const NUMBER: Pair = pair!(
        "number",
        "1",
        "integral of h (the window loses what leaves it)",
        JACKKNIFE
    );
    /// Its closed form (the error is not written).
    pub const NUMBER_CLOSED_FORM: Col<f64> = Col::f64(
        "number_closed_form",
        "1",
        "exp(t kappa_0), kappa_p = sum_k g_k x_k^p of the kernel",
    );
    /// Mean of `h`.
    pub const MEAN: Pair = pair!("mean", "v_th", "<u - u'>_h (normalized)", JACKKNIFE);
    /// Variance of `h`.
    pub const VARIANCE: Pair = pair!(
        "variance",
        "v_th^2",
        "variance of h (normalized): grows as t kappa_2 (kappa_2: the window variance rate, ~a_n)",
        JACKKNIFE
    );
    /// Its closed form.
    pub const VARIANCE_CLOSED_FORM: Pair =
        pair!("variance_closed_form", "v_th^2", "t kappa_2", JACKKNIFE);
    /// Excess kurtosis of `h`.
    pub const EXCESS_KURTOSIS: Pair = pair!(
        "excess_kurtosis",
        "1",
        "of h: the cusp's non-Gaussianity, decaying as 1/t (central limit)",
        JACKKNIFE
    );
    /// Its closed form.
    pub const EXCESS_KURTOSIS_CLOSED_FORM: Pair = pair!(
        "excess_kurtosis_closed_form",
        "1",
        "kappa_4 / (t kappa_2^2)",
        JACKKNIFE
    );
}

/// `evolution.parquet`: one row per time and grid node.
pub mod evolution {
    use super::*;
    pub use super::{TIME_GAMMA, TIME_NS, TIME_SCALED};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "evolution",
        description: "h(u, t) by the master equation on a velocity grid (node masses / step)",
    };
    /// Grid node.
    pub const U: Col<f64> = Col::f64("u", "v_th", "grid node");
    /// `h` of the linearized operator.
    pub const H_FULL: Pair = pair!(
        "h_full",
        DENSITY,
        "h(u, t) from delta(u - u') under the linearized three-body operator (all three particles' velocity changes)",
        JACKKNIFE_H
    );
    /// `h` of the special particle alone.
    pub const H_TAGGED: Pair = pair!(
        "h_tagged",
        DENSITY,
        "distribution of the special particle's own velocity (its kicks alone)",
        JACKKNIFE
    );
    /// `h` of the Fokker-Planck equation.
    pub const H_FOKKER_PLANCK: Pair = pair!(
        "h_fokker_planck",
        DENSITY,
        "Fokker-Planck evolution with the tagged variance rate D2 in detailed-balance form (drift (D2' - u D2) / 2: f0 stationary)",
        JACKKNIFE
    );
    /// Limit of `h_full`.
    pub const EQUILIBRIUM_FULL: Col<f64> = Col::f64(
        "equilibrium_full",
        DENSITY,
        "f0 (a + b u + c u^2) with the number, momentum and energy of delta(u - u') on the grid (f0 (1 + u u' + (u'^2 - 1)(u^2 - 1)/2) on an unbounded one): the limit of h_full",
    );
    /// Limit of `h_tagged`.
    pub const EQUILIBRIUM_TAGGED: Col<f64> = Col::f64(
        "equilibrium_tagged",
        DENSITY,
        "f0 normalized on the grid: the limit of h_tagged and h_fokker_planck",
    );
}

/// `evolution_summary.parquet`: one row per process and time.
pub mod evolution_summary {
    use super::*;
    pub use super::{TIME_GAMMA, TIME_NS, TIME_SCALED};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "evolution_summary",
        description: "conservation laws, spread and approach to equilibrium of h(u, t)",
    };
    /// Which process.
    pub const PROCESS: Col<String> = Col::text(
        "process",
        "full (linearized operator), tagged (special particle alone), fokker_planck",
    );
    /// The linearized three-body operator.
    pub const FULL: &str = "full";
    /// The special particle alone.
    pub const TAGGED: &str = "tagged";
    /// The Fokker-Planck equation of the tagged variance rate.
    pub const FOKKER_PLANCK: &str = "fokker_planck";
    /// Node spacing.
    pub const GRID_STEP: Col<f64> = Col::f64("grid_step", "v_th", "node spacing");
    /// `X`.
    pub const WINDOW_HALF_WIDTH: Col<f64> =
        Col::f64("window_half_width", "v_th", "X of window_variance");
    /// Sum of `h`.
    pub const NUMBER: Pair = pair!(
        "number",
        "1",
        "sum of h: 1 for every process (exact up to rounding and the grid's ends)",
        JACKKNIFE
    );
    /// First moment.
    pub const MOMENTUM: Pair = pair!(
        "momentum",
        "v_th",
        "sum u h: u' for full (momentum conservation)",
        JACKKNIFE
    );
    /// Second moment.
    pub const SECOND_MOMENT: Pair = pair!(
        "second_moment",
        "v_th^2",
        "sum u^2 h: u'^2 for full (energy conservation), 1 in equilibrium for tagged",
        JACKKNIFE
    );
    /// Variance over the grid.
    pub const VARIANCE: Pair = pair!(
        "variance",
        "v_th^2",
        "<(u - u')^2>_h over the whole grid",
        JACKKNIFE
    );
    /// Variance in the window.
    pub const WINDOW_VARIANCE: Pair = pair!(
        "window_variance",
        "v_th^2",
        "<(u - u')^2>_h within |u - u'| <= X (the published window): slope a_n at early times",
        JACKKNIFE
    );
    /// L1 distance to the limit.
    pub const DISTANCE_TO_EQUILIBRIUM: Pair = pair!(
        "distance_to_equilibrium",
        "1",
        "sum |h - h_eq| over the nodes (L1), h_eq the process's limit",
        JACKKNIFE
    );
    /// Linearized relative entropy.
    pub const ENTROPY: Pair = pair!(
        "entropy",
        "1",
        "linearized relative entropy to the limit, sum_i (h_i - h_eq,i)^2 / (2 f0_i) over the grid's node masses (H[f0 + df] - H[f0] to second order): non-increasing by the H-theorem",
        JACKKNIFE
    );
    /// Its decay rate.
    pub const ENTROPY_DECAY_RATE: Pair = pair!(
        "entropy_decay_rate",
        "rho^2 l v_th",
        "-(d ln entropy / dt) / 2 between the previous output time and this one: late in the relaxation, the rate of the slowest spectrum mode the start excites (spectrum.parquet: from u' = 0 the slowest even mode)",
        JACKKNIFE
    )
    .or_null("the first output time (no previous one)");
    /// Clipped eigenvalue.
    pub const LARGEST_CLIPPED_RATE: Pair = pair!(
        "largest_clipped_rate",
        RATE,
        "largest positive eigenvalue of the process's generator (symmetrized, invariants projected out), set to zero: rounding, since the Dirichlet form is negative semi-definite for every sample",
        JACKKNIFE
    );
    /// Detailed-balance violation.
    pub const ASYMMETRY: Pair = pair!(
        "asymmetry",
        "1",
        "||S - S^T|| / ||S + S^T|| of S = f0^(-1/2) M f0^(1/2): the generator's detailed-balance violation, rounding for the Dirichlet form (removed)",
        JACKKNIFE
    );

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "evolution of h from delta(u - u') for {instance}: full = linearized operator, tagged = special particle, fokker_planck (+- jackknife errors)",
        layout: Layout::PerInstance,
        rows: Selection::All,
        columns: &[
            Printed::new(PROCESS.name, Shown::Text(PROCESS)),
            Printed::new("t Gamma", Shown::Scientific(TIME_GAMMA, 3)),
            Printed::new("t [ns]", Shown::Fixed(TIME_NS, 0)),
            Printed::new(
                "<(u-u')^2>, |u-u'|<=X",
                Shown::Estimate(WINDOW_VARIANCE, "-"),
            ),
            Printed::new("<(u-u')^2>", Shown::Estimate(VARIANCE, "-")),
            Printed::new(
                "L1 distance to equilibrium",
                Shown::Estimate(DISTANCE_TO_EQUILIBRIUM, "-"),
            ),
            Printed::new("relative entropy", Shown::Estimate(ENTROPY, "-")),
        ],
        footnote: Footnote::None,
    };
}
