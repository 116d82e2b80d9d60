//! The `dissociation` stage: `dissociation.parquet`, one row, and
//! `recombination.parquet`, the recombination rate detailed balance predicts
//! against `u'`.

use super::*;

/// The stage, as named in instance ids and the store.
pub const STAGE: &str = "dissociation";

/// Standard error of every rate.
const SPREAD: &str = "standard error from the spread of randomizations";

/// The table.
pub const TABLE: TableSpec = TableSpec {
    stage: STAGE,
    name: "dissociation",
    description: "collision-induced dissociation A2 + A -> 3A of thermal bound pairs, dilute limit, and the recombination rate detailed balance predicts from it",
};
/// `theta = kT/eps`.
pub const THETA: Col<f64> = Col::f64("theta", "1", "kT/eps of the family's well")
    .or_null("a family without a temperature parameter");
/// `K_b`.
pub const BOUND_PAIR_LENGTH: Col<f64> = Col::f64(
    "bound_pair_length",
    "l",
    "K_b = int_(U<0) exp(-U) erf(sqrt(-U)) dx: a dilute gas holds K_b rho^2 bound pairs per length",
);
/// `k_d`.
pub const DISSOCIATION_RATE: Pair = pair!(
    "dissociation_rate",
    "rho v_th",
    "k_d: rate at which a thermal bound pair is broken into three free atoms by thermal atoms, per pair: sqrt(3/pi) times the share of pair-atom encounters that leave three free atoms",
    SPREAD
);
/// `3 K_b k_d`.
pub const BALANCED_RECOMBINATION: Pair = pair!(
    "balanced_recombination_rate",
    RATE,
    "3 K_b k_d / l: the thermally averaged recombination rate per atom that detailed balance predicts (recombination events rho^3 l v_th R / 3 = dissociation events K_b rho^2 x rho v_th k_d); compare sweep's recombination table",
    SPREAD
);
/// Scenes.
pub const SCENES: Col<u32> = Col::u32("scenes", "1", "pair-atom scenes integrated");
/// Failed scenes.
pub const FAILED_SCENES: Col<u32> = Col::u32(
    "failed_scenes",
    "1",
    "scenes that failed (step budget, breakdown): left out of the rates",
);
/// Largest energy error.
pub const MAX_ENERGY_ERROR: Col<f64> = Col::f64(
    "max_energy_error",
    "1",
    "largest |E_out - E_in| / (|E_in| + D) over the scenes (E relative-motion energy, D well depth)",
);

/// `recombination.parquet`: one row per `u'`, then the thermal average.
pub mod recombination {
    use super::*;

    /// The table.
    pub const TABLE: TableSpec = TableSpec {
        stage: STAGE,
        name: "recombination",
        description: "the recombination rate against u' that detailed balance predicts from the dissociating scenes (compare sweep's recombination table)",
    };
    /// Velocity of the atom.
    pub const U_PRIME: Col<f64> = Col::f64("u_prime", "v_th", "velocity of the atom")
        .or_null("the thermal average, 3 K_b k_d (over every u')");
    /// `R(u')`.
    pub const RATE_COLUMN: Pair = pair!(
        "recombination_rate",
        RATE,
        "rate at which an atom at u' takes part in a three-body encounter leaving a bound pair and a free atom, from detailed balance: f0(u') R(u') = K_b k_d <sum of the densities at u' of the three outgoing velocities>, the centre-of-mass velocity N(0, 1/3) integrated out",
        SPREAD
    );
}

/// The dissociation stage's columns of the study table (`table`, one row per
/// potential).
pub mod study {
    use super::*;

    /// The dissociation rate `k_d`.
    pub const DISSOCIATION_RATE: Pair = pair!(
        "dissociation_rate",
        "rho v_th",
        "k_d: rate at which thermal atoms break a thermal bound pair into three free atoms, per pair, dilute limit (the dissociation stage)",
        "standard error of dissociation_rate (spread of randomizations)"
    )
    .or_null("no well (nothing binds), or the dissociation stage is disabled");
    /// The thermal recombination rate from detailed balance.
    pub const THERMAL_RECOMBINATION: Pair = pair!(
        "thermal_recombination_rate",
        RATE,
        "recombination rate per atom averaged over thermal atoms, from detailed balance with dissociation: 3 K_b k_d (the dissociation stage; the sweep's scenes measure it directly, less precisely)",
        "standard error of thermal_recombination_rate (spread of randomizations)"
    )
    .or_null("no well (nothing binds), or the dissociation stage is disabled");

    /// Where the study table reads them: the potential's dissociation row.
    pub const COLUMNS: [StudyColumn; 2] = [
        StudyColumn {
            column: THERMAL_RECOMBINATION,
            source: TABLE,
            row: None,
            value: super::BALANCED_RECOMBINATION,
        },
        StudyColumn {
            column: DISSOCIATION_RATE,
            source: TABLE,
            row: None,
            value: super::DISSOCIATION_RATE,
        },
    ];
}
