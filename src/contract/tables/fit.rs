//! The `fit` stage: `fit.parquet`, one row.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "fit";

/// Standard error of every parameter.
const REFITS: &str = "standard error: spread of per-randomization refits times the scale factor";

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
    "randomizations whose own fit gave a shape",
);
/// Fits that stopped before converging.
pub const UNCONVERGED_FITS: Col<u32> = Col::u32(
    "unconverged_fits",
    "1",
    "fits (the mean's and the randomizations') whose Levenberg-Marquardt iterations stopped at their limit of 200 or on singular normal equations, not at a minimum (where chi-square improves by at most 1e-12 of itself, or no step improves it): their parameters are the last iterate",
);
/// Fit range, lower end.
pub const RANGE_MIN: Col<f64> = Col::f64("range_min", "v_th", "smallest |u - u'| fitted");
/// Fit range, upper end.
pub const RANGE_MAX: Col<f64> = Col::f64("range_max", "v_th", "largest |u - u'| fitted");
/// Whether the fit succeeded.
pub const STATUS: Col<String> = Col::text("status", "fitted, or why not");
