//! The paper's published numbers (Phys. Rev. E 110, 014114 (2024)), as
//! printed: Table I cell by cell and every other number `ternary` computes
//! independently (the Lennard-Jones rate, the detailed-balance ratio, the MD
//! rings' time, the scaling ratios and exponents, the nitrogen example), with
//! the uncertainty the paper gives or half a unit of its last printed digit.
//! `../shared/paper/` holds the same values with where the paper gives them.

use std::borrow::Cow;

use serde::Serialize;

use crate::contract;
use crate::physics::potential::Potential;

/// A number as the paper prints it.
#[derive(Clone, Debug, Serialize)]
pub struct Published {
    /// What it is.
    pub quantity: Cow<'static, str>,
    /// Where the paper gives it.
    pub source: Cow<'static, str>,
    /// Unit.
    pub unit: &'static str,
    /// Value.
    pub value: f64,
    /// Uncertainty: as printed, else half a unit of the last printed digit.
    pub uncertainty: f64,
    /// Whether the paper prints the uncertainty.
    pub printed_uncertainty: bool,
    /// Its cell of Table I, if it is one.
    pub table_i: Option<Cell>,
}

/// A cell of Table I: the exponent `n` and the column.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// The exponent of the inverse power law.
    pub n: u32,
    /// The column.
    pub column: Column,
}

/// The columns of Table I.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Column {
    /// `a_n`, the self variance rate at `X = 0.04`.
    RateConstant,
    /// The shape fit's amplitude `alpha`.
    Alpha,
    /// The shape fit's exponent `beta`.
    Beta,
    /// The shape fit's cut-off `sigma`.
    Sigma,
    /// `|u1f,max|` of the symmetric launch.
    KickMax,
}

impl Column {
    /// The column's name in the `paper` table and the summary.
    pub fn name(self) -> &'static str {
        match self {
            Column::RateConstant => "a_n",
            Column::Alpha => "alpha",
            Column::Beta => "beta",
            Column::Sigma => "sigma",
            Column::KickMax => "|u1f,max|",
        }
    }
}

/// One row of Table I as printed: `(value, uncertainty)` per column, `None`
/// where the cell is blank. Uncertainties: the caption's +-0.001 for the
/// shape, else half a unit of the last printed digit.
pub struct TableIRow {
    /// The exponent `n`.
    pub n: u32,
    /// `a_n` at `X = 0.04`.
    rate_constant: (f64, f64),
    /// `alpha`, `beta`, `sigma` (blank for `n = 2`).
    shape: Option<[f64; 3]>,
    /// `|u1f,max|` of the symmetric launch.
    kick_max: (f64, f64),
}

/// The caption's uncertainty of `alpha`, `beta` and `sigma`.
const SHAPE_UNCERTAINTY: f64 = 0.001;

/// Table I of the paper ("Rate constants a_n and fitting parameters for
/// different potential powers n"), transcribed from the paper's text. `n = 2`
/// prints `a_2 = 0`, `alpha = 0.000`, blank `beta` and `sigma`, and
/// `|u1f,max| = 1e-7`, which the paper says is zero within its integrator's
/// errors (the `n = 2` problem is integrable), so that cell is read as an
/// upper bound: `0 +- 1e-7`.
pub const TABLE_I: [TableIRow; 6] = [
    TableIRow {
        n: 2,
        rate_constant: (0.0, 0.0),
        shape: None,
        kick_max: (0.0, 1e-7),
    },
    TableIRow {
        n: 4,
        rate_constant: (3.49e-4, 0.005e-4),
        shape: Some([0.237, 1.182, 0.022]),
        kick_max: (2.69e-2, 0.005e-2),
    },
    TableIRow {
        n: 6,
        rate_constant: (2.58e-4, 0.005e-4),
        shape: Some([0.182, 1.117, 0.027]),
        kick_max: (3.06e-2, 0.005e-2),
    },
    TableIRow {
        n: 8,
        rate_constant: (1.62e-4, 0.005e-4),
        shape: Some([0.148, 1.076, 0.025]),
        kick_max: (2.76e-2, 0.005e-2),
    },
    TableIRow {
        n: 10,
        rate_constant: (1.02e-4, 0.005e-4),
        shape: Some([0.129, 1.046, 0.021]),
        kick_max: (2.37e-2, 0.005e-2),
    },
    TableIRow {
        n: 12,
        rate_constant: (6.55e-5, 0.005e-5),
        shape: Some([0.115, 1.023, 0.018]),
        kick_max: (2.04e-2, 0.005e-2),
    },
];

