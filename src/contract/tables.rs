//! Every output table of the study, grouped by the stage that writes it: its
//! name, description and columns in file order. The only place a column name
//! is spelled; units follow physics.md (`v_th`, `l/v_th`, `rho^2 l v_th`).

use super::{Col, Pair, TableSpec, UNIT_PER_PANEL, UNIT_PER_ROW};

/// Bin centre relative to `u'` (kernel, md and early-evolution tables).
pub const DU: Col<f64> = Col::f64("du", "v_th", "bin centre relative to u'");
/// Bin centre in the lab (md and early-evolution tables).
pub const BIN_CENTRE: Col<f64> = Col::f64("u", "v_th", "bin centre");
/// Potential id (gases and study tables).
pub const POTENTIAL: Col<String> = Col::text("potential", "potential id");
/// Density `h` in `1/v_th`.
const DENSITY: &str = "1/v_th";
/// Rates in scaled units.
const RATE: &str = "rho^2 l v_th";

/// The `scan` stage.
pub mod scan {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "scan";

    /// Name of the launch pair.
    pub const LAUNCH: Col<String> = Col::text("launch", "name of the launch pair");
    /// Velocity of the second arrival.
    pub const U3: Col<f64> = Col::f64("u3", "v_th", "velocity of the second arrival");
    /// Free-flight arrival offset (also in `collisions`' events).
    pub const ARRIVAL_OFFSET: Col<f64> = Col::f64(
        "arrival_offset",
        "l/v_th",
        "free-flight arrival time of particle 3 minus that of particle 2 at the special particle",
    );
    /// Middle outgoing velocity (also in `collisions`' events).
    pub const OUT_MIDDLE: Col<f64> = Col::f64("out_middle", "v_th", "middle outgoing velocity")
        .or_null("the scene failed (see outcome): no outgoing state");
    /// Fastest outgoing velocity (also in `collisions`' events).
    pub const OUT_FAST: Col<f64> = Col::f64("out_fast", "v_th", "fastest outgoing velocity")
        .or_null("the scene failed (see outcome): no outgoing state");
    /// Outcome of a scene (also in `collisions`' events).
    pub const OUTCOME: Col<String> = Col::text("outcome", "scattered, recombined or failed_*");
    /// Force evaluations of a scene (also in `collisions`' events).
    pub const FORCE_EVALUATIONS: Col<u32> = Col::u32(
        "force_evaluations",
        "1",
        "evaluations of the three pair forces",
    );

    /// `curve.parquet`: one row per launch pair and arrival offset.
    pub mod curve {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "curve",
            description: "mono-energetic kick curves u1f(arrival offset)",
        };
        /// Launch velocity of the first arrival.
        pub const U2: Col<f64> = Col::f64(
            "u2",
            "v_th",
            "velocity of the first arrival (special particle at rest)",
        );
        /// Launch delay for entry at `-sign(u) L/2`.
        pub const LAUNCH_DELAY: Col<f64> = Col::f64(
            "launch_delay",
            "l/v_th",
            "launch time of particle 3 minus that of particle 2 for entry at -sign(u) L/2",
        );
        /// Final velocity of the special particle.
        pub const U1_FINAL: Col<f64> = Col::f64(
            "u1_final",
            "v_th",
            "final velocity of the special particle (sorted matching)",
        )
        .or_null("the scene failed (see outcome): no outgoing state");
        /// Its tolerance sensitivity.
        pub const U1_FINAL_ERROR: Col<f64> = Col::f64(
            "u1_final_error",
            "v_th",
            "|u1_final - u1_final at 100x tighter tolerance|",
        )
        .or_null("the scene failed (see outcome): no outgoing state");
        /// Slowest outgoing velocity.
        pub const OUT_SLOW: Col<f64> = Col::f64("out_slow", "v_th", "slowest outgoing velocity")
            .or_null("the scene failed (see outcome): no outgoing state");
        /// Relative energy error.
        pub const ENERGY_ERROR: Col<f64> = Col::f64(
            "energy_error",
            "1",
            "(E_out - E_in) / E_in of the relative motion",
        )
        .or_null("the scene failed (see outcome): no outgoing state");
        /// Momentum error.
        pub const MOMENTUM_ERROR: Col<f64> = Col::f64(
            "momentum_error",
            "1",
            "|P_out - P_in| / relative-speed scale",
        )
        .or_null("the scene failed (see outcome): no outgoing state");
        /// Accepted steps.
        pub const STEPS: Col<u32> = Col::u32("steps", "1", "accepted integrator steps");
        /// Rejected steps.
        pub const REJECTED_STEPS: Col<u32> =
            Col::u32("rejected_steps", "1", "rejected integrator steps");
    }

    /// `peak.parquet`: one row per launch pair.
    pub mod peak {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "peak",
            description: "peak of each kick curve",
        };
        /// Launch velocity of the first arrival.
        pub const U2: Col<f64> = Col::f64("u2", "v_th", "velocity of the first arrival");
        /// Largest `|u1f|` with its error bound.
        pub const U1_FINAL_MAX_ABS: Pair = bounded!(
            "u1_final_max_abs",
            "v_th",
            "largest |u1f| over arrival offsets, refined between grid points",
            "error bound of u1_final_max_abs (tolerance sensitivity plus bracket spread)"
        )
        .or_null("no peak: every scene of the curve failed");
        /// Arrival offset of the maximum with the bracket's half-width.
        pub const ARRIVAL_OFFSET_AT_MAX: Pair = bounded!(
            "arrival_offset_at_max",
            "l/v_th",
            "arrival offset of the maximum",
            "half-width of the final bracket"
        )
        .or_null("the maximum was not located (no peak, or not bracketed by the offset grid)");
        /// Launch delay of the maximum.
        pub const LAUNCH_DELAY_AT_MAX: Col<f64> = Col::f64(
            "launch_delay_at_max",
            "l/v_th",
            "launch delay of the maximum for entry at -sign(u) L/2",
        )
        .or_null("no peak: every scene of the curve failed");
        /// Offset grid spacing.
        pub const GRID_SPACING: Col<f64> =
            Col::f64("grid_spacing", "l/v_th", "spacing of the offset grid");
        /// Failed scenes of the curve.
        pub const FAILED_SCENES: Col<u32> = Col::u32(
            "failed_scenes",
            "1",
            "scenes of the curve that failed (excluded)",
        );
        /// Worst energy error of the curve.
        pub const WORST_ENERGY_ERROR: Col<f64> = Col::f64(
            "worst_energy_error",
            "1",
            "largest |relative energy error| on the curve",
        );
    }
}

