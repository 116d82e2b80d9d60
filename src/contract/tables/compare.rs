//! The `compare` stage.

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
        description: "goodness of fit of MD against Boltzmann (the shape's chi-square and the window variance's ratio, with their verdict), and of the scaling collapse",
    };
    /// Why a shape column is null.
    const NO_SHAPE: &str =
        "no shape test: the thermal estimator (its reference is a rate, not an h)";
    /// Why a p-value is null.
    const NO_TEST: &str =
        "fewer than 3 degrees of freedom (a test without power), or no shape test (thermal)";
    /// Reference.
    pub const REFERENCE: Col<String> = Col::text(
        "reference",
        "boltzmann, or the ring it is compared with (scaling collapse)",
    );
    /// The reference of MD against the Boltzmann evolution.
    pub const BOLTZMANN: &str = "boltzmann";
    /// MD estimator ([`estimator`]).
    pub const ESTIMATOR: Col<String> = Col::text("estimator", "MD estimator");
    /// Chi-square with the covariance MD would have if it followed the reference.
    pub const CHI2: Col<f64> = Col::f64(
        "chi2",
        "1",
        "d^T (C + S)^-1 d over groups of bins of at least 10 expected counts, the largest cell left out: d the group masses of MD minus the reference's, C their covariance if MD followed the reference (multinomial counts), S the reference's squared standard errors",
    )
    .or_null(NO_SHAPE);
    /// Degrees of freedom.
    pub const DOF: Col<u32> = Col::u32("dof", "1", "groups of bins kept (0: no shape test)");
    /// Reduced chi-square.
    pub const CHI2_PER_DOF: Col<f64> = Col::f64(
        "chi2_per_dof",
        "1",
        "chi2 / dof: ~1 when MD follows the reference",
    )
    .or_null(NO_TEST);
    /// p-value of `chi2` with `dof` degrees of freedom.
    pub const P_VALUE: Col<f64> = Col::f64(
        "p_value",
        "1",
        "probability of a chi2 at least this large if MD followed the reference",
    )
    .or_null(NO_TEST);
    /// Reduced chi-square with the MD runs' own spread (the published definition).
    pub const SAMPLE_CHI2_PER_DOF: Col<f64> = Col::f64(
        "sample_chi2_per_dof",
        "1",
        "chi2 / dof with the MD runs' own standard errors, over the bins where they are nonzero (the published estimator's definition)",
    )
    .or_null(NO_SHAPE);
    /// Its degrees of freedom.
    pub const SAMPLE_DOF: Col<u32> = Col::u32(
        "sample_dof",
        "1",
        "bins where the MD runs' standard error is nonzero",
    );
    /// The window variance against the reference's.
    pub const VARIANCE_RATIO: Pair = pair!(
        "variance_ratio",
        "1",
        "MD's window variance sum (u - u')^2 h du by this estimator over the reference's (finite_size: the published and tagged estimators against the Boltzmann h, the thermal one against t times the thermal rate): 1 when MD follows the reference; the test with power against a broadening",
        "propagated from MD's standard error over runs and the reference's over the kernel's randomizations"
    )
    .or_null("not in the finite-size study: the scaling collapse, and rings of other potentials");
    /// The ratio against 1.
    pub const VARIANCE_Z: Col<f64> = Col::f64(
        "variance_z",
        "1",
        "(variance_ratio - 1) / variance_ratio_stderr",
    )
    .or_null("no variance ratio");
    /// The verdict.
    pub const VERDICT: Col<String> = Col::text(
        "verdict",
        "differs: the shape's p_value below 1e-3 or |variance_z| above 3.29 (thresholds::REJECTED_P, REJECTED_Z); agrees: neither; no test: no p_value and no variance ratio",
    );

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "MD against Boltzmann and the scaling collapse: the shape's chi2 per degree of freedom with the variance MD would have if it followed the reference, its p-value, and (sample) with the runs' own errors; the window variance over the reference's and its z; the verdict of both (differs: p < 1e-3 or |z| > 3.29)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new(RING.name, Shown::Text(RING)),
            Printed::new(REFERENCE.name, Shown::Text(REFERENCE)),
            Printed::new(ESTIMATOR.name, Shown::Text(ESTIMATOR)),
            Printed::new("chi2/dof", Shown::Fixed(CHI2_PER_DOF, 2)),
            Printed::new(DOF.name, Shown::Count(DOF)),
            Printed::new("p", Shown::Test(CHI2, DOF)),
            Printed::new(
                "sample chi2/dof",
                Shown::Composite(
                    "{} ({})",
                    &[
                        Shown::Fixed(SAMPLE_CHI2_PER_DOF, 2),
                        Shown::Count(SAMPLE_DOF),
                    ],
                ),
            ),
            Printed::new("variance / reference", Shown::Estimate(VARIANCE_RATIO, "-")),
            Printed::new("z", Shown::Fixed(VARIANCE_Z, 2)),
            Printed::new(VERDICT.name, Shown::Text(VERDICT)),
        ],
        footnote: Footnote::None,
    };
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

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "finite size and density: window variance at t_f, MD / Boltzmann (+- standard errors); tagged: starts near u', thermal: every start",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new(RING.name, Shown::Text(RING)),
            Printed::new("N", Shown::Count(PARTICLES)),
            Printed::new("rho l", Shown::Scientific(DENSITY, 3)),
            Printed::new("rho^2 l v_th t_f", Shown::Scientific(SCALED_TIME, 4)),
            Printed::new(
                super::super::estimator::TAGGED,
                Shown::Estimate(RATIO, "0/0: no spread"),
            ),
            Printed::new(
                super::super::estimator::THERMAL,
                Shown::Estimate(THERMAL_RATIO, "0/0: no spread"),
            ),
        ],
        footnote: Footnote::None,
    };
}
