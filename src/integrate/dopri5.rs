//! Dormand-Prince 5(4) step for `y'' = a(y)` written as the first-order system
//! `z = (y, v)`, `z' = (v, a(y))`.
//!
//! Method: J. R. Dormand and P. J. Prince, "A family of embedded Runge-Kutta formulae",
//! J. Comput. Appl. Math. 6 (1980) 19-26; tableau as in Hairer, Norsett & Wanner, *Solving
//! Ordinary Differential Equations I* (2nd ed., 1993), Section II.5, and in Hairer's `dopri5.f`
//! (version of April 25, 1996, subroutine `CDOPRI`), from which the rationals below are copied.
//!
//! Stage slopes `k_i = (V_i, A_i)` with `Y_i = y + h sum_j a_ij V_j`,
//! `V_i = v + h sum_j a_ij A_j`, `A_i = a(Y_i)`. The seventh stage is evaluated at the new point
//! (`a_7j = b_j`, "first same as last"), so `k_1 = (v, a0)` is free and a step costs six
//! accelerations, the last of which is returned as [`Step::a`]. The propagated solution is the
//! 5th-order one (local extrapolation); the error vector is `h sum_i e_i k_i` with
//! `e = b - b_hat` (4th-order `b_hat`), measured in the RMS norm of Hairer's code.

use super::{
    Acceleration, FirstOrderStages, Integrator, Step, Vector, first_order_stages, rms_norm,
    scaled_square_sum, weighted_sum,
};

/// Dormand-Prince 5(4) pair on the first-order form of `y'' = a(y)`, FSAL.
pub struct Dopri5;

const STAGES: usize = 7;

/// Runge-Kutta matrix rows `a_i1 .. a_i,i-1`; the last row is the 5th-order weights `b`.
const COUPLING: [&[f64]; STAGES] = [
    &[],
    &[1.0 / 5.0],
    &[3.0 / 40.0, 9.0 / 40.0],
    &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
    &[
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
    ],
    &[
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
    ],
    &[
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];

/// Error weights `e_i = b_i - b_hat_i` (Hairer's `E1 .. E7`).
const ERROR_WEIGHTS: [f64; STAGES] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

impl Integrator for Dopri5 {
    const NAME: &'static str = "dopri5";
    const ORDER: u32 = 5;
    const ERROR_ORDER: u32 = 4;
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
        let position_error = weighted_sum(h, &ERROR_WEIGHTS, &velocity);
        let velocity_error = weighted_sum(h, &ERROR_WEIGHTS, &stage_acceleration);
        Step {
            y: last_position,
            v: velocity[STAGES - 1].clone(),
            a: stage_acceleration[STAGES - 1].clone(),
            error: rms_norm(
                y.components().len(),
                scaled_square_sum(&position_error, position_scale),
                scaled_square_sum(&velocity_error, velocity_scale),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{
        assert_close, assert_error_estimate_exponent, assert_evaluations_and_returned_acceleration,
        assert_observed_order, assert_uniform_field_is_exact, moment,
    };
    use super::*;

    /// Published nodes `c_i`.
    const NODES: [f64; STAGES] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];

    /// A few units in the last place of the O(10) coefficients that get summed.
    const TABLEAU_TOLERANCE: f64 = 1e-14;

    #[test]
    fn row_sums_equal_nodes() {
        for (row, c) in COUPLING.iter().zip(NODES) {
            assert_close("row sum", row.iter().sum(), c, TABLEAU_TOLERANCE);
        }
    }

    #[test]
    fn weights_satisfy_fifth_order_quadrature_and_error_weights_fourth() {
        let weights = COUPLING[STAGES - 1];
        for k in 0..5 {
            let want = 1.0 / f64::from(k + 1);
            assert_close("b.c^k", moment(weights, &NODES, k), want, TABLEAU_TOLERANCE);
        }
        for k in 0..4 {
            assert_close(
                "e.c^k",
                moment(&ERROR_WEIGHTS, &NODES, k),
                0.0,
                TABLEAU_TOLERANCE,
            );
        }
    }

    #[test]
    fn converges_with_order_five() {
        // 4.97 measured; 200 .. 300 steps give 4.93 .. 4.97, fewer are pre-asymptotic.
        assert_observed_order::<Dopri5>(300, 0.2);
    }

    #[test]
    fn error_estimate_scales_as_h_to_the_fifth() {
        // 5.001 measured.
        assert_error_estimate_exponent::<Dopri5>(0.05);
    }

    #[test]
    fn counts_evaluations_and_returns_acceleration_at_new_point() {
        assert_evaluations_and_returned_acceleration::<Dopri5>();
    }

    #[test]
    fn integrates_uniform_field_exactly() {
        assert_uniform_field_is_exact::<Dopri5>();
    }
}
