//! The `fit` stage: `fit.parquet`, one row.

use super::*;
use crate::kernel::model::{Knots, Part, SideCurve, Warp};
use crate::pipeline::StageError;
use arrow_array::RecordBatch;

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
    "randomizations whose own fit converged to a shape (the standard errors' samples)",
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

/// Unit of `ln G`.
const LN_G_UNIT: &str = "ln(rho^2 l v_th / v_th)";

/// Unit of `G`.
const G_UNIT: &str = "rho^2 l v_th / v_th";

/// `kernel_model.parquet`: the kernel model's knots (`kernel::model`), one
/// row per side and knot. On each side `ln G` is the natural cubic spline
/// through `(t_k, ln_G_k)` in `t = ln|du| + |du| / cutoff_scale`, continued
/// straight beyond the end knots.
pub mod model {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_model",
        description: "kernel model: on each side of u', ln G(u' -> u) (or ln G_self, by part) is the natural cubic spline through (t, ln_G) in t = ln|du| + |du| / cutoff_scale, straight beyond the end knots; one row per part, side and knot",
    };
    /// The part of the kernel modelled.
    pub const PART: Col<String> = Col::text(
        "part",
        "total (the kernel G, self plus bath) or self (its self part G_self: the special particle's own velocity); the bath part G - G_self is the difference of the two models, jackknifed over the randomizations they share",
    );
    /// Side of `u'`.
    pub const SIDE: Col<String> = Col::text(
        "side",
        "below (u < u') or above (u > u'); a mirrored kernel's below rows repeat its above rows",
    );
    /// Knot number.
    pub const KNOT: Col<u32> = Col::u32("knot", "1", "knot number on its side, from u' outwards");
    /// The knot's `u - u'`.
    pub const DU: Col<f64> = Col::f64(
        "du",
        "v_th",
        "u - u' at the knot (negative below u'): the first at the innermost group's inner edge, the last at the outermost resolved group's outer edge",
    );
    /// The knot in the warped distance.
    pub const T: Col<f64> = Col::f64("t", "1", "the knot in t = ln|du| + |du| / cutoff_scale");
    /// The cut-off scale of the warp.
    pub const CUTOFF_SCALE: Col<f64> = Col::f64(
        "cutoff_scale",
        "v_th",
        "x_c of the side's warp t = ln|du| + |du| / x_c: a quarter of the last knot's |du|",
    );
    /// `ln G` at the knot.
    pub const LN_G: Pair = Pair {
        value: Col::f64(
            "ln_G",
            LN_G_UNIT,
            "ln G at the knot: the spline's value there",
        ),
        stderr: Col::f64(
            "ln_G_stderr",
            LN_G_UNIT,
            "standard error of ln_G: jackknife over the randomizations (kernel_model_covariance holds the covariance)",
        ),
    };
}

/// `kernel_model_covariance.parquet`: the jackknife covariance of each
/// side's knot values, one row per side and pair of knots (with which the
/// error of `ln G` anywhere is `sqrt(b^T C b)`, `b` the spline's cardinal
/// basis there).
pub mod model_covariance {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_model_covariance",
        description: "jackknife covariance over the randomizations of the kernel model's ln_G at the knots of one side, one row per part, side and pair of knots",
    };
    /// The first knot.
    pub const KNOT_I: Col<u32> = Col::u32("knot_i", "1", "knot number of the first value");
    /// The second knot.
    pub const KNOT_J: Col<u32> = Col::u32("knot_j", "1", "knot number of the second value");
    /// The covariance.
    pub const COVARIANCE: Col<f64> = Col::f64(
        "covariance",
        "ln(rho^2 l v_th / v_th)^2",
        "covariance of ln_G at knot_i and knot_j: (R - 1)/R sum over the fits leaving out one randomization each",
    );
}

/// `kernel_model_jackknife.parquet`: each side's knot values fitted
/// without each randomization in turn, one row per side, randomization and
/// knot: the covariance's source, and paired across the kernels computed
/// from the same scenes (every `u'` of a potential) for the error of any
/// function of several models.
pub mod model_jackknife {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_model_jackknife",
        description: "the kernel model's ln_G at the knots of one side fitted without one randomization (the jackknife replicates of kernel_model_covariance), one row per part, side, left-out randomization and knot",
    };
    /// The randomization left out.
    pub const RANDOMIZATION: Col<u32> = Col::u32(
        "randomization",
        "1",
        "the randomization left out (the kernel's randomization numbers: kernels of the same scenes share them)",
    );
    /// Knot number.
    pub const KNOT: Col<u32> = Col::u32("knot", "1", "knot number on its side, from u' outwards");
    /// `ln G` at the knot without the randomization.
    pub const LN_G: Col<f64> = Col::f64(
        "ln_G",
        LN_G_UNIT,
        "ln G at the knot fitted without the randomization: with R randomizations, kernel_model_covariance is (R - 1)/R sum over them of the deviations' products from their mean",
    );
}