/// The `launches` stage: `launches.parquet`, one row per launch pair drawn.
pub mod launches {
    pub use super::collisions::{POINT, RANDOMIZATION, STRATUM, U2, U3};
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "launches";

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "launches",
        description: "launch pairs of the collision kernel's point set, before integration",
    };
    /// Proposal density of the launch pair.
    pub const LAUNCH_DENSITY: Col<f64> = Col::f64(
        "launch_density",
        "1/v_th^2",
        "proposal density of (|u2|, |u3|) within the stratum",
    );
    /// Third coordinate of the point.
    pub const OFFSET_COORDINATE: Col<f64> = Col::f64(
        "offset_coordinate",
        "1",
        "third coordinate of the scrambled Sobol' point in (0, 1): the arrival offset's when offsets are sampled",
    );
}

/// The `collisions` stage: `events.parquet`, one row per integrated scene.
pub mod collisions {
    pub use super::scan::{ARRIVAL_OFFSET, FORCE_EVALUATIONS, OUT_FAST, OUT_MIDDLE, OUTCOME};
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "collisions";

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "events",
        description: "integrated three-body scenes for the collision kernel",
    };
    /// Replicate.
    pub const RANDOMIZATION: Col<u32> = Col::u32(
        "randomization",
        "1",
        "independent randomization (replicate) of the point set",
    );
    /// Stratum index.
    pub const STRATUM: Col<u32> = Col::u32(
        "stratum",
        "1",
        "sign pattern: 0 opposite sides (u2 > 0 > u3), 1 same side (u2, u3 > 0; mirror image stands for both < 0)",
    );
    /// Sobol' point index.
    pub const POINT: Col<u32> = Col::u32("point", "1", "index of the scrambled Sobol' point");
    /// Node of the offset rule.
    pub const NODE: Col<u32> = Col::u32(
        "node",
        "1",
        "node of the arrival-offset rule within the point's launch pair (0 when the offset is sampled)",
    );
    /// Error bound of the pair's offset rule.
    pub const QUADRATURE_ERROR: Col<f64> = Col::f64(
        "quadrature_error",
        "v_th^2 l/v_th",
        "bound on the error of the launch pair's offset rule on int self_kick^2 d(arrival_offset) (0 when the offset is sampled)",
    );
    /// Launch velocity of the first arrival.
    pub const U2: Col<f64> = Col::f64(
        "u2",
        "v_th",
        "launch velocity of the first arrival, special particle's frame",
    );
    /// Launch velocity of the second arrival.
    pub const U3: Col<f64> = Col::f64("u3", "v_th", "launch velocity of the second arrival");
    /// Proposal density.
    pub const PROPOSAL_DENSITY: Col<f64> = Col::f64(
        "proposal_density",
        "1/(v_th^2 l/v_th)",
        "joint sampling density of (|u2|, |u3|, arrival_offset) within the stratum; for a quadrature node, the launch pair's density over the node's weight",
    );
    /// Slowest outgoing velocity.
    pub const OUT_SLOW: Col<f64> = Col::f64(
        "out_slow",
        "v_th",
        "slowest outgoing velocity, special particle's frame",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
    /// The special particle's kick.
    pub const SELF_KICK: Col<f64> = Col::f64(
        "self_kick",
        "v_th",
        "velocity change of the special particle (sorted matching)",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
    /// Relative energy error.
    pub const ENERGY_ERROR: Col<f64> = Col::f64(
        "energy_error",
        "1",
        "(E_out - E_in) / (E_in + well depth) of the relative motion",
    )
    .or_null("the scene failed (see outcome): no outgoing state");
}

/// The `kernel` stage: `kernel.parquet`, one row per bin.
pub mod kernel {
    pub use super::DU;
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "kernel";

    /// Unit of `G`.
    const G_UNIT: &str = "rho^2 l v_th / v_th";

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel",
        description: "collision kernel G(u' -> u) in units of rho^2 l v_th per v_th",
    };
    /// Lab velocity of the bin.
    pub const U: Col<f64> = Col::f64("u", "v_th", "bin centre (lab velocity)");
    /// The kernel.
    pub const G: Pair = pair!(
        "G",
        G_UNIT,
        "kernel G(u' -> u): rate per unit velocity, +-1 rule, self plus bath",
        "standard error of G from the spread of randomizations"
    );
    /// Its self part.
    pub const G_SELF: Pair = pair!(
        "G_self",
        G_UNIT,
        "part of G from the special particle's own velocity",
        "standard error of G_self"
    );
    /// Its bath part.
    pub const G_BATH: Pair = pair!(
        "G_bath",
        G_UNIT,
        "part of G from the bath particles' velocities",
        "standard error of G_bath"
    );

    /// `kernel_replicates.parquet`: `G` of every randomization alone, one row
    /// per randomization and bin (what `fit` refits one by one, and what any
    /// other error analysis of the kernel starts from).
    pub mod replicates {
        pub use super::super::collisions::RANDOMIZATION;
        use super::*;
        use crate::pipeline::{Input, StageError};

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "kernel_replicates",
            description: "collision kernel G(u' -> u) of each randomization alone, in units of rho^2 l v_th per v_th",
        };
        /// The kernel of one randomization.
        pub const G: Col<f64> = Col::f64(
            "G",
            G_UNIT,
            "kernel G(u' -> u) of this randomization alone: self plus bath",
        );

        /// The kernel of every randomization (`[randomization][bin]`) from
        /// a `kernel` input's replicates table, and the bins' centres
        /// relative to `u'`.
        pub fn read(input: &Input) -> Result<(Vec<Vec<f64>>, Vec<f64>), StageError> {
            let batch = TABLE.of(input)?;
            let (du, randomization, g) = (
                super::DU.read(batch)?,
                RANDOMIZATION.read(batch)?,
                G.read(batch)?,
            );
            let mut kernels: Vec<Vec<f64>> = Vec::new();
            let mut offsets = Vec::new();
            for k in 0..batch.num_rows() {
                let r = randomization[k] as usize;
                if r >= kernels.len() {
                    kernels.resize(r + 1, Vec::new());
                }
                kernels[r].push(g[k]);
                if r == 0 {
                    offsets.push(du[k]);
                }
            }
            if kernels.iter().any(|kernel| kernel.len() != offsets.len()) {
                return Err(StageError::Input(format!(
                    "{}: randomizations with different bins",
                    input.id
                )));
            }
            Ok((kernels, offsets))
        }
    }

    /// `kernel_log.parquet`: the kernel averaged over log-spaced groups of
    /// bins on either side of `u'` (`kernel::tail`), one row per group.
    pub mod log {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "kernel_log",
            description: "collision kernel G(u' -> u) averaged over groups of bins a twentieth of a decade of |u - u'| wide, in units of rho^2 l v_th per v_th",
        };
        /// Mean bin centre of the group.
        pub const DU: Col<f64> = Col::f64(
            "du",
            "v_th",
            "mean of the group's bin centres relative to u'",
        );
        /// Inner edge.
        pub const DU_INNER: Col<f64> = Col::f64(
            "du_inner",
            "v_th",
            "edge of the group nearest u', relative to u'",
        );
        /// Outer edge.
        pub const DU_OUTER: Col<f64> = Col::f64(
            "du_outer",
            "v_th",
            "edge of the group farthest from u', relative to u'",
        );
        /// Width.
        pub const WIDTH: Col<f64> =
            Col::f64("width", "v_th", "width of the group, |du_outer - du_inner|");
        /// Fine bins in the group.
        pub const BINS: Col<u32> = Col::u32("bins", "1", "fine bins of kernel.parquet averaged");
    }
}

