//! The `spectrum` stage: the relaxation spectrum of the linearized
//! three-body collision operator (`full`) and of the tagged particle's
//! generator (`tagged`) on a velocity grid.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "spectrum";

/// Jackknife error over the randomizations.
const JACKKNIFE: &str = "jackknife standard error over randomizations";
/// Why a rate over `Gamma` is null.
const NO_GAMMA: &str = "Gamma = 0: no collision changes a velocity (n = 2, integrable)";
/// Unit of rates and eigenvalues.
const RATE_UNIT: &str = super::RATE;
/// Unit of a density in `u`.
const DENSITY_UNIT: &str = super::DENSITY;

/// Which generator (every table).
pub const GENERATOR: Col<String> = Col::text(
    "generator",
    "full: the linearized three-body collision operator (all three particles; conserves number, momentum and energy); tagged: the special particle's velocity alone (conserves number)",
);
/// The linearized three-body operator (a value of [`GENERATOR`]).
pub const FULL: &str = "full";
/// The tagged particle's generator (a value of [`GENERATOR`]).
pub const TAGGED: &str = "tagged";
/// Rank of a mode (spectrum, modes and scenes tables).
pub const MODE: Col<u32> = Col::u32(
    "mode",
    "1",
    "rank of the relaxation rate, 1 = slowest (the gap), in the estimate on all randomizations",
);
/// A relaxation rate.
pub const RATE: Pair = pair!(
    "rate",
    RATE_UNIT,
    "relaxation rate r_k: -eigenvalue of the symmetrized operator f0^(-1/2) M f0^(1/2) with the invariant directions projected out (a mode df = f0 g(u) decays as exp(-r_k t)); negative: a growing mode of the noisy estimate",
    JACKKNIFE
);

/// `spectrum.parquet`: one row per generator and mode.
pub mod rates {
    use super::*;
    pub use super::{GENERATOR, MODE, RATE};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "spectrum",
        description: "relaxation rates of the collision generators, slowest first, in rho^2 l v_th and in units of the variance rate Gamma at u' = 0",
    };
    /// Mirror parity.
    pub const PARITY: Col<String> = Col::text(
        "parity",
        "even (g(-u) = g(u)) or odd (g(-u) = -g(u)) in the estimate on all randomizations (every scene enters with its mirror image, so each mode has one); a start h(u, 0) excites only the modes of its own parity (from u' = 0: the even ones)",
    );
    /// The rate over `Gamma`.
    pub const RATE_OVER_VARIANCE_RATE: Pair = pair!(
        "rate_over_variance_rate",
        "1",
        "r_k / Gamma, Gamma = the tagged particle's variance rate at u' = 0 from the same generator (a_n, untruncated); per replicate, so correlations cancel",
        JACKKNIFE
    )
    .or_null(NO_GAMMA);
}

