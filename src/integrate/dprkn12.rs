//! Dormand, El-Mikkawy & Prince RKN 12(10) step for `y'' = a(y)`, applied to the
//! second-order system directly.
//!
//! Method: J. R. Dormand, M. E. A. El-Mikkawy and P. J. Prince, "High-order embedded
//! Runge-Kutta-Nystrom formulae", IMA J. Numer. Anal. 7 (1987) 423-430: the 17-stage pair of
//! orders 12 and 10 for velocity-independent forces. Coefficients: the exact rationals of
//! `DPRKN12Tableau` in Julia's OrdinaryDiffEq.jl, `lib/OrdinaryDiffEqRKN/src/rkn_tableaus.jl`
//! (commit 63aebf266452d8a06fc490d9ef6e3ef3ea95b4e0), where the error weights are given as
//! differences `b - b_hat`. Generator note: each rational `p // q` (for the error weights, the
//! exact difference) was evaluated with Python's `fractions.Fraction` and written as
//! `repr(float(Fraction(p, q)))`, the correctly rounded shortest round-trip literal; rationals
//! with `|p|, q < 10^7` are written as `p.0 / q.0`, which rounds identically. The same script
//! checked in exact arithmetic that the rows sum to `c_i^2 / 2` (to 1e-53 for rows 14-17,
//! which are published as rational approximations), the quadrature conditions below, and, in
//! 60-digit arithmetic on a Kepler orbit, observed orders 12 and 10.
//!
//! Equations (stage `i = 1 .. 17`, `F_1 = a0`):
//! `Y_i = y + c_i h v + h^2 sum_j a_ij F_j`, `F_i = a(Y_i)`,
//! `y_new = y + h v + h^2 sum_i b_i F_i`, `v_new = v + h sum_i b'_i F_i`.
//! Error vectors are `h^2 sum_i (b_i - b_hat_i) F_i` for positions and
//! `h sum_i (b'_i - b'_hat_i) F_i` for velocities, from the 10th-order embedded pair, measured
//! in the RMS norm over all `2 D` components. The last stage is not at the new point, so a
//! step costs sixteen stage accelerations plus one at `y_new` (returned as [`Step::a`] for the
//! next step's `a0`): seventeen in all.

use super::{
    Acceleration, Integrator, Step, Trial, Vector, rms_norm, scaled_square_sum, weighted_sum,
};

/// Dormand-El-Mikkawy-Prince RKN 12(10) pair for `y'' = a(y)`.
pub struct Dprkn12;

const STAGES: usize = 17;

/// Nodes `c_i`.
const NODES: [f64; STAGES] = [
    0.0,
    1.0 / 50.0,
    1.0 / 25.0,
    1.0 / 10.0,
    2.0 / 15.0,
    4.0 / 25.0,
    1.0 / 20.0,
    1.0 / 5.0,
    1.0 / 4.0,
    1.0 / 3.0,
    1.0 / 2.0,
    5.0 / 9.0,
    3.0 / 4.0,
    6.0 / 7.0,
    8437.0 / 8926.0,
    1.0,
    1.0,
];

