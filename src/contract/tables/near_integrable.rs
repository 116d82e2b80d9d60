//! The `near_integrable` stage: how the relaxation rates of `r^-n` vanish as
//! `n -> 2+` (the Calogero point, where every collision only permutes the
//! velocities), from the `spectrum` stage of every inverse power law with
//! `2 < n <= spectrum.near_integrable_max_n`.

pub use super::POTENTIAL;
use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "near_integrable";

/// Jackknife error over the randomizations (the spectrum stage's).
const JACKKNIFE: &str = "jackknife standard error over randomizations (spectrum_summary)";
/// Error of a fitted coefficient.
const FIT_ERROR: &str = "standard error from the fit's covariance: generalized least squares with the covariance of ln rate across the potentials (every potential draws its scenes from the same random stream), the jackknife's over the randomizations (spectrum_jackknife) times (R - 1)/(R - points - 2) so that its inverse is unbiased";
/// Why a fitted value is null.
const TOO_FEW: &str = "fewer than four resolved rates (three coefficients and one degree of freedom), too few randomizations to estimate their covariance (at most points + 2), or their abscissae too close for three coefficients (a singular fit)";

/// A rate is resolved, and fitted, when it is positive by this many
/// standard errors: below it the spectrum's low end is noise (growing
/// modes pull the slowest rate down and its error up).
const RESOLVED_Z: f64 = 3.0;

/// Whether a rate of `near_integrable_rates` is resolved: the rule that
/// picks the points of the fits (and of the figure).
pub fn resolved(rate: crate::stats::Estimate) -> bool {
    rate.stderr > 0.0 && rate.mean > RESOLVED_Z * rate.stderr
}

/// `near_integrable_rates.parquet`: one row per potential.
pub mod rates {
    pub use super::POTENTIAL;
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "near_integrable_rates",
        description: "the variance rate and the relaxation gaps of every inverse power law near the Calogero point n = 2, the points of the near_integrable fits",
    };
    /// `n - 2`.
    pub const EXCESS: Col<f64> =
        Col::f64("n_minus_2", "1", "distance n - 2 from the Calogero point");
    /// `Gamma`.
    pub const VARIANCE_RATE: Pair = pair!(
        "variance_rate",
        RATE,
        "Gamma: the tagged variance rate at u' = 0 of the spectrum's generator (a_n without a window)",
        JACKKNIFE
    );
    /// The gas's gap.
    pub const GAP: Pair = pair!(
        "gap",
        RATE,
        "relaxation gap of the gas (linearized three-body operator; spectrum_summary: gap)",
        JACKKNIFE
    );
    /// One particle's gap.
    pub const PARTICLE_GAP: Pair = pair!(
        "particle_gap",
        RATE,
        "relaxation gap of one particle (tagged generator; spectrum_summary: gap)",
        JACKKNIFE
    );
    /// The gas's gap over `Gamma`.
    pub const GAP_OVER_VARIANCE_RATE: Pair = pair!(
        "gap_over_variance_rate",
        "1",
        "gap / Gamma, per replicate",
        JACKKNIFE
    );
    /// One particle's gap over `Gamma`.
    pub const PARTICLE_GAP_OVER_VARIANCE_RATE: Pair = pair!(
        "particle_gap_over_variance_rate",
        "1",
        "particle_gap / Gamma, per replicate",
        JACKKNIFE
    );
    /// Growing modes of the gas's estimate.
    pub const GROWING_MODES: Col<u32> = Col::u32(
        "growing_modes",
        "1",
        "modes of the gas's estimate that grow (noise; spectrum_summary)",
    );
    /// Growing modes of one particle's estimate.
    pub const PARTICLE_GROWING_MODES: Col<u32> = Col::u32(
        "particle_growing_modes",
        "1",
        "modes of one particle's estimate that grow (noise; spectrum_summary)",
    );
}