/// `spectrum_summary.parquet`: one row per generator.
pub mod summary {
    use super::*;
    pub use super::{GENERATOR, RATE};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "spectrum_summary",
        description: "per generator: the grid, the variance rate, the gap and what the estimate's noise does to the spectrum",
    };
    /// Grid half-range.
    pub const VELOCITY_RANGE: Col<f64> = Col::f64(
        "velocity_range",
        "v_th",
        "the grid spans [-velocity_range, velocity_range]",
    );
    /// Grid step.
    pub const GRID_STEP: Col<f64> = Col::f64("grid_step", "v_th", "node spacing of the grid");
    /// Randomizations.
    pub const RANDOMIZATIONS: Col<u32> = Col::u32(
        "randomizations",
        "1",
        "randomizations of the scenes (replicates of the jackknife)",
    );
    /// `Gamma`.
    pub const VARIANCE_RATE: Pair = pair!(
        "variance_rate",
        RATE_UNIT,
        "Gamma: the tagged particle's variance rate at u' = 0, sum_i M_i0 u_i^2 of the tagged generator (a_n without a window)",
        JACKKNIFE
    );
    /// The gap.
    pub const GAP: Pair = pair!(
        "gap",
        RATE_UNIT,
        "the slowest relaxation rate: r_1, or with growing modes (noise) the slowest mode above them, r_(growing_modes + 1) (same rank in every replicate)",
        JACKKNIFE
    );
    /// The gap over `Gamma`.
    pub const GAP_OVER_VARIANCE_RATE: Pair = pair!(
        "gap_over_variance_rate",
        "1",
        "gap / Gamma, per replicate",
        JACKKNIFE
    )
    .or_null(NO_GAMMA);
    /// Growing modes.
    pub const GROWING_MODES: Col<u32> = Col::u32(
        "growing_modes",
        "1",
        "modes of the estimate on all randomizations with a negative rate (noise: the operator has none; evolve clips them)",
    );
    /// Most negative rate.
    pub const FASTEST_GROWTH: Col<f64> = Col::f64(
        "fastest_growth",
        RATE_UNIT,
        "-(most negative rate), 0 when none: the noise scale of the spectrum's low end",
    );
    /// Detailed-balance violation.
    pub const ASYMMETRY: Pair = pair!(
        "asymmetry",
        "1",
        "||S - S^T||_F / ||S + S^T||_F of S = f0^(-1/2) M f0^(1/2): the estimate's detailed-balance violation",
        JACKKNIFE
    )
    .or_null("a generator that is zero (n = 2)");

    /// What `ternary run --details` and the HTML report print of the table.
    pub const PRINTOUT: Printout = Printout {
        table: TABLE,
        title: "relaxation spectrum: the gap (slowest rate above the growing noise modes) of the linearized operator (full: the gas) and of the tagged particle, over Gamma = the tagged variance rate at u' = 0 [rho^2 l v_th] (+- jackknife errors; docs/spectrum.md)",
        layout: Layout::Joined,
        rows: Selection::All,
        columns: &[
            Printed::new("potential", Shown::Instance),
            Printed::new(GENERATOR.name, Shown::Text(GENERATOR)),
            Printed::new("Gamma", Shown::Estimate(VARIANCE_RATE, "-")),
            Printed::new("gap", Shown::Estimate(GAP, "-")),
            Printed::new(
                "gap / Gamma",
                Shown::Estimate(GAP_OVER_VARIANCE_RATE, "-: no kicks"),
            ),
            Printed::new("growing modes", Shown::Count(GROWING_MODES)),
        ],
        footnote: Footnote::None,
    };
}

/// `spectrum_conserved.parquet`: one row per generator and invariant.
pub mod conserved {
    pub use super::GENERATOR;
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "spectrum_conserved",
        description: "the conserved modes of the symmetrized estimate before projection: zero in the exact operator",
    };
    /// Invariant.
    pub const INVARIANT: Col<String> = Col::text(
        "invariant",
        "number (f0), momentum (f0 u) or energy (f0 u^2), in this order",
    );
    /// Residual.
    pub const RESIDUAL: Pair = pair!(
        "residual",
        RATE_UNIT,
        "||S_sym q||, q the unit invariant direction (orthonormalized in this order): q^T S_sym q = 0 exactly (conservation event by event), so an eigenvalue of S_sym lies within the residual of zero",
        JACKKNIFE
    );
    /// The k-th conserved mode's eigenvalue.
    pub const EIGENVALUE: Pair = pair!(
        "eigenvalue",
        RATE_UNIT,
        "eigenvalue of the row's conserved mode: the eigenvectors lying most in the invariant subspace, as many as invariants, eigenvalue ascending, row k the k-th",
        JACKKNIFE
    );
    /// Its overlap.
    pub const OVERLAP: Pair = pair!(
        "overlap",
        "1",
        "squared length of that eigenvector's projection on the invariant subspace (1: all of it)",
        JACKKNIFE
    );
}

/// `spectrum_modes.parquet`: the shapes of the slowest modes, one row per
/// generator, mode and grid node.
pub mod modes {
    use super::*;
    pub use super::{GENERATOR, MODE};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "spectrum_modes",
        description: "shapes of the slowest relaxation modes, df_k(u) = f0(u) g_k(u)",
    };
    /// Velocity.
    pub const U: Col<f64> = Col::f64("u", "v_th", "grid node");
    /// `g_k(u)`.
    pub const SHAPE: Pair = pair!(
        "shape",
        "1",
        "g_k(u), normalized to <g_k^2>_f0 = 1 and signed to agree with the estimate on all randomizations",
        JACKKNIFE
    );
    /// `f0 g_k`.
    pub const DENSITY: Pair = pair!(
        "density",
        DENSITY_UNIT,
        "df_k(u) = f0(u) g_k(u) per v_th",
        JACKKNIFE
    );
}