/// Scenes drawn (moments and study tables).
const EVENTS: &str = "events";
/// Scenes failed (moments and study tables).
const FAILED_EVENTS: &str = "failed_events";

/// The `moments` stage: `moments.parquet`, one row per truncation.
pub mod moments {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "moments";

    /// Standard error of every rate.
    const SPREAD: &str = "standard error from the spread of randomizations";

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "moments",
        description: "drift and variance rates against truncation, units of rho^2 l v_th",
    };
    /// Truncation half-width.
    pub const TRUNCATION: Col<f64> = Col::f64(
        "truncation",
        "v_th",
        "half-width X: only |u - u'| <= X counts",
    )
    .or_null("no truncation: every |u - u'| counts");
    /// Self drift rate.
    pub const SELF_DRIFT: Pair = pair!(
        "self_drift",
        RATE,
        "drift rate d<u - u'>/dt of the special particle",
        SPREAD
    );
    /// Self variance rate (`a_n`).
    pub const SELF_VARIANCE: Pair = pair!(
        "self_variance",
        RATE,
        "variance rate d<(u - u')^2>/dt of the special particle (a_n at u' = 0)",
        SPREAD
    );
    /// Window drift rate.
    pub const WINDOW_DRIFT: Pair = pair!(
        "window_drift",
        RATE,
        "drift rate of all particles within the truncation",
        SPREAD
    );
    /// Window variance rate.
    pub const WINDOW_VARIANCE: Pair = pair!(
        "window_variance",
        RATE,
        "variance rate of all particles within the truncation",
        SPREAD
    );
    /// Scenes drawn.
    pub const EVENTS: Col<u32> = Col::u32(super::EVENTS, "1", "scenes drawn");
    /// Scenes failed.
    pub const FAILED_EVENTS: Col<u32> = Col::u32(
        super::FAILED_EVENTS,
        "1",
        "scenes that failed (counted as drawn, contributing nothing)",
    );
}

/// Names of the kernel shape parameters (fit and study tables).
const ALPHA: &str = "alpha";
const BETA: &str = "beta";
const SIGMA: &str = "sigma";

/// Unit of the shape amplitude alpha: `g(x) = alpha |x|^-beta exp(...)` is a
/// rate density in `rho^2 l v_th` per `v_th`, and `|x|^-beta` carries
/// `v_th^-beta`.
pub const ALPHA_UNIT: &str = "rho^2 l v_th (v_th)^(beta-1)";

/// The `fit` stage: `fit.parquet`, one row.
pub mod fit {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "fit";

    /// Standard error of every parameter.
    const REFITS: &str =
        "standard error: spread of per-randomization refits times the scale factor";

    /// Systematic error of every parameter.
    const SPREAD: &str = "systematic error from the fit protocol: half the spread (largest minus smallest) of the parameter over every row's protocol, the same on every row";

    /// The table: one row per fit protocol, the study's first.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "fit",
        description: "kernel shape fit near u', one row per fit protocol (the study's first)",
    };
    /// The row of the study's protocol (always the first row).
    pub const STUDY_PROTOCOL: &str = "study";
    /// The row of the paper's protocol, as far as the paper states it.
    pub const PAPER_PROTOCOL: &str = "paper";
    /// The rows varied for the systematic error.
    pub const VARIED_PROTOCOL: &str = "varied";
    /// What the row's protocol is for.
    pub const PROTOCOL: Col<String> = Col::text(
        "protocol",
        "study (the configured range, statistical weights), paper (the same up to the paper's truncation |x| <= 0.04) or varied (ranges and weights varied for the systematic error)",
    );
    /// Weights of the fit.
    pub const WEIGHTS: Col<String> = Col::text(
        "weights",
        "statistical (1 / stderr^2 of the group means) or relative (1 / G^2: least squares in ln G; its chi2 is not a goodness of fit)",
    );
    /// Amplitude.
    pub const ALPHA: Pair = Pair {
        value: Col::f64(
            super::ALPHA,
            ALPHA_UNIT,
            "amplitude of g(x) = alpha |x|^-beta exp(-x^2/2 sigma^2), fit to the mean kernel",
        ),
        stderr: Col::f64("alpha_stderr", ALPHA_UNIT, REFITS),
    }
    .or_null("the fit did not converge (see status), or its error is not estimable");
    /// Systematic error of alpha.
    pub const ALPHA_SYSTEMATIC: Col<f64> = Col::f64("alpha_systematic", ALPHA_UNIT, SPREAD)
        .or_null("not estimable: a protocol's fit did not converge");
    /// Systematic error of beta.
    pub const BETA_SYSTEMATIC: Col<f64> = Col::f64("beta_systematic", "1", SPREAD)
        .or_null("not estimable: a protocol's fit did not converge");
    /// Systematic error of sigma.
    pub const SIGMA_SYSTEMATIC: Col<f64> = Col::f64("sigma_systematic", "v_th", SPREAD)
        .or_null("not estimable: a protocol's fit did not converge");
    /// Power-law exponent.
    pub const BETA: Pair = Pair {
        value: Col::f64(super::BETA, "1", "power-law exponent near u'"),
        stderr: Col::f64("beta_stderr", "1", REFITS),
    }
    .or_null("the fit did not converge (see status), or its error is not estimable");
    /// Gaussian cut-off.
    pub const SIGMA: Pair = Pair {
        value: Col::f64(
            super::SIGMA,
            "v_th",
            "Gaussian cut-off: largest momentum transfer of a collision",
        ),
        stderr: Col::f64("sigma_stderr", "v_th", REFITS),
    }
    .or_null("the fit did not converge (see status), or its error is not estimable");
    /// Covariance of alpha and beta.
    pub const COV_ALPHA_BETA: Col<f64> = Col::f64(
        "cov_alpha_beta",
        ALPHA_UNIT,
        "covariance of the means of alpha and beta over replicates",
    )
    .or_null("the fit did not converge (see status), or its covariance is not estimable");
    /// Covariance of alpha and sigma.
    pub const COV_ALPHA_SIGMA: Col<f64> = Col::f64(
        "cov_alpha_sigma",
        "rho^2 l v_th (v_th)^beta",
        "covariance of the means of alpha and sigma",
    )
    .or_null("the fit did not converge (see status), or its covariance is not estimable");
    /// Covariance of beta and sigma.
    pub const COV_BETA_SIGMA: Col<f64> = Col::f64(
        "cov_beta_sigma",
        "v_th",
        "covariance of the means of beta and sigma",
    )
    .or_null("the fit did not converge (see status), or its covariance is not estimable");
    /// Error scale factor.
    pub const SCALE_FACTOR: Col<f64> = Col::f64(
        "scale_factor",
        "1",
        "sqrt(max(1, chi2/dof)) applied to the errors and covariances",
    );
    /// Goodness of the mean fit.
    pub const CHI2_PER_DOF: Col<f64> = Col::f64(
        "chi2_per_dof",
        "1",
        "chi-square per degree of freedom of the mean fit (bins treated as independent)",
    )
    .or_null("the fit did not converge (see status)");
    /// Groups fitted.
    pub const BINS: Col<u32> = Col::u32(
        "bins",
        "1",
        "log-spaced groups of bins fitted (with a non-zero error)",
    );
    /// Replicates fitted.
    pub const REPLICATES_FITTED: Col<u32> = Col::u32(
        "replicates_fitted",
        "1",
        "randomizations whose own fit converged",
    );
    /// Fit range, lower end.
    pub const RANGE_MIN: Col<f64> = Col::f64("range_min", "v_th", "smallest |u - u'| fitted");
    /// Fit range, upper end.
    pub const RANGE_MAX: Col<f64> = Col::f64("range_max", "v_th", "largest |u - u'| fitted");
    /// Whether the fit succeeded.
    pub const STATUS: Col<String> = Col::text("status", "fitted, or why not");
}