/// Nystrom matrix rows `a_i1 .. a_i,i-1` (position coupling, row sums `c_i^2 / 2`).
const COUPLING: [&[f64]; STAGES] = [
    &[],
    // a_2,1
    &[1.0 / 5000.0],
    // a_3,j for j = 1..2
    &[1.0 / 3750.0, 1.0 / 1875.0],
    // a_4,j for j = 1..3
    &[7.0 / 2400.0, -1.0 / 240.0, 1.0 / 160.0],
    // a_5,j for j = 1..4
    &[2.0 / 1215.0, 0.0, 4.0 / 729.0, 32.0 / 18225.0],
    // a_6,j for j = 1..5
    &[
        152.0 / 78125.0,
        0.0,
        1408.0 / 196875.0,
        2048.0 / 703125.0,
        432.0 / 546875.0,
    ],
    // a_7,j for j = 1..6
    &[
        29.0 / 51200.0,
        0.0,
        341.0 / 387072.0,
        -151.0 / 345600.0,
        243.0 / 716800.0,
        -11.0 / 110592.0,
    ],
    // a_8,j for j = 1..7
    &[
        37.0 / 12000.0,
        0.0,
        0.0,
        2.0 / 1125.0,
        27.0 / 10000.0,
        5.0 / 3168.0,
        224.0 / 20625.0,
    ],
    // a_9,j for j = 1..8
    &[
        0.00365183937480113,
        0.0,
        0.003965171714072343,
        0.0031972582629306284,
        0.008221467306855435,
        -0.0013130926959572379,
        0.009771586968064868,
        0.003755769069232834,
    ],
    // a_10,j for j = 1..9
    &[
        0.003707241068718501,
        0.0,
        0.005082045854555286,
        0.001174708002175412,
        -0.021147629915126993,
        0.06010463698107881,
        0.02010573476850619,
        -0.02835075012293358,
        0.014879568918581932,
    ],
    // a_11,j for j = 1..10
    &[
        0.03512537656073344,
        0.0,
        -0.008615749195138479,
        -0.005791448051007917,
        1.945554823782616,
        -3.4351238674565137,
        -0.10930701107475221,
        2.3496383118995166,
        -0.7560094086870229,
        0.10952897222156927,
    ],
    // a_12,j for j = 1..11
    &[
        0.020527792537482496,
        0.0,
        -0.00728644676448018,
        -0.0021153556079618403,
        0.9275807968723522,
        -1.6522824844257367,
        -0.02107956300568657,
        1.2065364326207872,
        -0.4137144770010661,
        0.09079873982809654,
        0.005355552600533985,
    ],
    // a_13,j for j = 1..12
    &[
        -0.14324078875545515,
        0.0,
        0.012528703773091817,
        0.006826019163969827,
        -4.799555395574387,
        5.6986250439519415,
        0.7553430369523645,
        -0.12755487858281084,
        -1.9605926051117384,
        0.9185609056635262,
        -0.23880085505284432,
        0.15911081357234216,
    ],
    // a_14,j for j = 1..13
    &[
        0.8045019205520489,
        0.0,
        -0.016658527067011247,
        -0.021415834042629735,
        16.827235928962466,
        -11.172835357176098,
        -3.377159297226324,
        -15.243326655360846,
        17.179835738215417,
        -5.437719239823995,
        1.3878671618364655,
        -0.5925827732652812,
        0.029603873171297354,
    ],
    // a_15,j for j = 1..14
    &[
        -0.913296766697358,
        0.0,
        0.0024112725757805178,
        0.01765812269386174,
        -14.851649779720384,
        2.1589708670045757,
        3.99791558311788,
        28.434151800232232,
        -25.2593643549416,
        7.733878542362238,
        -1.8913028948478674,
        1.0014845070224718,
        0.004641199599109052,
        0.011218755022148957,
    ],
    // a_16,j for j = 1..15
    &[
        -0.27519629720559396,
        0.0,
        0.03661188877915492,
        0.009789519688231562,
        -12.293062345886211,
        14.207226453937903,
        1.5866476906789537,
        2.4577735327595946,
        -8.935193694403273,
        4.373672731613407,
        -1.8347181765449492,
        1.1592085289061491,
        -0.017290253165383924,
        0.019325977904460768,
        0.005204442937554993,
    ],
    // a_17,j for j = 1..16
    &[
        1.3076391847404059,
        0.0,
        0.017364109189745843,
        -0.018544456454265796,
        14.811522032867726,
        9.38317630848247,
        -5.2284261999445425,
        -48.95128052584765,
        38.297096034337926,
        -10.58738133697598,
        2.4332304376226275,
        -1.0453406042575444,
        0.0717732095086726,
        0.0021622109708082783,
        0.007009595759602514,
        0.0,
    ],
];

/// Position weights `b_i` (12th order).
const POSITION_WEIGHTS: [f64; STAGES] = [
    0.012127868517185414,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.08629746251568875,
    0.2525469581187147,
    -0.1974186799326823,
    0.2031869190789726,
    -0.020775808077714918,
    0.10967804874502014,
    0.038065132526466504,
    0.01163406880432423,
    0.0046580297040248785,
    0.0,
    0.0,
];

/// Velocity weights `b'_i` (12th order).
const VELOCITY_WEIGHTS: [f64; STAGES] = [
    0.012127868517185414,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.09083943422704079,
    0.3156836976483934,
    -0.2632249065769097,
    0.3047803786184589,
    -0.041551616155429835,
    0.2467756096762953,
    0.15226053010586602,
    0.08143848163026961,
    0.08502571193890811,
    -0.009155189630077963,
    1.0 / 40.0,
];

/// Position error weights `b_i - b_hat_i`.
const POSITION_ERROR_WEIGHTS: [f64; STAGES] = [
    -0.004880833389821577,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.014038126584857338,
    -0.11947921920803832,
    0.20440246507662121,
    -0.1322681492223791,
    0.11053069299761689,
    -0.07975385787102851,
    0.011224330486437457,
    -0.004671596801593694,
    0.0008580413473282841,
    0.0,
    0.0,
];