/// `spectrum_scenes.parquet`: the slowest rates from subsets of the
/// randomizations, one row per generator, subset size and mode.
pub mod scenes {
    use super::*;
    pub use super::{GENERATOR, MODE};

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "spectrum_scenes",
        description: "how the low end of the spectrum moves as scenes grow: the slowest rates of the generator estimated from disjoint groups of randomizations",
    };
    /// Randomizations per group.
    pub const RANDOMIZATIONS: Col<u32> = Col::u32(
        "randomizations",
        "1",
        "randomizations per group (each group's estimate is the mean of its own)",
    );
    /// Groups.
    pub const GROUPS: Col<u32> = Col::u32(
        "groups",
        "1",
        "disjoint groups: the rate is their mean, the error their spread (null for one group)",
    );
    /// The group mean of a rate.
    pub const RATE: Pair = pair!(
        "rate",
        RATE_UNIT,
        "the mode's rate (rank within each group's own spectrum), mean over the groups",
        "standard error of the mean over the groups"
    )
    .or_null("one group: no spread to measure");
}

/// `spectrum_jackknife.parquet`: the leave-one-out values behind the
/// summary's errors, one row per generator and randomization.
pub mod jackknife {
    pub use super::GENERATOR;
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "spectrum_jackknife",
        description: "the variance rate and the gap of spectrum_summary with each randomization left out: the jackknife's leave-one-out values, from which the covariance of the spectra of several potentials follows (randomization r of every potential draws from the same random stream, so their errors are correlated)",
    };
    /// The randomization left out.
    pub const RANDOMIZATION: Col<u32> = Col::u32(
        "randomization",
        "1",
        "the randomization left out, 0-based; the jackknife error of a summary column is sqrt((R - 1)/R sum_r (x_r - mean x)^2) over these rows",
    );
    /// `Gamma` without this randomization.
    pub const VARIANCE_RATE: Col<f64> = Col::f64(
        "variance_rate",
        RATE_UNIT,
        "spectrum_summary's variance_rate on the other randomizations",
    );
    /// The gap without this randomization.
    pub const GAP: Col<f64> = Col::f64(
        "gap",
        RATE_UNIT,
        "spectrum_summary's gap on the other randomizations (the same rank, growing_modes + 1)",
    );
}

/// The spectrum stage's columns of the study table (`table`, one row per
/// potential).
pub mod study {
    use super::*;

    /// Why a gap is null.
    const NO_SPECTRUM: &str =
        "the spectrum stage is disabled, or Gamma = 0 (n = 2: every rate vanishes)";
    /// The gap of the linearized operator.
    pub const GAP: Pair = pair!(
        "gap",
        RATE_UNIT,
        "relaxation gap of the gas: the slowest relaxation rate of the linearized three-body operator on the spectrum's grid, above any growing (noise) modes (spectrum_summary: gap and growing_modes)",
        "jackknife standard error over randomizations"
    )
    .or_null(NO_SPECTRUM);
    /// The gap over `Gamma`.
    pub const GAP_OVER_VARIANCE_RATE: Pair = pair!(
        "gap_over_variance_rate",
        "1",
        "gap / Gamma, Gamma = the tagged variance rate at u' = 0 from the same scenes (a_n without a window), per replicate",
        "jackknife standard error over randomizations"
    )
    .or_null(NO_SPECTRUM);
    /// The gap of the tagged generator.
    pub const PARTICLE_GAP: Pair = pair!(
        "particle_gap",
        RATE_UNIT,
        "relaxation gap of one particle: the slowest relaxation rate of the tagged particle's generator (how fast one particle forgets its velocity), above any growing (noise) modes",
        "jackknife standard error over randomizations"
    )
    .or_null(NO_SPECTRUM);
    /// The particle gap over `Gamma`.
    pub const PARTICLE_GAP_OVER_VARIANCE_RATE: Pair = pair!(
        "particle_gap_over_variance_rate",
        "1",
        "particle_gap / Gamma, per replicate",
        "jackknife standard error over randomizations"
    )
    .or_null(NO_SPECTRUM);

    /// Where the study table reads them: the potential's spectrum summary,
    /// the row of each generator.
    pub const COLUMNS: [StudyColumn; 4] = [
        gap(GAP, FULL, super::summary::GAP),
        gap(
            GAP_OVER_VARIANCE_RATE,
            FULL,
            super::summary::GAP_OVER_VARIANCE_RATE,
        ),
        gap(PARTICLE_GAP, TAGGED, super::summary::GAP),
        gap(
            PARTICLE_GAP_OVER_VARIANCE_RATE,
            TAGGED,
            super::summary::GAP_OVER_VARIANCE_RATE,
        ),
    ];

    /// `column` read as `value` from the summary row of `generator`.
    const fn gap(column: Pair, generator: &'static str, value: Pair) -> StudyColumn {
        StudyColumn {
            column,
            source: super::summary::TABLE,
            row: Some((GENERATOR, generator)),
            value,
        }
    }
}