/// The `sweep` stage.
pub mod sweep {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "sweep";

    /// `rates.parquet`: one row per `u'`.
    pub mod rates {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "rates",
            description: "drift and variance rates against u', dilute limit",
        };
        /// Velocity of the special particle.
        pub const U_PRIME: Col<f64> =
            Col::f64("u_prime", "v_th", "velocity of the special particle");
        /// `D1`.
        pub const SELF_DRIFT: Pair = pair!(
            "self_drift",
            RATE,
            "D1 = d<u - u'>/dt of the special particle (|u - u'| <= window/2)",
            "standard error"
        );
        /// `D2`.
        pub const SELF_VARIANCE: Pair = pair!(
            "self_variance",
            RATE,
            "D2 = d<(u - u')^2>/dt of the special particle",
            "standard error"
        );
        /// `(D2' - u D2) / 2`.
        pub const FOKKER_PLANCK_DRIFT: Pair = pair!(
            "fokker_planck_drift",
            RATE,
            "(dD2/du - u D2) / 2: the drift for which f0 is stationary",
            "standard error (finite differences on the grid)"
        );
        /// Significance of `D1 - (D2' - u D2) / 2`.
        pub const FOKKER_PLANCK_Z: Col<f64> = Col::f64(
            "fokker_planck_z",
            "1",
            "(D1 - Fokker-Planck drift) / its standard error (per-replicate differences)",
        )
        .or_null("not estimable: the difference has no spread over randomizations");
    }

    /// `detailed_balance.parquet`: one row per `(a, b)`.
    pub mod detailed_balance {
        use super::*;

        /// Unit of the self kernel.
        const G_UNIT: &str = "rho^2 l v_th / v_th";

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "detailed_balance",
            description: "detailed balance of the self kernel for nearby velocities",
        };
        /// Initial velocity.
        pub const A: Col<f64> = Col::f64("a", "v_th", "initial velocity");
        /// Final velocity.
        pub const B: Col<f64> = Col::f64(
            "b",
            "v_th",
            "final velocity (a plus a whole number of bins)",
        );
        /// `G_self(a -> b)`.
        pub const G_SELF_AB: Pair = pair!(
            "G_self_ab",
            G_UNIT,
            "self kernel G(a -> b), bin centred on b",
            "standard error"
        );
        /// `G_self(b -> a)`.
        pub const G_SELF_BA: Pair = pair!(
            "G_self_ba",
            G_UNIT,
            "self kernel G(b -> a)",
            "standard error"
        );
        /// Their ratio.
        pub const RATIO: Pair = pair!(
            "ratio",
            "1",
            "G(a -> b) / G(b -> a)",
            "standard error from the randomizations, the two kernels' correlation kept (first order)"
        )
        .or_null("not estimable: G(b -> a) is zero");
        /// `f0(b) / f0(a)`.
        pub const EXPECTED_RATIO: Col<f64> =
            Col::f64("expected_ratio", "1", "f0(b) / f0(a): detailed balance");
        /// Significance of the imbalance.
        pub const IMBALANCE_Z: Col<f64> = Col::f64(
            "imbalance_z",
            "1",
            "(f0(a) G(a->b) - f0(b) G(b->a)) / its standard error (per-replicate differences)",
        )
        .or_null("not estimable: the imbalance has no spread over randomizations");
        /// Share of the imbalance's spread in one randomization.
        pub const LARGEST_SHARE: Col<f64> = Col::f64(
            "largest_share",
            "1",
            "share of the imbalance's spread over randomizations carried by the most deviant one; above 0.5 one scene makes the error and the pair is no evidence (left out of the joint test)",
        )
        .or_null("not estimable: the imbalance has no spread over randomizations");
    }

    /// `balance_tests.parquet`: one joint detailed-balance test per separation.
    pub mod balance_tests {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "balance_tests",
            description: "joint test of detailed balance over the pairs of each separation, with their correlations",
        };
        /// `b - a`.
        pub const SEPARATION: Col<f64> = Col::f64("separation", "v_th", "b - a of the pairs");
        /// Pairs of the separation.
        pub const PAIRS: Col<u32> = Col::u32(
            "pairs",
            "1",
            "independent pairs (a, b) on the u' grid: those with a <= 0 (every scene enters with its mirror image, so a pair at a > 0 repeats its mirror's evidence)",
        );
        /// Pairs counted in the joint test.
        pub const COUNTED: Col<u32> = Col::u32(
            "counted",
            "1",
            "independent pairs whose error is not carried by one randomization (largest_share <= 0.5)",
        );
        /// The joint statistic.
        pub const JOINT_IMBALANCE: Pair = pair!(
            "joint_imbalance",
            "1",
            "sum over counted pairs of (f0(a) G(a->b) - f0(b) G(b->a)) / mean flow, 0 under detailed balance",
            "standard error from its spread over randomizations (pairs share scenes: their correlations are in it)"
        )
        .or_null("not estimable: fewer than two randomizations or no counted pair");
        /// Its z-score.
        pub const JOINT_Z: Col<f64> = Col::f64(
            "joint_z",
            "1",
            "joint_imbalance / its standard error: 0 +- 1 under detailed balance",
        )
        .or_null("not estimable: fewer than two randomizations or no counted pair");
        /// Share of the joint statistic's spread in one randomization.
        pub const JOINT_LARGEST_SHARE: Col<f64> = Col::f64(
            "joint_largest_share",
            "1",
            "share of joint_imbalance's spread carried by one randomization; above 0.5 one scene makes the error (z ~ +-1 by construction) and the test is no evidence",
        )
        .or_null("not estimable: fewer than two randomizations or no counted pair");
    }
}

