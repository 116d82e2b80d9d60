//! Hairer's DOP853 step for `y'' = a(y)` written as the first-order system
//! `z = (y, v)`, `z' = (v, a(y))`.
//!
//! Method: the 8th-order explicit Runge-Kutta formula of P. J. Prince and J. R. Dormand
//! ("High order embedded Runge-Kutta formulae", J. Comput. Appl. Math. 7 (1981) 67-75) with
//! the 5th-order error estimator and 3rd-order correction that Hairer and Wanner gave it in
//! DOP853, described in Hairer, Norsett & Wanner, *Solving Ordinary Differential Equations I*
//! (2nd ed., Springer 1993).
//! Coefficients: the 30-digit decimals of Hairer's `dop853.f` (version of April 25, 1996, with
//! corrections of March 4, 2002; subroutine `DP86CO`), the same digits as SciPy's
//! `scipy/integrate/_ivp/dop853_coefficients.py`, each converted to the nearest `f64` and
//! written as its shortest round-trip literal. `ERROR3_WEIGHTS` is `b - bhh` evaluated in
//! exact decimal arithmetic before rounding.
//!
//! Stage slopes `k_i = (V_i, A_i)` with `Y_i = y + h sum_j a_ij V_j`,
//! `V_i = v + h sum_j a_ij A_j`, `A_i = a(Y_i)`. Twelve stages give the 8th-order solution;
//! a thirteenth row `a_13,j = b_j` evaluates the field at the new point ("first same as last"),
//! so `k_1 = (v, a0)` is free and a step costs twelve accelerations, the last returned as
//! [`Step::a`]. Error estimate (Hairer's `dop853.f`, after label 35): with
//! `err5 = h sum_i e5_i k_i` (5th-order embedded) and `err3 = h sum_i e3_i k_i` (3rd-order),
//! and `S5`, `S3` their scaled square sums over the `N = 2 D` components,
//! `error = S5 / sqrt(N (S5 + 0.01 S3))`, i.e. `rms(err5) * sqrt(S5 / (S5 + 0.01 S3))`,
//! which behaves as `h^8` once the 3rd-order term dominates the denominator.

use super::{
    Acceleration, FirstOrderStages, Integrator, Step, Vector, first_order_stages,
    scaled_square_sum, weighted_sum,
};

/// Hairer's DOP853 8(5,3) pair on the first-order form of `y'' = a(y)`, FSAL.
pub struct Dop853;

const STAGES: usize = 13;

/// Runge-Kutta matrix rows `a_i1 .. a_i,i-1` (Hairer's `A21 .. A1211`, `B1 .. B12`).
const COUPLING: [&[f64]; STAGES] = [
    &[],
    // a_2,1
    &[0.05260015195876773],
    // a_3,j for j = 1..2
    &[0.0197250569845379, 0.0591751709536137],
    // a_4,j for j = 1..3
    &[0.02958758547680685, 0.0, 0.08876275643042054],
    // a_5,j for j = 1..4
    &[
        0.2413651341592667,
        0.0,
        -0.8845494793282861,
        0.924834003261792,
    ],
    // a_6,j for j = 1..5
    &[
        0.037037037037037035,
        0.0,
        0.0,
        0.17082860872947386,
        0.12546768756682242,
    ],
    // a_7,j for j = 1..6
    &[
        0.037109375,
        0.0,
        0.0,
        0.17025221101954405,
        0.06021653898045596,
        -0.017578125,
    ],
    // a_8,j for j = 1..7
    &[
        0.03709200011850479,
        0.0,
        0.0,
        0.17038392571223998,
        0.10726203044637328,
        -0.015319437748624402,
        0.008273789163814023,
    ],
    // a_9,j for j = 1..8
    &[
        0.6241109587160757,
        0.0,
        0.0,
        -3.3608926294469414,
        -0.868219346841726,
        27.59209969944671,
        20.154067550477894,
        -43.48988418106996,
    ],
    // a_10,j for j = 1..9
    &[
        0.47766253643826434,
        0.0,
        0.0,
        -2.4881146199716677,
        -0.590290826836843,
        21.230051448181193,
        15.279233632882423,
        -33.28821096898486,
        -0.020331201708508627,
    ],
    // a_11,j for j = 1..10
    &[
        -0.9371424300859873,
        0.0,
        0.0,
        5.186372428844064,
        1.0914373489967295,
        -8.149787010746927,
        -18.52006565999696,
        22.739487099350505,
        2.4936055526796523,
        -3.0467644718982196,
    ],
    // a_12,j for j = 1..11
    &[
        2.273310147516538,
        0.0,
        0.0,
        -10.53449546673725,
        -2.0008720582248625,
        -17.9589318631188,
        27.94888452941996,
        -2.8589982771350235,
        -8.87285693353063,
        12.360567175794303,
        0.6433927460157636,
    ],
    // a_13,j = b_j for j = 1..12: the 8th-order weights (FSAL stage at the new point)
    &[
        0.054293734116568765,
        0.0,
        0.0,
        0.0,
        0.0,
        4.450312892752409,
        1.8915178993145003,
        -5.801203960010585,
        0.3111643669578199,
        -0.1521609496625161,
        0.20136540080403034,
        0.04471061572777259,
    ],
];