/// `near_integrable.parquet`: one row per fitted quantity.
pub mod fits {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "near_integrable",
        description: "the near-integrable law rate = A (n - 2)^p exp(q (n - 2)) of the variance rate, the gaps and their ratios to it, fitted over the resolved rates of near_integrable_rates (generalized least squares in ln rate with the rates' covariance), with the exponent perturbation theory predicts",
    };
    /// What is fitted.
    pub const QUANTITY: Col<String> = Col::text(
        "quantity",
        "variance_rate (Gamma), gap (the gas), particle_gap (one particle), gap_over_variance_rate, particle_gap_over_variance_rate",
    );
    /// Potentials fitted.
    pub const FITTED: Col<String> = Col::text(
        "fitted",
        "the potentials whose rate is resolved (positive, at least three standard errors) and enters the fit, comma-separated",
    );
    /// Number of rates fitted.
    pub const POINTS: Col<u32> = Col::u32("points", "1", "rates in the fit");
    /// The exponent.
    pub const EXPONENT: Pair = pair!("exponent", "1", "p", FIT_ERROR).or_null(TOO_FEW);
    /// The predicted exponent.
    pub const EXPECTED_EXPONENT: Col<f64> = Col::f64(
        "expected_exponent",
        "1",
        "p from first-order perturbation theory about n = 2: every kick is O(n - 2), so every rate O((n - 2)^2) and every ratio of rates O(1)",
    );
    /// The exponent of the law with one more order.
    pub const NEXT_ORDER_EXPONENT: Pair = pair!(
        "next_order_exponent",
        "1",
        "p of the law with the next order, A (n - 2)^p exp(q (n - 2) + s (n - 2)^2), fitted to the same rates the same way: how far the law's truncation moves p",
        FIT_ERROR
    )
    .or_null(TOO_FEW);
    /// The exponent's whole error.
    pub const EXPONENT_ERROR: Col<f64> = Col::f64(
        "exponent_error",
        "1",
        "the error of p that exponent_z divides by: exponent_stderr and the truncation's, |next_order_exponent - exponent| (0 when the next order cannot be fitted), in quadrature (the rates share their launch draws, so their statistical error is far below what the three-coefficient law describes)",
    )
    .or_null(TOO_FEW);
    /// The exponent against the prediction.
    pub const EXPONENT_Z: Col<f64> = Col::f64(
        "exponent_z",
        "1",
        "(exponent - expected_exponent) / exponent_error",
    )
    .or_null(TOO_FEW);
    /// The amplitude.
    pub const AMPLITUDE: Pair = pair!(
        "amplitude",
        "the quantity's unit (rho^2 l v_th for a rate, 1 for a ratio)",
        "A: the quantity over (n - 2)^p exp(q (n - 2))",
        FIT_ERROR
    )
    .or_null(TOO_FEW);
    /// The next order.
    pub const CORRECTION: Pair = pair!("correction", "1", "q", FIT_ERROR).or_null(TOO_FEW);
    /// Chi-square.
    pub const CHI2: Col<f64> = Col::f64("chi2", "1", "chi-square of the fit").or_null(TOO_FEW);
    /// Degrees of freedom.
    pub const DOF: Col<u32> = Col::u32("dof", "1", "points - 3 (0 when not fitted)");
    /// The fit's p-value.
    pub const P_VALUE: Col<f64> = Col::f64(
        "p_value",
        "1",
        "probability of a chi-square at least chi2 if the law holds (chi-square with dof degrees of freedom; the covariance is estimated, so this is approximate for few randomizations)",
    )
    .or_null(TOO_FEW);

    /// What `ternary run` and the HTML report print of the table, after the study table.
    pub const HEADLINE: Printout = Printout {
        table: TABLE,
        title: "near the Calogero point n = 2: rate = A (n - 2)^p exp(q (n - 2)), generalized least squares with the rates' covariance across n over the resolved rates (positive by 3 standard errors; four needed) [A: rho^2 l v_th, or 1 for a ratio] (+- fit errors; z: p against first-order perturbation theory with the law's truncation error, |p - p with s (n - 2)^2|, added; docs/spectrum.md)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new(QUANTITY.name, Shown::Text(QUANTITY)),
            Printed::new("p", Shown::Estimate(EXPONENT, "-")),
            Printed::new("expected", Shown::Fixed(EXPECTED_EXPONENT, 0)),
            Printed::new("z", Shown::Fixed(EXPONENT_Z, 2)),
            Printed::new("A", Shown::Estimate(AMPLITUDE, "-")),
            Printed::new("q", Shown::Estimate(CORRECTION, "-")),
            Printed::new("chi2/dof", Shown::PerDof(CHI2, DOF)),
            Printed::new("p-value", Shown::PValue(CHI2, DOF)),
            Printed::new("fitted", Shown::Text(FITTED)),
        ],
        footnote: Footnote::None,
    };
}