/// `a_n` (convergence, gases and study tables).
const A_N: &str = "a_n";

/// The `convergence` stage: `convergence.parquet`, one row per setting.
pub mod convergence {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "convergence";

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "convergence",
        description: "a_n under changes of the numerical settings",
    };
    /// Which setting.
    pub const PARAMETER: Col<String> = Col::text(
        "parameter",
        "default, density (rho l), offset_bound (|tau| <= B T), tolerance, bin_width (a_n from the binned kernel)",
    );
    /// Labels of [`PARAMETER`].
    pub mod parameter {
        /// The configured settings.
        pub const DEFAULT: &str = "default";
        /// `rho l` of the literal algorithm.
        pub const DENSITY: &str = "density";
        /// A bound `|tau| <= B T` on the arrival offset.
        pub const OFFSET_BOUND: &str = "offset_bound";
        /// The integrator tolerance.
        pub const TOLERANCE: &str = "tolerance";
        /// The bin width of the binned kernel.
        pub const BIN_WIDTH: &str = "bin_width";

        /// Unit of a setting's value: `rho l`, the bound `B` (in units of
        /// the crossing time `T`) and the tolerance are pure numbers, a bin
        /// width is in `v_th`; the default row has no value.
        pub fn unit(parameter: &str) -> &'static str {
            match parameter {
                DENSITY | OFFSET_BOUND | TOLERANCE => "1",
                BIN_WIDTH => "v_th",
                _ => "",
            }
        }
    }
    /// The setting's value.
    pub const VALUE: Col<f64> = Col::f64("value", UNIT_PER_ROW, "the setting's value")
        .or_null("the default row: no setting varied");
    /// Unit of the setting's value.
    pub const UNIT: Col<String> = Col::text(
        "unit",
        "unit of this row's value: 1 (density, offset_bound, tolerance), v_th (bin_width), empty (default)",
    );
    /// `a_n` at the setting.
    pub const A_N: Pair = Pair {
        value: Col::f64(
            super::A_N,
            RATE,
            "self variance rate at u' = 0 within half the window (tolerance rows: of the launch pairs re-integrated)",
        ),
        stderr: Col::f64(
            "a_n_stderr",
            RATE,
            "standard error (spread of randomizations)",
        ),
    };
    /// Paired shift against the default.
    pub const SHIFT: Pair = pair!(
        "shift",
        RATE,
        "a_n minus the default's on the same launch pairs, per replicate, averaged",
        "standard error of the paired shift"
    );
    /// Shift over the default's error.
    pub const SHIFT_OVER_ERROR: Col<f64> = Col::f64(
        "shift_over_error",
        "1",
        "shift divided by the default's standard error: |value| << 1 means converged",
    );
}

/// The `evolve` stage.
pub mod evolve {
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
            "Fokker-Planck evolution with the tagged drift and variance rates",
            JACKKNIFE
        );
        /// Limit of `h_full`.
        pub const EQUILIBRIUM_FULL: Col<f64> = Col::f64(
            "equilibrium_full",
            DENSITY,
            "f0 (1 + u u' + (u'^2 - 1)(u^2 - 1)/2): the limit of h_full (number, momentum, energy conserved)",
        );
        /// Limit of `h_tagged`.
        pub const EQUILIBRIUM_TAGGED: Col<f64> = Col::f64(
            "equilibrium_tagged",
            DENSITY,
            "f0: the limit of h_tagged and h_fokker_planck",
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
        /// The Fokker-Planck equation of the tagged rates.
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
        /// Clipped eigenvalue.
        pub const LARGEST_CLIPPED_RATE: Pair = pair!(
            "largest_clipped_rate",
            RATE,
            "largest positive eigenvalue of the estimated generator (symmetrized, invariants projected out), set to zero: Monte Carlo noise",
            JACKKNIFE
        )
        .or_null("not projected: the process has no estimated generator");
        /// Detailed-balance violation.
        pub const ASYMMETRY: Pair = pair!(
            "asymmetry",
            "1",
            "||S - S^T|| / ||S + S^T|| of S = f0^(-1/2) M f0^(1/2): detailed-balance violation of the raw estimate, removed",
            JACKKNIFE
        )
        .or_null("not projected: the process has no estimated generator");
    }

    /// `projection.parquet`: one row per time, the `full` process.
    pub mod projection {
        use super::*;
        pub use super::{TIME_GAMMA, TIME_NS, TIME_SCALED};

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "projection",
            description: "what projecting the full operator's estimate (symmetrization, clipping of positive eigenvalues) does to h_full, against h_full's statistical error",
        };
        /// L1 size of the clipping's change.
        pub const CLIPPING_CHANGE: Pair = pair!(
            "clipping_change",
            "1",
            "sum_i |h_i - h_unclipped_i|: h_unclipped propagates the same symmetrized, invariant-projected operator without clipping its positive eigenvalues (0 when none is positive)",
            JACKKNIFE
        )
        .or_null("overflow: the unprojected evolution diverges beyond the floating-point range");
        /// Weight of `h` in the clipped modes.
        pub const CLIPPED_WEIGHT: Pair = pair!(
            "clipped_weight",
            "1",
            "sum_i |f0^(1/2) sum_(lambda_k > 0) c_k v_k|_i: the part of h kept frozen in the clipped modes at every time (the noiseless rates are <= 0), bounding the clipping's bias",
            JACKKNIFE
        );
        /// Number of the change.
        pub const CLIPPING_NUMBER: Pair = pair!(
            "clipping_number",
            "1",
            "sum_i (h - h_unclipped)_i: 0 to rounding (clipped modes are orthogonal to the invariants)",
            JACKKNIFE
        )
        .or_null("overflow: the unprojected evolution diverges beyond the floating-point range");
        /// Momentum of the change.
        pub const CLIPPING_MOMENTUM: Pair = pair!(
            "clipping_momentum",
            "v_th",
            "sum_i u_i (h - h_unclipped)_i: 0 to rounding",
            JACKKNIFE
        )
        .or_null("overflow: the unprojected evolution diverges beyond the floating-point range");
        /// Second moment of the change.
        pub const CLIPPING_SECOND_MOMENT: Pair = pair!(
            "clipping_second_moment",
            "v_th^2",
            "sum_i u_i^2 (h - h_unclipped)_i: 0 to rounding",
            JACKKNIFE
        )
        .or_null("overflow: the unprojected evolution diverges beyond the floating-point range");
        /// L1 size of the whole projection's change.
        pub const PROJECTION_CHANGE: Pair = pair!(
            "projection_change",
            "1",
            "sum_i |h_i - h_raw_i|: h_raw = exp(t M) h(0) of the raw estimate M (neither symmetrized nor clipped)",
            JACKKNIFE
        )
        .or_null("overflow: the unprojected evolution diverges beyond the floating-point range");
        /// The statistical error of `h_full` in L1.
        pub const H_ERROR_L1: Col<f64> = Col::f64(
            "h_error_l1",
            "1",
            "sum_i of the jackknife standard errors of h_full's node masses: the L1 size of h's statistical error",
        );
        /// Clipping change against the error.
        pub const CLIPPING_CHANGE_OVER_ERROR: Col<f64> = Col::f64(
            "clipping_change_over_error",
            "1",
            "largest clipping_change of the full and every leave-one-out estimate over h_error_l1 (< 1: within the errors)",
        )
        .or_null("h_error_l1 is zero to rounding (h is exact at t = 0): no finite ratio");
        /// Clipped weight against the error.
        pub const CLIPPED_WEIGHT_OVER_ERROR: Col<f64> = Col::f64(
            "clipped_weight_over_error",
            "1",
            "largest clipped_weight of the full and every leave-one-out estimate over h_error_l1",
        )
        .or_null("h_error_l1 is zero to rounding (h is exact at t = 0): no finite ratio");
        /// Projection change against the error.
        pub const PROJECTION_CHANGE_OVER_ERROR: Col<f64> = Col::f64(
            "projection_change_over_error",
            "1",
            "largest projection_change of the full and every leave-one-out estimate over h_error_l1",
        )
        .or_null("h_error_l1 is zero to rounding (h is exact at t = 0): no finite ratio");
    }
}