/// Weights `e5_i = b_i - b5_i` of the 5th-order error estimate (Hairer's `ER1 .. ER12`).
const ERROR5_WEIGHTS: [f64; STAGES] = [
    0.01312004499419488,
    0.0,
    0.0,
    0.0,
    0.0,
    -1.2251564463762044,
    -0.4957589496572502,
    1.6643771824549864,
    -0.35032884874997366,
    0.3341791187130175,
    0.08192320648511571,
    -0.022355307863886294,
    0.0,
];

/// Weights `e3_i = b_i - bhh_i` of the 3rd-order error estimate (Hairer's `BHH1 .. BHH3`).
const ERROR3_WEIGHTS: [f64; STAGES] = [
    -0.18980075407240762,
    0.0,
    0.0,
    0.0,
    0.0,
    4.450312892752409,
    1.8915178993145003,
    -5.801203960010585,
    -0.42268232132379197,
    -0.1521609496625161,
    0.20136540080403034,
    0.022651792198360825,
    0.0,
];

/// Weight of the 3rd-order error in the denominator of the combined estimate (Hairer's `0.01`).
const ERROR3_SHARE: f64 = 0.01;

impl Integrator for Dop853 {
    const NAME: &'static str = "dop853";
    const ORDER: u32 = 8;
    const ERROR_ORDER: u32 = 7;
    const EVALUATIONS_PER_STEP: u32 = STAGES as u32 - 1;

    fn step<V: Vector, A: Acceleration<V>>(
        acceleration: &A,
        y: &V,
        v: &V,
        a0: &V,
        h: f64,
        position_scale: &V,
        velocity_scale: &V,
    ) -> Step<V> {
        let FirstOrderStages {
            velocity,
            acceleration: stage_acceleration,
            last_position,
        } = first_order_stages(acceleration, y, v, a0, h, &COUPLING);
        let scaled_squares = |weights: &[f64; STAGES]| {
            scaled_square_sum(&weighted_sum(h, weights, &velocity), position_scale)
                + scaled_square_sum(
                    &weighted_sum(h, weights, &stage_acceleration),
                    velocity_scale,
                )
        };
        Step {
            y: last_position,
            v: velocity[STAGES - 1].clone(),
            a: stage_acceleration[STAGES - 1].clone(),
            error: combined_error(
                y.components().len(),
                scaled_squares(&ERROR5_WEIGHTS),
                scaled_squares(&ERROR3_WEIGHTS),
            ),
        }
    }
}

/// Hairer's combined estimate `S5 / sqrt(2 D (S5 + 0.01 S3))` from the scaled square sums of
/// the 5th- and 3rd-order error vectors (zero when both vanish).
fn combined_error(len: usize, error5_squares: f64, error3_squares: f64) -> f64 {
    let denominator = error5_squares + ERROR3_SHARE * error3_squares;
    if denominator > 0.0 {
        error5_squares / ((2 * len) as f64 * denominator).sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{
        assert_close, assert_error_estimate_exponent, assert_evaluations_and_returned_acceleration,
        assert_observed_order, assert_uniform_field_is_exact, moment,
    };
    use super::*;

    /// Published nodes `c_i` (Hairer's `C2 .. C11`; `c_12 = c_13 = 1`).
    const NODES: [f64; STAGES] = [
        0.0,
        0.05260015195876773,
        0.0789002279381516,
        0.1183503419072274,
        0.2816496580927726,
        0.3333333333333333,
        0.25,
        0.3076923076923077,
        0.6512820512820513,
        0.6,
        0.8571428571428571,
        1.0,
        1.0,
    ];

    /// A few units in the last place of the O(10) coefficients that get summed.
    const TABLEAU_TOLERANCE: f64 = 1e-13;

    #[test]
    fn row_sums_equal_nodes() {
        for (row, c) in COUPLING.iter().zip(NODES) {
            assert_close("row sum", row.iter().sum(), c, TABLEAU_TOLERANCE);
        }
    }

    #[test]
    fn weights_satisfy_eighth_order_quadrature_and_error_weights_lower_orders() {
        let weights = COUPLING[STAGES - 1];
        for k in 0..8 {
            let want = 1.0 / f64::from(k + 1);
            assert_close("b.c^k", moment(weights, &NODES, k), want, TABLEAU_TOLERANCE);
        }
        for k in 0..5 {
            assert_close(
                "e5.c^k",
                moment(&ERROR5_WEIGHTS, &NODES, k),
                0.0,
                TABLEAU_TOLERANCE,
            );
        }
        for k in 0..3 {
            assert_close(
                "e3.c^k",
                moment(&ERROR3_WEIGHTS, &NODES, k),
                0.0,
                TABLEAU_TOLERANCE,
            );
        }
    }

    #[test]
    fn converges_with_order_eight() {
        // 7.86 measured; 24 .. 48 steps give 7.80 .. 7.93, 64 reach roundoff.
        assert_observed_order::<Dop853>(32, 0.3);
    }

    #[test]
    fn error_estimate_scales_as_h_to_the_eighth() {
        // 8.003 measured.
        assert_error_estimate_exponent::<Dop853>(0.1);
    }

    #[test]
    fn counts_evaluations_and_returns_acceleration_at_new_point() {
        assert_evaluations_and_returned_acceleration::<Dop853>();
    }

    #[test]
    fn integrates_uniform_field_exactly() {
        assert_uniform_field_is_exact::<Dop853>();
    }
}
