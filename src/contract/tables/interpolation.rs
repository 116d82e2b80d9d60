//! The `interpolation` stage: the kernel models interpolated between the
//! computed kernels (in `1/n`, `ln theta` and `u'`), each computed kernel
//! held out in turn and predicted from its neighbours.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "interpolation";

/// Unit of `G`.
const G_UNIT: &str = "rho^2 l v_th / v_th";

/// Which held-out kernel, from which nodes: the columns both tables lead
/// with.
pub mod held_out {
    pub use super::super::POTENTIAL;
    use super::*;

    /// Along what the kernel is interpolated.
    pub const COORDINATE: Col<String> = Col::text(
        "coordinate",
        "what the kernel is interpolated in: 1/n (inverse power laws with n > 2), ln theta (Lennard-Jones) or u' (every modelled potential, mirror images G(u' -> u) = G(-u' -> -u) included)",
    );
    /// Its `u'`.
    pub const U_PRIME: Col<f64> = Col::f64("u_prime", "v_th", "the held-out kernel's u'");
    /// Its density.
    pub const RHO_L: Col<f64> = Col::f64("density", "1", "the held-out kernel's rho l");
    /// The kernels it is predicted from.
    pub const NODES: Col<String> = Col::text(
        "nodes",
        "the kernels it is predicted from, as ternary kernel would choose them without it: potential ids (the same u'), or u' values (the same potential)",
    );
}

/// `kernel_interpolation.parquet`: one row per held-out kernel and group.
pub mod groups {
    pub use super::super::kernel::log::{DU_INNER, DU_OUTER};
    pub use super::held_out::*;
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_interpolation",
        description: "each computed kernel held out and predicted from its neighbours' models (ln of their group means interpolated by the Lagrange polynomial through the nodes), against its own model at its log-spaced groups measured to better than a third (kernel_model_groups); one row per held-out kernel and group",
    };
    /// The group's middle.
    pub const DU: Col<f64> = Col::f64(
        "du",
        "v_th",
        "middle of the group relative to u' (negative below u')",
    );
    /// The held-out kernel's group mean.
    pub const G: Pair = pair!(
        "G",
        G_UNIT,
        "the held-out kernel's mean over the group (kernel_model_groups)",
        "its standard error pooled with the two neighbouring groups'"
    );
    /// The held-out kernel's model there.
    pub const G_MODEL: Pair = pair!(
        "G_model",
        G_UNIT,
        "the held-out kernel's own model's mean over the group (kernel_model_groups' G_model)",
        "G_model times the jackknife error of its logarithm (kernel_model_jackknife)"
    );
    /// The prediction.
    pub const G_PREDICTED: Pair = pair!(
        "G_predicted",
        G_UNIT,
        "exp of the Lagrange polynomial through the nodes' ln(group mean of the model)",
        "G_predicted times the jackknife error of its logarithm: the Lagrange combination recomputed without each randomization, which the nodes share (their covariance included)"
    );
    /// The interpolation's error.
    pub const LN_RATIO: Pair = pair!(
        "ln_ratio",
        "1",
        "ln(G_model / G_predicted): the interpolation's error at the held-out kernel",
        "its jackknife error, the held-out model and the nodes recomputed together without each randomization (they share scenes): the ratio's noise, beside which the interpolation's bias shows"
    );
    /// The interpolation's own estimate of it.
    pub const CORRECTION: Col<f64> = Col::f64(
        "correction",
        "1",
        "ln G_predicted less the same through every node but the farthest: the last correction of Neville's algorithm, the interpolation's own estimate of its error (what ternary kernel prints)",
    );
    /// The pull.
    pub const Z: Col<f64> = Col::f64(
        "z",
        "1",
        "ln_ratio over the error ternary kernel states for an interpolated kernel, sqrt(correction^2 + (G_predicted_stderr / G_predicted)^2): N(0, 1)-like when that error is right",
    );
}