/// MD estimators: labels of `md`'s summary rows and of `compare`'s goodness rows.
pub mod estimator {
    /// The published estimator.
    pub const PUBLISHED: &str = "published";
    /// The tagged-velocity estimator.
    pub const TAGGED: &str = "tagged";
    /// The thermal estimator.
    pub const THERMAL: &str = "thermal";
}

/// Error over MD runs.
const OVER_RUNS: &str = "standard error over runs";

/// The `md` stage.
pub mod md {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "md";

    /// `h.parquet`: one row per bin.
    pub mod h {
        pub use super::super::{BIN_CENTRE, DU};
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "h",
            description: "h(u, t_f) of a ring by molecular dynamics",
        };
        /// Published estimator.
        pub const H_PUBLISHED: Pair = pair!(
            "h_published",
            DENSITY,
            "published estimator: velocities in the bin minus (N - 1) f0, per bin width, averaged over the sample times",
            OVER_RUNS
        );
        /// Tagged-velocity estimator.
        pub const H_TAGGED: Pair = pair!(
            "h_tagged",
            DENSITY,
            "tagged-velocity estimator: change of every velocity lineage starting within start_band of u', per lineage and bin width",
            OVER_RUNS
        );
    }

    /// `summary.parquet`: one row per estimator ([`estimator`](super::estimator)).
    pub mod summary {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "summary",
            description: "moments of h(u, t_f) within the window",
        };
        /// Which estimator.
        pub const ESTIMATOR: Col<String> = Col::text(
            "estimator",
            "published (background subtracted), tagged (velocity lineages starting within start_band of u'), or thermal (every lineage starting with |u| <= 3: number = fraction whose change stays within the window, window_variance = mean of its square there)",
        );
        /// Mass in the window.
        pub const NUMBER: Pair = pair!("number", "1", "sum h dx over the window", OVER_RUNS);
        /// Variance in the window.
        pub const WINDOW_VARIANCE: Pair = pair!(
            "window_variance",
            "v_th^2",
            "sum (u - u')^2 h dx over the window",
            OVER_RUNS
        );
    }

    /// `runs.parquet`: one row per run.
    pub mod runs {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "runs",
            description: "conservation diagnostics and work per run",
        };
        /// Run index.
        pub const RUN: Col<u32> = Col::u32("run", "1", "run index");
        /// Its seed.
        pub const SEED: Col<String> = Col::text("seed", "seed of the run's initial state");
        /// Tagged lineages.
        pub const LINEAGES: Col<f64> =
            Col::f64("lineages", "1", "lineages in the tagged estimator");
        /// Thermal lineages.
        pub const THERMAL_LINEAGES: Col<f64> = Col::f64(
            "thermal_lineages",
            "1",
            "lineages in the thermal estimator (|u| <= 3 at the start)",
        );
        /// Energy error.
        pub const ENERGY_ERROR: Col<f64> =
            Col::f64("energy_error", "1", "|E(t_end) - E(0)| / E(0)");
        /// Momentum error.
        pub const MOMENTUM_ERROR: Col<f64> =
            Col::f64("momentum_error", "v_th", "|P(t_end) - P(0)|");
        /// Macro steps.
        pub const MACRO_STEPS: Col<f64> = Col::f64(
            "macro_steps",
            "1",
            "macro steps of the cluster stepping (accepted steps of a whole ring)",
        );
        /// Pair forces.
        pub const PAIR_FORCES: Col<f64> = Col::f64("pair_forces", "1", "pair-force evaluations");
        /// Bound pairs at the start.
        pub const BOUND_PAIRS_START: Col<u32> = Col::u32(
            "bound_pairs_start",
            "1",
            "bound neighbour pairs (w^2/4 + U < 0) in the initial state",
        );
        /// Bound pairs at the end.
        pub const BOUND_PAIRS_END: Col<u32> = Col::u32(
            "bound_pairs_end",
            "1",
            "bound neighbour pairs at the last sample time",
        );
        /// Sutherland invariants' drift.
        pub const INVARIANT_DRIFT: Col<f64> = Col::f64(
            "invariant_drift",
            "v_th",
            "largest change of a Lax eigenvalue (rapidity) over the run: the n = 2 Sutherland ring's conservation check",
        )
        .or_null("not the n = 2 Sutherland ring: no conserved rapidities to check");
    }

    /// The tables of a shard of a ring's runs (stage `md.shard`): every run's
    /// estimators and diagnostics, exactly, for the merge into the ring's tables.
    pub mod shard {
        pub use super::runs::{
            BOUND_PAIRS_END, BOUND_PAIRS_START, ENERGY_ERROR, INVARIANT_DRIFT, LINEAGES,
            MACRO_STEPS, MOMENTUM_ERROR, PAIR_FORCES, RUN, THERMAL_LINEAGES,
        };
        use super::*;

        /// One row per run.
        pub const RESULTS: TableSpec = TableSpec {
            stage: STAGE,
            name: "run_results",
            description: "each run's diagnostics and thermal-lineage estimates (a shard of the runs)",
        };
        /// Thermal lineages within the window.
        pub const THERMAL_NUMBER: Col<f64> = Col::f64(
            "thermal_number",
            "1",
            "fraction of thermal lineages whose change stays within the window",
        );
        /// Their mean square change.
        pub const THERMAL_WINDOW_VARIANCE: Col<f64> = Col::f64(
            "thermal_window_variance",
            "v_th^2",
            "mean square change of the thermal lineages within the window",
        );
        /// One row per run and bin.
        pub const BINS: TableSpec = TableSpec {
            stage: STAGE,
            name: "run_bins",
            description: "each run's estimators per bin (a shard of the runs)",
        };
        /// Bin index.
        pub const BIN: Col<u32> = Col::u32("bin", "1", "bin index");
        /// The run's published estimator.
        pub const PUBLISHED: Col<f64> = Col::f64(
            "published",
            "1/v_th",
            "the run's published estimator, averaged over the sample times",
        );
        /// The run's tagged estimator.
        pub const TAGGED: Col<f64> = Col::f64(
            "tagged",
            "1/v_th",
            "the run's tagged-velocity estimator, averaged over the sample times",
        );
    }

    /// `pairs.parquet`: one row per state.
    pub mod pairs {
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "pairs",
            description: "bound neighbour pairs of the ring: sampler, dynamics and dilute limit",
        };
        /// Which state.
        pub const STATE: Col<String> = Col::text(
            "state",
            "initial (sampled), final (after MD), or dilute_limit (rho K_b)",
        );
        /// Bound fraction.
        pub const BOUND_FRACTION: Pair = pair!(
            "bound_fraction",
            "1",
            "bound neighbour pairs per gap",
            "standard error over runs (0 for the closed form; its O(rho l) correction is not included)"
        );
        /// Row of the sampled initial states.
        pub const INITIAL: &str = "initial";
        /// Row after the dynamics.
        pub const FINAL: &str = "final";
        /// Row of the closed form `rho K_b`.
        pub const DILUTE_LIMIT: &str = "dilute_limit";
    }
}