/// A `fit` instance's tables of its kernel model.
pub struct ModelTables<'a> {
    /// `kernel_model`.
    pub knots: &'a RecordBatch,
    /// `kernel_model_covariance`.
    pub covariance: &'a RecordBatch,
    /// `kernel_model_jackknife`.
    pub jackknife: &'a RecordBatch,
}

/// The rows of `batch` (a model table, with [`model::PART`]) of `part`.
pub fn part_rows(batch: &RecordBatch, part: Part) -> Result<Vec<usize>, StageError> {
    let parts = model::PART.read(batch)?;
    Ok((0..parts.len())
        .filter(|&k| parts[k] == part.name())
        .collect())
}

/// The row of `kernel_model_fit` (`batch`) that tests `part`'s model.
pub fn goodness_row(batch: &RecordBatch, part: Part) -> Result<usize, StageError> {
    part_rows(batch, part)?.first().copied().ok_or_else(|| {
        StageError::Input(format!(
            "kernel_model_fit has no row of part {}",
            part.name()
        ))
    })
}

/// The rows of `batch` (a table with [`model::PART`] and [`model::SIDE`])
/// of `part`'s model on `side`.
fn rows_of(batch: &RecordBatch, part: Part, side: &str) -> Result<Vec<usize>, StageError> {
    let sides = model::SIDE.read(batch)?;
    Ok(part_rows(batch, part)?
        .into_iter()
        .filter(|&k| sides[k] == side)
        .collect())
}

/// The model of `part` on `side` (`below` or `above` `u'`) of a `fit`
/// instance: its knots, their covariance and their jackknife replicates.
pub fn side_curve(tables: &ModelTables, part: Part, side: &str) -> Result<SideCurve, StageError> {
    use model::{CUTOFF_SCALE, LN_G, T};
    let rows = rows_of(tables.knots, part, side)?;
    let first = *rows.first().ok_or_else(|| {
        StageError::Input(format!(
            "kernel_model has no knots of part {} {side} u'",
            part.name()
        ))
    })?;
    let (t, values) = (T.read(tables.knots)?, LN_G.read(tables.knots)?);
    Ok(SideCurve {
        knots: Knots {
            warp: Warp {
                cutoff_scale: CUTOFF_SCALE.read(tables.knots)?[first],
            },
            t: rows.iter().map(|&k| t[k]).collect(),
        },
        values: rows.iter().map(|&k| values[k].mean).collect(),
        covariance: covariance_of(tables.covariance, part, side, rows.len())?,
        left_out: left_out_of(tables.jackknife, part, side, rows.len())?,
    })
}

/// The `size` x `size` covariance of `part`'s knot values on `side`,
/// row-major.
fn covariance_of(
    batch: &RecordBatch,
    part: Part,
    side: &str,
    size: usize,
) -> Result<Vec<f64>, StageError> {
    use model_covariance::{COVARIANCE, KNOT_I, KNOT_J};
    let mut matrix = vec![0.0; size * size];
    let (i, j) = (KNOT_I.read(batch)?, KNOT_J.read(batch)?);
    let entries = COVARIANCE.read(batch)?;
    for k in rows_of(batch, part, side)? {
        let (i, j) = (i[k] as usize, j[k] as usize);
        if i >= size || j >= size {
            return Err(StageError::Input(format!(
                "kernel_model_covariance: knot ({i}, {j}) {side} u', beyond its {size} knots"
            )));
        }
        matrix[i * size + j] = entries[k];
    }
    Ok(matrix)
}

/// `part`'s knot values on `side` fitted without each randomization,
/// `[randomization][knot]` (`size` knots).
fn left_out_of(
    batch: &RecordBatch,
    part: Part,
    side: &str,
    size: usize,
) -> Result<Vec<Vec<f64>>, StageError> {
    use model_jackknife::{KNOT, LN_G, RANDOMIZATION};
    let (randomization, knot) = (RANDOMIZATION.read(batch)?, KNOT.read(batch)?);
    let values = LN_G.read(batch)?;
    let mut left_out: Vec<Vec<f64>> = Vec::new();
    for k in rows_of(batch, part, side)? {
        let (r, j) = (randomization[k] as usize, knot[k] as usize);
        if j >= size {
            return Err(StageError::Input(format!(
                "kernel_model_jackknife: knot {j} {side} u', beyond its {size} knots"
            )));
        }
        if r >= left_out.len() {
            left_out.resize(r + 1, vec![f64::NAN; size]);
        }
        left_out[r][j] = values[k];
    }
    Ok(left_out)
}