/// Velocity error weights `b'_i - b'_hat_i`.
const VELOCITY_ERROR_WEIGHTS: [f64; STAGES] = [
    -0.004880833389821577,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.014776975352481408,
    -0.1493490240100479,
    0.2725366201021616,
    -0.19840222383356862,
    0.22106138599523378,
    -0.17944618020981415,
    0.04489732194574983,
    -0.03270117761115586,
    0.015662325288859434,
    -0.029155189630077964,
    1.0 / 40.0,
];

impl Integrator for Dprkn12 {
    const NAME: &'static str = "dprkn12";
    const ORDER: u32 = 12;
    const ERROR_ORDER: u32 = 10;
    const EVALUATIONS_PER_STEP: u32 = STAGES as u32;

    fn step<V: Vector, A: Acceleration<V>>(
        acceleration: &A,
        y: &V,
        v: &V,
        a0: &V,
        h: f64,
        position_scale: &V,
        velocity_scale: &V,
    ) -> Step<V> {
        let trial = Trial {
            y,
            v,
            a0,
            h,
            position_scale,
            velocity_scale,
        };
        let [step] = Self::steps(acceleration, [trial]);
        step
    }

    /// The trials' stages advance together, stage `i` of every trial before stage `i + 1` of
    /// any: each stage's force waits on the one before (the step is latency-bound on the
    /// force's division and the stage sums), so independent trials fill each other's waits.
    /// Every trial takes exactly the operations of a step of its own: the same bits.
    #[inline(always)]
    fn steps<V: Vector, A: Acceleration<V>, const L: usize>(
        acceleration: &A,
        trials: [Trial<'_, V>; L],
    ) -> [Step<V>; L] {
        let mut forces: [[V; STAGES]; L] = trials[0].a0.stage_table();
        for (lane_forces, trial) in forces.iter_mut().zip(&trials) {
            lane_forces[0].clone_from(trial.a0);
        }
        fill_stage_accelerations(acceleration, &trials, &mut forces);
        let ends: [(V, V); L] = std::array::from_fn(|lane| end_state(&trials[lane], &forces[lane]));
        std::array::from_fn(|lane| {
            let (trial, (y, v)) = (&trials[lane], &ends[lane]);
            let position_error =
                weighted_sum(trial.h * trial.h, &POSITION_ERROR_WEIGHTS, &forces[lane]);
            let velocity_error = weighted_sum(trial.h, &VELOCITY_ERROR_WEIGHTS, &forces[lane]);
            Step {
                a: acceleration.acceleration(y),
                error: rms_norm(
                    y.components().len(),
                    scaled_square_sum(&position_error, trial.position_scale),
                    scaled_square_sum(&velocity_error, trial.velocity_scale),
                ),
                y: y.clone(),
                v: v.clone(),
            }
        })
    }
}

/// Positions and velocities at the end of `trial`, from its stage accelerations `forces`.
#[inline(always)]
fn end_state<V: Vector>(trial: &Trial<'_, V>, forces: &[V; STAGES]) -> (V, V) {
    let h = trial.h;
    let position_increment = weighted_sum(h, &POSITION_WEIGHTS, forces);
    let velocity_increment = weighted_sum(h, &VELOCITY_WEIGHTS, forces);
    let mut new_y = trial.y.clone();
    let mut new_v = trial.v.clone();
    let positions = new_y.components_mut().iter_mut();
    let increments = trial
        .v
        .components()
        .iter()
        .zip(position_increment.components());
    for (y, (vk, increment)) in positions.zip(increments) {
        *y += h * (vk + increment);
    }
    let velocities = new_v.components_mut().iter_mut();
    for (v, increment) in velocities.zip(velocity_increment.components()) {
        *v += increment;
    }
    (new_y, new_v)
}

/// Stage accelerations `F_i = a(y + c_i h v + h^2 sum_j a_ij F_j)` of every trial into
/// `forces[lane][i]`, `i >= 1`, from `F_1 = forces[lane][0] = a0`, stage by stage across the
/// trials.
#[inline(always)]
fn fill_stage_accelerations<V: Vector, A: Acceleration<V>, const L: usize>(
    acceleration: &A,
    trials: &[Trial<'_, V>; L],
    forces: &mut [[V; STAGES]; L],
) {
    for (i, (row, c)) in COUPLING.iter().zip(&NODES).enumerate().skip(1) {
        let positions: [V; L] =
            std::array::from_fn(|lane| stage_position(&trials[lane], row, *c, &forces[lane]));
        for (lane_forces, position) in forces.iter_mut().zip(&positions) {
            lane_forces[i] = acceleration.acceleration(position);
        }
    }
}

/// The position `y + c_i h v + h^2 sum_j a_ij F_j` of a stage with coupling `row` and node `c`.
#[inline(always)]
fn stage_position<V: Vector>(trial: &Trial<'_, V>, row: &[f64], c: f64, forces: &[V; STAGES]) -> V {
    let (y, v, h) = (trial.y, trial.v, trial.h);
    let mut position = y.clone();
    let mut coupling_sum = y.zeros_like();
    let sums = coupling_sum.components_mut();
    for (&a_ij, force) in row.iter().zip(forces) {
        for (s, f) in sums.iter_mut().zip(force.components()) {
            *s += a_ij * f;
        }
    }
    let position_components = position.components_mut().iter_mut();
    for ((p, vk), sum) in position_components.zip(v.components()).zip(sums.iter()) {
        *p += h * (c * vk + h * sum);
    }
    position
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{
        assert_close, assert_error_estimate_exponent, assert_evaluations_and_returned_acceleration,
        assert_observed_order, assert_uniform_field_is_exact, moment,
    };
    use super::*;

    /// A few units in the last place of the O(10) coefficients that get summed.
    const TABLEAU_TOLERANCE: f64 = 1e-13;

    #[test]
    fn row_sums_equal_half_squared_nodes() {
        for (row, c) in COUPLING.iter().zip(NODES) {
            assert_close("row sum", row.iter().sum(), 0.5 * c * c, TABLEAU_TOLERANCE);
        }
    }

    #[test]
    fn weights_satisfy_quadrature_conditions() {
        for k in 0..12 {
            let velocity_moment = moment(&VELOCITY_WEIGHTS, &NODES, k);
            assert_close(
                "b'.c^k",
                velocity_moment,
                1.0 / f64::from(k + 1),
                TABLEAU_TOLERANCE,
            );
        }
        for k in 0..11 {
            let want = 1.0 / f64::from((k + 1) * (k + 2));
            let position_moment = moment(&POSITION_WEIGHTS, &NODES, k);
            assert_close("b.c^k", position_moment, want, TABLEAU_TOLERANCE);
        }
    }

    #[test]
    fn position_weights_equal_velocity_weights_times_one_minus_nodes() {
        // The RKN simplifying assumption b_i = b'_i (1 - c_i), exact in rationals; the weights
        // are below 0.4, so rounding each side costs at most ~5e-17.
        for ((b, b_velocity), c) in POSITION_WEIGHTS.iter().zip(VELOCITY_WEIGHTS).zip(NODES) {
            assert_close("b - b'(1 - c)", *b, b_velocity * (1.0 - c), 1e-16);
        }
    }

    #[test]
    fn error_weights_vanish_on_tenth_order_quadrature() {
        for k in 0..10 {
            let velocity_moment = moment(&VELOCITY_ERROR_WEIGHTS, &NODES, k);
            assert_close("(b' - b'_hat).c^k", velocity_moment, 0.0, TABLEAU_TOLERANCE);
        }
        for k in 0..9 {
            let position_moment = moment(&POSITION_ERROR_WEIGHTS, &NODES, k);
            assert_close("(b - b_hat).c^k", position_moment, 0.0, TABLEAU_TOLERANCE);
        }
    }

    #[test]
    fn converges_with_order_twelve() {
        // 11.81 measured; 5 .. 9 steps give 11.46 .. 11.81 and 10 reach roundoff (in 60-digit
        // arithmetic the e = 0.5 orbit gives 12.07 from 40 to 80 steps, far below f64 roundoff).
        assert_observed_order::<Dprkn12>(7, 0.5);
    }

    #[test]
    fn error_estimate_scales_as_h_to_the_eleventh() {
        // 11.12 measured; at h = 0.2 the half step is at roundoff.
        assert_error_estimate_exponent::<Dprkn12>(0.4);
    }

    #[test]
    fn counts_evaluations_and_returns_acceleration_at_new_point() {
        assert_evaluations_and_returned_acceleration::<Dprkn12>();
    }

    #[test]
    fn integrates_uniform_field_exactly() {
        assert_uniform_field_is_exact::<Dprkn12>();
    }
}