/// The md system (compare's tables).
const RING: &str = "ring";

/// The `compare` stage.
pub mod compare {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "compare";

    /// The md system.
    pub const RING: Col<String> = Col::text(super::RING, "md system");

    /// `comparison.parquet`: one row per ring and bin.
    pub mod comparison {
        pub use super::super::DU;
        pub use super::RING;
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "comparison",
            description: "h(u, t_f) of every ring: MD against Boltzmann",
        };
        /// Boltzmann `h`.
        pub const H_BOLTZMANN: Pair = pair!(
            "h_boltzmann",
            DENSITY,
            "master equation with the translation-invariant kernel at t_f, exact in Fourier space, on the ring's bins",
            "jackknife standard error over the kernel's randomizations"
        );
        /// MD, published.
        pub const H_PUBLISHED: Pair =
            pair!("h_published", DENSITY, "MD, published estimator", OVER_RUNS);
        /// MD, tagged.
        pub const H_TAGGED: Pair = pair!(
            "h_tagged",
            DENSITY,
            "MD, tagged-velocity estimator",
            OVER_RUNS
        );
    }

    /// `goodness.parquet`: one row per ring, reference and estimator.
    pub mod goodness {
        pub use super::RING;
        use super::*;

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "goodness",
            description: "goodness of fit of MD against Boltzmann, and of the scaling collapse",
        };
        /// Reference.
        pub const REFERENCE: Col<String> = Col::text(
            "reference",
            "boltzmann, or the ring it is compared with (scaling collapse)",
        );
        /// The reference of MD against the Boltzmann evolution.
        pub const BOLTZMANN: &str = "boltzmann";
        /// MD estimator ([`estimator`](super::super::estimator)).
        pub const ESTIMATOR: Col<String> = Col::text("estimator", "MD estimator");
        /// Chi-square with the covariance MD would have if it followed the reference.
        pub const CHI2: Col<f64> = Col::f64(
            "chi2",
            "1",
            "d^T (C + S)^-1 d over groups of bins of at least 10 expected counts, the largest cell left out: d the group masses of MD minus the reference's, C their covariance if MD followed the reference (multinomial counts), S the reference's squared standard errors",
        );
        /// Degrees of freedom.
        pub const DOF: Col<u32> = Col::u32("dof", "1", "groups of bins kept");
        /// Reduced chi-square.
        pub const CHI2_PER_DOF: Col<f64> = Col::f64(
            "chi2_per_dof",
            "1",
            "chi2 / dof: ~1 when MD follows the reference",
        )
        .or_null("no degrees of freedom: no test");
        /// p-value of `chi2` with `dof` degrees of freedom.
        pub const P_VALUE: Col<f64> = Col::f64(
            "p_value",
            "1",
            "probability of a chi2 at least this large if MD followed the reference",
        )
        .or_null("no degrees of freedom: no test");
        /// Reduced chi-square with the MD runs' own spread (the published definition).
        pub const SAMPLE_CHI2_PER_DOF: Col<f64> = Col::f64(
            "sample_chi2_per_dof",
            "1",
            "chi2 / dof with the MD runs' own standard errors, over the bins where they are nonzero (the published estimator's definition)",
        )
        .or_null("no degrees of freedom: no test");
        /// Its degrees of freedom.
        pub const SAMPLE_DOF: Col<u32> = Col::u32(
            "sample_dof",
            "1",
            "bins where the MD runs' standard error is nonzero",
        );
    }

    /// `finite_size.parquet`: one row per ring.
    pub mod finite_size {
        pub use super::RING;
        use super::*;

        /// Unit of window variances.
        const VARIANCE: &str = "v_th^2";
        /// Error of a ratio.
        const PROPAGATED: &str = "propagated from both standard errors";

        /// The table.
        pub const TABLE: TableSpec = TableSpec {
            stage: STAGE,
            name: "finite_size",
            description: "finite-size and density study: MD window variance against Boltzmann per ring",
        };
        /// `N`.
        pub const PARTICLES: Col<u32> = Col::u32("particles", "1", "N");
        /// `rho l`.
        pub const DENSITY: Col<f64> = Col::f64("density", "1", "rho l = (N - 1) l / (2 pi R)");
        /// `rho^2 l v_th t_f`.
        pub const SCALED_TIME: Col<f64> = Col::f64(
            "scaled_time",
            "1",
            "rho^2 l v_th t_f (Gamma t_f = a_n times this)",
        );
        /// Tagged MD variance.
        pub const MD_VARIANCE: Pair = pair!(
            "md_variance",
            VARIANCE,
            "tagged estimator: window variance sum (u - u')^2 h du at t_f",
            OVER_RUNS
        );
        /// Boltzmann variance.
        pub const BOLTZMANN_VARIANCE: Pair = pair!(
            "boltzmann_variance",
            VARIANCE,
            "the same of the Boltzmann h (dilute kernel) on the ring's bins",
            "jackknife over the kernel's randomizations"
        );
        /// Their ratio.
        pub const RATIO: Pair = pair!(
            "ratio",
            "1",
            "md_variance / boltzmann_variance: 1 at large N and small rho l",
            PROPAGATED
        )
        .or_null("not estimable: the ratio's denominator is zero");
        /// Thermal MD variance.
        pub const THERMAL_MD_VARIANCE: Pair = pair!(
            "thermal_md_variance",
            VARIANCE,
            "thermal estimator: mean over every lineage starting with |u| <= 3 of its squared change within the window",
            OVER_RUNS
        );
        /// Thermal Boltzmann variance.
        pub const THERMAL_BOLTZMANN_VARIANCE: Pair = pair!(
            "thermal_boltzmann_variance",
            VARIANCE,
            "t_f times the self kernel's window variance rate averaged over thermal starts (f0 on [-3, 3]); first order in Gamma t_f",
            "standard error over the kernel's randomizations"
        );
        /// Their ratio.
        pub const THERMAL_RATIO: Pair = pair!(
            "thermal_ratio",
            "1",
            "thermal_md_variance / thermal_boltzmann_variance",
            PROPAGATED
        )
        .or_null("not estimable: the ratio's denominator is zero");
    }
}