/// `kernel_model_fit.parquet`: the kernel model's goodness of fit, one row.
pub mod model_fit {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_model_fit",
        description: "goodness of fit of the kernel model to the log-spaced groups of kernel_log, both sides together, calibrated by flipping the randomizations' deviations from the model (a wild bootstrap); one row per part (total, self)",
    };
    /// Fitted, or why not.
    pub const STATUS: Col<String> = Col::text(
        "status",
        "fitted, or why the kernel has no model (fewer than three randomizations, or a side with fewer than three groups measured to better than a third, as the vanishing n = 2 kernel)",
    );
    /// Whether one model stands for both sides.
    pub const MIRRORED: Col<u32> = Col::u32(
        "mirrored",
        "1",
        "1 when the two sides are equal in every randomization (the mirror images at u' = 0) and one model describes both, else 0",
    );
    /// Groups fitted.
    pub const GROUPS: Col<u32> = Col::u32(
        "groups",
        "1",
        "log-spaced groups fitted (one side's when mirrored)",
    );
    /// Knots.
    pub const KNOTS: Col<u32> = Col::u32(
        "knots",
        "1",
        "knots of every side: the model's parameters, chosen per side by leaving out each randomization in turn",
    );
    /// Degrees of freedom.
    pub const DOF: Col<u32> = Col::u32("dof", "1", "groups minus knots");
    /// Chi-square.
    pub const CHI2: Col<f64> = Col::f64(
        "chi2",
        "1",
        "sum over groups of (G - model)^2 / var, var the variance of the group mean pooled with its two neighbours'",
    )
    .or_null("no model (see status)");
    /// Its expectation.
    pub const CHI2_EXPECTED: Col<f64> = Col::f64(
        "chi2_expected",
        "1",
        "mean chi2 of the model refitted to data whose randomizations' deviations from it are flipped in every sign pattern: what a model that follows the kernel gives (compare chi2 / chi2_expected with 1)",
    )
    .or_null("no model (see status)");
    /// The spread of chi-square under the model.
    pub const CHI2_SPREAD: Col<f64> = Col::f64(
        "chi2_spread",
        "1",
        "standard deviation of the refitted chi2 over the sign patterns: how far from chi2_expected a model that follows the kernel may land",
    )
    .or_null("no model (see status)");
    /// The p-value.
    pub const P_VALUE: Col<f64> = Col::f64(
        "p_value",
        "1",
        "share of sign patterns whose refitted chi2 reaches the observed one (the unflipped data counts, so p >= 1 / sign_patterns)",
    )
    .or_null("no model (see status)");
    /// Patterns drawn.
    pub const SIGN_PATTERNS: Col<u32> = Col::u32(
        "sign_patterns",
        "1",
        "sign patterns drawn: all 2^R for R <= 12 randomizations, else 4096 fixed ones",
    );
    /// Whether the fits converged.
    pub const CONVERGED: Col<u32> = Col::u32(
        "converged",
        "1",
        "1 when every side's fit to the mean groups reached a minimum, else 0",
    );

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "kernel model: ln G (part total) and ln G_self (part self) a natural cubic spline in ln|du| + |du| / x_c on each side of u', fitted to kernel_log's groups; chi2 against its mean and spread under flipped randomizations (a wild bootstrap), p the share of flips reaching it (docs/kernel-model.md)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new("kernel", Shown::Instance),
            Printed::new("part", Shown::Text(super::model::PART)),
            Printed::new("knots", Shown::Count(KNOTS)),
            Printed::new("groups", Shown::Count(GROUPS)),
            Printed::new("chi2", Shown::Fixed(CHI2, 1)),
            Printed::new(
                "expected",
                Shown::Estimate(
                    Pair {
                        value: CHI2_EXPECTED,
                        stderr: CHI2_SPREAD,
                    },
                    "-",
                ),
            ),
            Printed::new("chi2/expected", Shown::Quotient(CHI2, CHI2_EXPECTED, 2)),
            Printed::new("p", Shown::Fixed(P_VALUE, 3)),
            Printed::new("status", Shown::Text(STATUS)),
        ],
        footnote: Footnote::None,
    };
}

/// `kernel_model_groups.parquet`: the groups the kernel model was fitted
/// to, with the model's value and the residual, one row per side and group.
pub mod model_groups {
    pub use super::super::kernel::log::{DU_INNER, DU_OUTER};
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_model_groups",
        description: "the log-spaced groups of kernel_log the kernel model is fitted to, with the model's mean over each group and the normalized residual, one row per part, side and group (one side when mirrored)",
    };
    /// The group's mean `u - u'`.
    pub const DU: Col<f64> = Col::f64(
        "du",
        "v_th",
        "middle of the group relative to u' (negative below u')",
    );
    /// The measured group mean.
    pub const G: Col<f64> = Col::f64(
        "G",
        G_UNIT,
        "the kernel's mean over the group, averaged over the randomizations (kernel_log's G)",
    );
    /// Its error as weighted.
    pub const G_STDERR: Col<f64> = Col::f64(
        "G_stderr",
        G_UNIT,
        "standard error of G pooled with the two neighbouring groups' (the root of the averaged variances): the fit's weight is its inverse square",
    );
    /// The model's group mean.
    pub const G_MODEL: Col<f64> = Col::f64("G_model", G_UNIT, "the model's mean over the group");
    /// The residual.
    pub const RESIDUAL: Col<f64> = Col::f64(
        "residual",
        "1",
        "(G - G_model) / G_stderr: chi2 is the sum of its squares",
    );
}