impl TableIRow {
    /// The cell of `column`, as a published number (`None`: blank).
    pub fn published(&self, column: Column) -> Option<Published> {
        let n = self.n;
        let (quantity, unit, (value, uncertainty), printed) = match column {
            Column::RateConstant => (
                format!("a_{n}: self variance rate, n = {n}, u' = 0, dilute, |u - u'| <= 0.04"),
                "rho^2 l v_th",
                self.rate_constant,
                false,
            ),
            Column::Alpha | Column::Beta | Column::Sigma => {
                let k = [Column::Alpha, Column::Beta, Column::Sigma]
                    .iter()
                    .position(|c| *c == column)?;
                let unit = [contract::ALPHA_UNIT, "1", "v_th"][k];
                (
                    format!("{}: shape fit, n = {n}", column.name()),
                    unit,
                    (self.shape?[k], SHAPE_UNCERTAINTY),
                    true,
                )
            }
            Column::KickMax => (
                format!("|u1f,max|, n = {n}: largest kick, symmetric launch u2 = 1, u3 = -1"),
                "v_th",
                self.kick_max,
                n == 2,
            ),
        };
        Some(Published {
            quantity: Cow::Owned(quantity),
            source: Cow::Borrowed("Table I"),
            unit,
            value,
            uncertainty,
            printed_uncertainty: printed,
            table_i: Some(Cell { n, column }),
        })
    }
}

/// The Lennard-Jones rate at `kT = 0.1 eps`.
pub const A_LJ: Published = Published {
    quantity: Cow::Borrowed(
        "a: self variance rate, Lennard-Jones theta = kT/eps = 0.1, u' = 0, dilute",
    ),
    source: Cow::Borrowed("Lennard-Jones section (16% above n = 6)"),
    unit: "rho^2 l v_th",
    value: 3.00e-4,
    uncertainty: 0.005e-4,
    printed_uncertainty: false,
    table_i: None,
};

/// The detailed-balance ratio at `u' = -3`.
pub const BALANCE: Published = Published {
    quantity: Cow::Borrowed("G(-3.00 -> -2.96) / G(-2.96 -> -3.00), n = 6"),
    source: Cow::Borrowed("detailed-balance check"),
    unit: "1",
    value: 1.12,
    uncertainty: 0.04,
    printed_uncertainty: true,
    table_i: None,
};

/// The MD rings' final time in units of `1 / Gamma`.
pub const RING_TIME: Published = Published {
    quantity: Cow::Borrowed("Gamma t_f of the MD rings, n = 6"),
    source: Cow::Borrowed("MD section: t_f = 1.6e-4 / Gamma"),
    unit: "1",
    value: 1.6e-4,
    uncertainty: 0.05e-4,
    printed_uncertainty: false,
    table_i: None,
};

/// The nitrogen example's thermalization time.
pub const NITROGEN: Published = Published {
    quantity: Cow::Borrowed("1/Gamma of 1D N2, one molecule per 10 um at 10 K"),
    source: Cow::Borrowed("N2 example: about 10 s to thermalize"),
    unit: "s",
    value: 10.0,
    uncertainty: 5.0,
    printed_uncertainty: false,
    table_i: None,
};