/// `kernel_interpolation_summary.parquet`: one row per held-out kernel.
pub mod summary {
    pub use super::held_out::*;
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_interpolation_summary",
        description: "each held-out kernel's prediction from its neighbours, summarised over its groups (kernel_interpolation): the interpolation's error in the study's own terms; one row per held-out kernel",
    };
    /// Groups compared.
    pub const GROUPS: Col<u32> = Col::u32("groups", "1", "groups compared");
    /// Median |z|.
    pub const MEDIAN_ABS_Z: Col<f64> = Col::f64(
        "median_abs_z",
        "1",
        "median |z| over the groups: 0.674 when the stated error is right",
    );
    /// Largest |z|.
    pub const LARGEST_ABS_Z: Col<f64> =
        Col::f64("largest_abs_z", "1", "largest |z| over the groups");
    /// Groups beyond two combined errors.
    pub const BEYOND_TWO: Col<u32> = Col::u32(
        "beyond_two",
        "1",
        "groups with |z| > 2: 4.6% of the groups by chance alone",
    );
    /// The interpolation's typical error.
    pub const MEDIAN_ABS_LN_RATIO: Col<f64> = Col::f64(
        "median_abs_ln_ratio",
        "1",
        "median |ln(G_model / G_predicted)| over the groups: the interpolation's typical relative error",
    );
    /// Its own estimate.
    pub const MEDIAN_ABS_CORRECTION: Col<f64> = Col::f64(
        "median_abs_correction",
        "1",
        "median |correction| over the groups: the interpolation's own estimate of that error",
    );
    /// The largest relative deviation.
    pub const LARGEST_DEVIATION: Col<f64> = Col::f64(
        "largest_deviation",
        "1",
        "largest |G_predicted / G_model - 1| over the groups",
    );
}

/// `kernel_interpolation_coordinates.parquet`: one row per coordinate.
pub mod coordinates {
    pub use super::held_out::COORDINATE;
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "kernel_interpolation_coordinates",
        description: "how well the kernel models interpolate along each coordinate: the held-out kernels' groups (kernel_interpolation_summary) summed; one row per coordinate",
    };
    /// Kernels held out.
    pub const HELD_OUT: Col<u32> = Col::u32("held_out", "1", "kernels held out and predicted");
    /// Groups compared.
    pub const GROUPS: Col<u32> =
        Col::u32("groups", "1", "groups compared, over every held-out kernel");
    /// Groups beyond two combined errors.
    pub const BEYOND_TWO: Col<u32> = Col::u32(
        "beyond_two",
        "1",
        "groups with |z| > 2: 4.6% of the groups by chance alone",
    );
    /// Their share.
    pub const BEYOND_TWO_SHARE: Col<f64> = Col::f64(
        "beyond_two_share",
        "1",
        "beyond_two / groups: 0.046 when the stated errors are right",
    );
    /// The held-out kernels' median |z|.
    pub const MEDIAN_ABS_Z: Col<f64> = Col::f64(
        "median_abs_z",
        "1",
        "median over the held-out kernels of their median |z| over groups: 0.674 when the stated errors are right",
    );
    /// Largest |z|.
    pub const LARGEST_ABS_Z: Col<f64> =
        Col::f64("largest_abs_z", "1", "largest |z| over every group");
    /// Whose.
    pub const LARGEST_POTENTIAL: Col<String> = Col::text(
        "largest_potential",
        "potential id of the held-out kernel with the largest |z|",
    );
    /// At what `u'`.
    pub const LARGEST_U_PRIME: Col<f64> = Col::f64(
        "largest_u_prime",
        "v_th",
        "u' of the held-out kernel with the largest |z|",
    );
    /// The largest relative deviation.
    pub const LARGEST_DEVIATION: Col<f64> = Col::f64(
        "largest_deviation",
        "1",
        "largest |G_predicted / G_model - 1| over every group",
    );

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "kernel models between the computed kernels: each held out and predicted from its neighbours' models as `ternary kernel` interpolates them; z = ln(model / predicted) in the error `ternary kernel` states (its interpolation estimate and statistical error in quadrature) per log group, |z| > 2 for 4.6% of the groups and median |z| (the median of the held-out kernels') 0.674 when the errors are right (kernel_interpolation.parquet lists each group; docs/kernel-model.md)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new("in", Shown::Text(COORDINATE)),
            Printed::new("held out", Shown::Count(HELD_OUT)),
            Printed::new("groups", Shown::Count(GROUPS)),
            Printed::new(
                "|z| > 2",
                Shown::Composite(
                    "{} ({})",
                    &[
                        Shown::Count(BEYOND_TWO),
                        Shown::Percent(BEYOND_TWO_SHARE, 1),
                    ],
                ),
            ),
            Printed::new("median |z|", Shown::Fixed(MEDIAN_ABS_Z, 2)),
            Printed::new("largest |z|", Shown::Fixed(LARGEST_ABS_Z, 2)),
            Printed::new(
                "where",
                Shown::Composite(
                    "{} u' = {}",
                    &[
                        Shown::Text(LARGEST_POTENTIAL),
                        Shown::Significant(LARGEST_U_PRIME),
                    ],
                ),
            ),
            Printed::new("largest deviation", Shown::Percent(LARGEST_DEVIATION, 1)),
        ],
        footnote: Footnote::None,
    };
}
