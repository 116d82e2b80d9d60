//! The `sweep` stage.

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
    pub const U_PRIME: Col<f64> = Col::f64("u_prime", "v_th", "velocity of the special particle");
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

/// `recombination.parquet`: one row per `u'`, then their thermal average.
pub mod recombination {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "recombination",
        description: "the recombination rate against u' and its thermal average, dilute limit",
    };
    /// Velocity of the special particle.
    pub const U_PRIME: Col<f64> = Col::f64("u_prime", "v_th", "velocity of the special particle")
        .or_null("the average over thermal u': int f0 r du' / int f0 du' over |u'| <= 3 (99.73% of atoms; Simpson, step 0.25)");
    /// The recombination rate.
    pub const RATE_COLUMN: Pair = pair!(
        "recombination_rate",
        RATE,
        "rate at which the special particle takes part in a three-body encounter that leaves a bound pair and a free atom (0 without a well)",
        "standard error (spread of randomizations)"
    );
    /// The mean binding energy of the bound pairs.
    pub const MEAN_BINDING: Pair = pair!(
        "mean_binding",
        "kT",
        "rate-weighted mean binding energy B = -(w^2/4 + U) of the pairs this rate leaves bound (minus the events' binding_energy; 0 at the dissociation threshold, the well depth at the bottom of the well)",
        "standard error (spread of randomizations, first order, the correlation of the B-weighted rate and the rate kept)"
    )
    .or_null("not estimable: no scene recombined (no well, or none drawn)");
}

/// `binding.parquet`: one row per bin of the binding energy.
pub mod binding {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "binding",
        description: "the distribution of the binding energy of the pairs three-body recombination leaves bound, rate per unit binding energy averaged over thermal u', dilute limit (no rows without a well)",
    };
    /// Lower edge of the bin.
    pub const BINDING_LOW: Col<f64> = Col::f64(
        "binding_low",
        "kT",
        "lower edge of the bin of binding energy B = -(w^2/4 + U) of the bound pair (minus the events' binding_energy; 0 at the dissociation threshold)",
    );
    /// Upper edge of the bin.
    pub const BINDING_HIGH: Col<f64> = Col::f64(
        "binding_high",
        "kT",
        "upper edge of the bin: the bins are uniform in B/D, the last ending at the well depth D",
    );
    /// The rate per unit binding energy.
    pub const RATE_DENSITY: Pair = pair!(
        "rate_density",
        "rho^2 l v_th / kT",
        "recombination rate into pairs bound by B in the bin, per unit B, averaged over thermal u' like the thermal row of recombination.parquet: summed times the bin widths, its recombination_rate",
        "standard error (spread of randomizations)"
    );
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

/// `stationarity.parquet`: one row, the joint test of the measured drift
/// against Fokker-Planck stationarity.
pub mod stationarity {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "stationarity",
        description: "joint test of the drift D1 against the stationarity drift (D2' - u D2) / 2 over the independent half of the u' grid, with the points' correlations",
    };
    /// Points joined.
    pub const POINTS: Col<u32> = Col::u32(
        "points",
        "1",
        "grid points at u' < 0 (every scene enters with its mirror image, so those at u' > 0 repeat their evidence; at u' = 0 both drifts vanish)",
    );
    /// The relative residual.
    pub const RELATIVE_RESIDUAL: Pair = pair!(
        "relative_residual",
        "1",
        "sum of s (D1 - P) over the points / sum of |P|, P = (D2' - u D2) / 2 the stationarity drift and s its sign: the drift's relative excess along it (below 0: weaker); 0 for a Fokker-Planck process, a few percent from the higher Kramers-Moyal terms a jump process has",
        "standard error from its spread over randomizations (the points share scenes: their correlations are in it)"
    )
    .or_null("not estimable: fewer than two randomizations");
    /// Its z-score.
    pub const JOINT_Z: Col<f64> =
        Col::f64("joint_z", "1", "relative_residual / its standard error")
            .or_null("not estimable: fewer than two randomizations");
    /// Share of the spread in one randomization.
    pub const LARGEST_SHARE: Col<f64> = Col::f64(
        "largest_share",
        "1",
        "share of relative_residual's spread carried by one randomization; above 0.5 one scene makes the error and the z-score is no evidence",
    )
    .or_null("not estimable: fewer than two randomizations");

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "Fokker-Planck stationarity, joint over u' < 0: the drift's relative excess along P = (D2' - u D2)/2, sum s (D1 - P) / sum |P| (s the sign of P; correlations from the randomizations; below 0 the drift is weaker than stationarity requires)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new("potential", Shown::Instance),
            Printed::new("points", Shown::Count(POINTS)),
            Printed::new("relative residual", Shown::Estimate(RELATIVE_RESIDUAL, "-")),
            Printed::new("z", Shown::Fixed(JOINT_Z, 2)),
            Printed::new("", Shown::Evidence(LARGEST_SHARE)),
        ],
        footnote: Footnote::None,
    };
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

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "detailed balance, joint over the pairs of each separation (sum of relative imbalances, correlations from the randomizations; pairs whose error one randomization carries left out)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new("potential", Shown::Instance),
            Printed::new("b - a", Shown::Fixed(SEPARATION, 3)),
            Printed::new(
                "pairs counted",
                Shown::Composite("{}/{}", &[Shown::Count(COUNTED), Shown::Count(PAIRS)]),
            ),
            Printed::new("joint imbalance", Shown::Estimate(JOINT_IMBALANCE, "-")),
            Printed::new("z", Shown::Fixed(JOINT_Z, 2)),
            Printed::new("", Shown::Evidence(JOINT_LARGEST_SHARE)),
        ],
        footnote: Footnote::None,
    };
}