/// The `gases` stage: `gases.parquet`, one row per gas.
pub mod gases {
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
}

/// The `paper` stage: `paper.parquet`, one row per published number.
pub mod paper {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "paper";

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "paper",
        description: "published numbers of Phys. Rev. E 110, 014114 (2024) against ours under the paper's definition",
    };
    /// What the number is.
    pub const QUANTITY: Col<String> = Col::text("quantity", "the published quantity");
    /// Where the paper gives it.
    pub const SOURCE: Col<String> = Col::text("source", "where the paper gives it");
    /// Unit of the published value and ours.
    pub const UNIT: Col<String> = Col::text("unit", "unit of the value columns of this row");
    /// The row's `n` in Table I.
    pub const TABLE_I_N: Col<f64> =
        Col::f64("table_i_n", "1", "exponent n of the row's Table I cell")
            .or_null("not in Table I");
    /// The row's column in Table I.
    pub const TABLE_I_COLUMN: Col<String> = Col::text(
        "table_i_column",
        "column of the row's Table I cell: a_n, alpha, beta, sigma or |u1f,max| (empty: not in Table I)",
    );
    /// The published value.
    pub const PUBLISHED: Pair = pair!(
        "published",
        UNIT_PER_ROW,
        "the published value",
        "its uncertainty: as printed, else half a unit of its last printed digit"
    );
    /// Ours under the paper's definition.
    pub const OURS: Pair = pair!(
        "ours",
        UNIT_PER_ROW,
        "ours under the paper's definition",
        "standard error"
    )
    .or_null("the study lacks what this row is computed from (see note)");
    /// `ours / published - 1`.
    pub const RELATIVE_DIFFERENCE: Col<f64> =
        Col::f64("relative_difference", "1", "ours / published - 1")
            .or_null("ours is missing (see note), or the published value is zero");
    /// z-score of the difference.
    pub const Z: Col<f64> = Col::f64(
        "z",
        "1",
        "(ours - published) / sqrt(ours_stderr^2 + published_stderr^2)",
    )
    .or_null("no measurement: ours holds by construction, or is missing");
    /// Ours under our (converged) definition, where it differs.
    pub const OURS_CONVERGED: Pair = pair!(
        "ours_converged",
        UNIT_PER_ROW,
        "ours under our definition where it differs from the paper's",
        "standard error"
    )
    .or_null("see converged: our definition is the paper's, or not converged or missing");
    /// Whether ours under our definition differs.
    pub const CONVERGED: Col<String> = Col::text(
        "converged",
        "differs (ours_converged holds it), same (our definition is the paper's), not converged (ours has no converged value yet) or missing",
    );
    /// Where the definitions differ, and how to read the row.
    pub const NOTE: Col<String> = Col::text("note", "where the definitions differ");
}

/// The `table` stage: `table.parquet`, one row per potential.
pub mod table {
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
        description: "thermalization constants a_n and scan maxima per potential",
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
            "self variance rate at u' = 0, dilute limit, |u - u'| <= window/2",
        ),
        stderr: Col::f64(
            "a_n_stderr",
            RATE,
            "standard error of a_n (spread of randomizations)",
        ),
    };
    /// `a_n` without truncation.
    pub const A_N_UNTRUNCATED: Pair = pair!(
        "a_n_untruncated",
        RATE,
        "self variance rate without truncation",
        "standard error of a_n_untruncated"
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
}

/// The `figures` stage: one instance per figure.
pub mod figures {
    use super::*;

    /// The stage, as named in instance ids and the store.
    pub const STAGE: &str = "figures";

    /// `points.parquet`: one row per plotted point. Units of `x` and `y` are
    /// per panel, in the file's `ternary.axes` metadata (the figure's layout):
    /// their declared unit is [`UNIT_PER_PANEL`].
    pub mod points {
        use super::*;

        /// Panel the point is drawn in.
        pub const PANEL: Col<String> = Col::text("panel", "panel of the figure, top to bottom");
        /// Series (a legend entry).
        pub const SERIES: Col<String> = Col::text("series", "series: one legend entry");
        /// Horizontal coordinate.
        pub const X: Col<f64> = Col::f64(
            "x",
            UNIT_PER_PANEL,
            "horizontal coordinate (unit: the panel's x axis)",
        );
        /// Vertical coordinate.
        pub const Y: Col<f64> = Col::f64(
            "y",
            UNIT_PER_PANEL,
            "vertical coordinate (unit: the panel's y axis)",
        )
        .or_null("no value at this point: a null in the plotted table");
        /// Its standard error (0 where the series has none).
        pub const Y_ERROR: Col<f64> = Col::f64(
            "y_error",
            UNIT_PER_PANEL,
            "standard error of y (0 for lines without errors: fits, closed forms)",
        )
        .or_null("no error at this point: a null in the plotted table");
    }
}