/// `Gamma ~ rho^2 T^(1/2 - 1/n)` checked from the kernels: the ring at
/// `(2 rho, 800 meV)` against the one at `(2 rho, 100 meV)`, `n = 6`.
pub const SCALING_KERNEL: Published = Published {
    quantity: Cow::Borrowed(
        "Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, scaled kernel (dilute)",
    ),
    source: Cow::Borrowed(
        "rho^2 T^(1/2 - 1/n) scaling checked from kernels at two temperatures: 8^(1/2 - 1/6) = 2",
    ),
    unit: "1",
    value: 2.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The same ratio measured by MD, which does not assume the scaling.
pub const SCALING_MD: Published = Published {
    quantity: Cow::Borrowed("Gamma(2 rho, 800 meV) / Gamma(2 rho, 100 meV), n = 6, MD"),
    source: Cow::Borrowed("rho^2 T^(1/2 - 1/n) scaling (MD collapse): 8^(1/2 - 1/6) = 2"),
    unit: "1",
    value: 2.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The density exponent of `Gamma ~ rho^2 T^(1/2 - 1/n)` measured by MD.
pub const DENSITY_EXPONENT: Published = Published {
    quantity: Cow::Borrowed(
        "p in Gamma ~ rho^p T^q, n = 6, MD (thermal estimator): density exponent",
    ),
    source: Cow::Borrowed("rho^2 T^(1/2 - 1/n) scaling: three-body collisions, p = 2"),
    unit: "1",
    value: 2.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The temperature exponent, `1/2 - 1/6` for `n = 6`.
pub const TEMPERATURE_EXPONENT: Published = Published {
    quantity: Cow::Borrowed(
        "q in Gamma ~ rho^p T^q, n = 6, MD (thermal estimator): temperature exponent",
    ),
    source: Cow::Borrowed("rho^2 T^(1/2 - 1/n) scaling: q = 1/2 - 1/6 = 1/3"),
    unit: "1",
    value: 1.0 / 3.0,
    uncertainty: 0.0,
    printed_uncertainty: false,
    table_i: None,
};

/// The temperature ratio of the paper's two rings at `2 rho` (800 / 100 meV).
pub const SCALING_TEMPERATURES: f64 = 8.0;

/// The gas of the nitrogen example in a study (`[[gas]]` name).
pub const NITROGEN_GAS: &str = "N2_10K";

/// The paper's `n = 6` and Lennard-Jones `theta = 0.1` potentials.
pub const IPP_6: Potential = Potential::inverse_power(6.0);
pub const LJ_0_1: Potential = Potential::lennard_jones(0.1);

/// The paper's detailed-balance pair `(a, b)`.
pub const BALANCE_PAIR: (f64, f64) = (-3.0, -2.96);

/// The symmetric launch of Table I's `|u1f,max|`.
pub const SYMMETRIC_LAUNCH: (f64, f64) = (1.0, -1.0);

#[cfg(test)]
mod tests {
    use super::*;

    const COLUMNS: [Column; 5] = [
        Column::RateConstant,
        Column::Alpha,
        Column::Beta,
        Column::Sigma,
        Column::KickMax,
    ];

    #[test]
    fn table_i_has_every_cell_the_paper_prints() {
        // n = 2 prints a_2 and |u1f,max| only; n = 4..12 all five columns.
        let cells: usize = TABLE_I
            .iter()
            .map(|row| COLUMNS.iter().filter_map(|&c| row.published(c)).count())
            .sum();
        assert_eq!(cells, 2 + 5 * 5);
        for row in &TABLE_I {
            for column in COLUMNS {
                if let Some(published) = row.published(column) {
                    assert_eq!(published.table_i, Some(Cell { n: row.n, column }));
                    assert!(published.uncertainty >= 0.0 && published.value >= 0.0);
                    let named = format!("{}", published.quantity);
                    assert!(named.contains(&format!("n = {}", row.n)), "{named}");
                }
            }
        }
    }

    #[test]
    fn the_rate_constants_fall_with_n() {
        // Table I: a_n decreases from n = 4 to 12 (softer potentials kick more).
        let rates: Vec<f64> = TABLE_I[1..].iter().map(|r| r.rate_constant.0).collect();
        assert!(rates.windows(2).all(|w| w[1] < w[0]), "{rates:?}");
    }
}
