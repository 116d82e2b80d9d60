//! Adaptive integration of small autonomous second-order systems `y'' = a(y)`: single-step
//! kernels and the one driver that strings their steps together.
//!
//! Each kernel takes one attempted step of size `h` from `(y, v = y')` with an embedded
//! explicit Runge-Kutta(-Nystrom) pair and returns the propagated solution together with the
//! pair's error estimate, already reduced to one RMS number in units of the caller's scales.
//! The state is any [`Vector`]: fixed-size arrays on the stack for three-body scenes (no
//! allocation, fully unrolled), [`StackVector`] for systems sized at run time up to a bound
//! (a ring's clusters: no allocation, one compiled integrator for every size), `Vec<f64>`
//! beyond it (the whole ring).
//!
//! The driver ([`drive`], `driver.rs`) integrates systems of gaps (ordered particles: the
//! three-body scene, the ring and its clusters) over a duration or until the caller stops it;
//! [`drive_lanes`] drives several independent ones at once, their steps taken together
//! ([`Integrator::steps`]: a step alone is a latency-bound chain of stages), each to the same
//! bits as alone.
//!
//! Owned here: the tableaus (published coefficients as `const` tables, one method per file),
//! the arithmetic of one step, and in the driver the attempt loop, the step budget, the
//! step-size controller (accept/reject, growth bounds, rejection of NaN estimates and of
//! steps that carry neighbours past each other), the local time scale and approach limit
//! that size a step, and the stop exactly at the end time. Not owned here: the choice of
//! error scales ([`ErrorScales`]) and what happens between steps (a scene's free-flight
//! jumps and start/stop conditions, a ring's collision bookkeeping), given to the driver by
//! the caller; dense output. All quantities are dimensionless (the caller's scaled units).
//!
//! | kernel | method | order | error ~ `h^(q+1)` | accelerations per step |
//! | --- | --- | --- | --- | --- |
//! | [`Dopri5`] | Dormand-Prince 5(4), first-order form, FSAL | 5 | `q = 4` | 6 |
//! | [`Dop853`] | Hairer's DOP853 8(5,3), first-order form, FSAL | 8 | `q = 7` | 12 |
//! | [`Dprkn12`] | Dormand-El-Mikkawy-Prince RKN 12(10) | 12 | `q = 10` | 17 |

mod dop853;
mod dopri5;
mod dprkn12;
mod driver;

pub use dop853::Dop853;
pub use dopri5::Dopri5;
pub use dprkn12::Dprkn12;
pub use driver::{
    AfterStep, Drive, Ending, ErrorScales, Span, Trajectory, Work, drive, drive_lanes,
};

/// A state vector of `len` components: `[f64; D]`, [`StackVector`] or `Vec<f64>`.
pub trait Vector: Clone {
    /// A vector of zeros of the same length.
    fn zeros_like(&self) -> Self;
    /// `L` rows of `S` slots for vectors of this length, each replaced whole before a
    /// nonzero weight reads it (the stage accelerations of `Dprkn12::steps`).
    fn stage_table<const S: usize, const L: usize>(&self) -> [[Self; S]; L];
    /// The components.
    fn components(&self) -> &[f64];
    /// The components, mutable.
    fn components_mut(&mut self) -> &mut [f64];
}

impl<const D: usize> Vector for [f64; D] {
    #[inline(always)]
    fn zeros_like(&self) -> Self {
        [0.0; D]
    }

    /// Zeroed in place: `array::from_fn` built the table of stage accelerations of
    /// `Dprkn12::steps` elsewhere and copied it (`memcpy`) three times: 7.3% of the collisions
    /// stage's time in `perf` before this (docs/benchmarks.md).
    #[inline(always)]
    fn stage_table<const S: usize, const L: usize>(&self) -> [[Self; S]; L] {
        [[[0.0; D]; S]; L]
    }

    #[inline(always)]
    fn components(&self) -> &[f64] {
        self
    }

    #[inline(always)]
    fn components_mut(&mut self) -> &mut [f64] {
        self
    }
}

impl Vector for Vec<f64> {
    fn zeros_like(&self) -> Self {
        vec![0.0; self.len()]
    }

    /// Empty slots, no allocation: a stage's position reads the slots not yet filled with
    /// zero couplings only, over no components (as zeros would add nothing); zeroed slots
    /// were 17 allocations a step, thrown away.
    fn stage_table<const S: usize, const L: usize>(&self) -> [[Self; S]; L] {
        std::array::from_fn(|_| std::array::from_fn(|_| Vec::new()))
    }

    fn components(&self) -> &[f64] {
        self
    }

    fn components_mut(&mut self) -> &mut [f64] {
        self
    }
}

/// Up to `C` components, their number set at run time, on the stack: the state of a ring's
/// clusters of a few to a dozen particles. `Vec<f64>` allocated every stage position and
/// acceleration (about 50 allocations a step), and an array per size compiled the
/// integrator once per size (docs/benchmarks.md).
#[derive(Clone, Copy, Debug)]
pub struct StackVector<const C: usize> {
    len: usize,
    values: [f64; C],
}

impl<const C: usize> StackVector<C> {
    /// The components `values`, or `None` when there are more than `C`.
    pub fn from_slice(values: &[f64]) -> Option<Self> {
        let mut vector = StackVector {
            len: values.len(),
            values: [0.0; C],
        };
        vector
            .values
            .get_mut(..values.len())?
            .copy_from_slice(values);
        Some(vector)
    }
}

impl<const C: usize> Vector for StackVector<C> {
    fn zeros_like(&self) -> Self {
        StackVector {
            len: self.len,
            values: [0.0; C],
        }
    }

    fn stage_table<const S: usize, const L: usize>(&self) -> [[Self; S]; L] {
        [[self.zeros_like(); S]; L]
    }

    fn components(&self) -> &[f64] {
        &self.values[..self.len]
    }

    fn components_mut(&mut self) -> &mut [f64] {
        &mut self.values[..self.len]
    }
}

/// Acceleration field of an autonomous second-order system y'' = a(y).
pub trait Acceleration<V: Vector> {
    fn acceleration(&self, y: &V) -> V;
}

/// Result of one attempted step of size h.
#[derive(Clone, Copy, Debug)]
pub struct Step<V> {
    /// Positions at `t + h` (the higher-order solution, which is the one propagated).
    pub y: V,
    /// Velocities `y'` at `t + h`.
    pub v: V,
    /// `a(y)` at the new positions; pass it back as `a0` of the next step.
    pub a: V,
    /// The method's embedded error estimate as an RMS norm over all `2 D` components, each
    /// divided by its scale: `error <= 1` means "within tolerance".
    pub error: f64,
}

/// An embedded explicit Runge-Kutta(-Nystrom) pair.
pub trait Integrator {
    /// Short name: `"dopri5"`, `"dop853"` or `"dprkn12"`.
    const NAME: &'static str;
    /// Order of the propagated solution.
    const ORDER: u32;
    /// `q` such that `error` scales as `h^(q+1)` (controller exponent `1 / (q + 1)`).
    const ERROR_ORDER: u32;
    /// Acceleration calls per step, including the one producing [`Step::a`].
    const EVALUATIONS_PER_STEP: u32;

    /// One step of size `h` from positions `y`, velocities `v` and `a0 = a(y)`.
    ///
    /// The scales are absolute and must be positive (typically tolerance times a
    /// characteristic size per component).
    fn step<V: Vector, A: Acceleration<V>>(
        acceleration: &A,
        y: &V,
        v: &V,
        a0: &V,
        h: f64,
        position_scale: &V,
        velocity_scale: &V,
    ) -> Step<V>;

    /// `L` independent steps in one call, one per trial, each the same to the last bit as
    /// [`Integrator::step`] of that trial. One after the other unless the method interleaves
    /// them.
    #[inline(always)]
    fn steps<V: Vector, A: Acceleration<V>, const L: usize>(
        acceleration: &A,
        trials: [Trial<'_, V>; L],
    ) -> [Step<V>; L] {
        trials.map(|trial| {
            Self::step(
                acceleration,
                trial.y,
                trial.v,
                trial.a0,
                trial.h,
                trial.position_scale,
                trial.velocity_scale,
            )
        })
    }
}

/// The arguments of one attempted step ([`Integrator::step`]).
#[derive(Clone, Copy, Debug)]
pub struct Trial<'a, V> {
    /// Positions at the start.
    pub y: &'a V,
    /// Velocities at the start.
    pub v: &'a V,
    /// `a(y)`.
    pub a0: &'a V,
    /// Step size.
    pub h: f64,
    /// Allowed error of each position.
    pub position_scale: &'a V,
    /// Allowed error of each velocity.
    pub velocity_scale: &'a V,
}

/// Stages of an explicit Runge-Kutta method applied to the first-order system
/// `z = (y, v)`, `z' = (v, a(y))`: stage `i` has slope `k_i = (V_i, A_i)`.
struct FirstOrderStages<V, const S: usize> {
    /// Stage velocities `V_i`, the position part of `k_i`.
    velocity: [V; S],
    /// Stage accelerations `A_i = a(Y_i)`, the velocity part of `k_i`.
    acceleration: [V; S],
    /// Position `Y_S` of the last stage.
    last_position: V,
}

/// Evaluates the stages `Y_i = y + h sum_j a_ij V_j`, `V_i = v + h sum_j a_ij A_j`,
/// `A_i = a(Y_i)` for `i >= 2`, with `coupling[i]` holding `a_i1 .. a_i,i-1`.
///
/// The first stage is `(V_1, A_1) = (v, a0)`, so it costs no evaluation; `S - 1` calls in all.
#[inline(always)]
fn first_order_stages<V: Vector, A: Acceleration<V>, const S: usize>(
    acceleration: &A,
    y: &V,
    v: &V,
    a0: &V,
    h: f64,
    coupling: &[&[f64]; S],
) -> FirstOrderStages<V, S> {
    let mut stages = FirstOrderStages {
        velocity: std::array::from_fn(|_| v.clone()),
        acceleration: std::array::from_fn(|_| a0.clone()),
        last_position: y.clone(),
    };
    let len = y.components().len();
    for (i, row) in coupling.iter().enumerate().skip(1) {
        let mut velocity_sum = y.zeros_like();
        let mut acceleration_sum = y.zeros_like();
        for (j, &a_ij) in row.iter().enumerate() {
            let (vs, acs) = (
                velocity_sum.components_mut(),
                stages.velocity[j].components(),
            );
            for k in 0..len {
                vs[k] += a_ij * acs[k];
            }
            let (sums, stage) = (
                acceleration_sum.components_mut(),
                stages.acceleration[j].components(),
            );
            for k in 0..len {
                sums[k] += a_ij * stage[k];
            }
        }
        // Increments are summed first and added to the state once, so the propagated
        // solution takes one rounding at the size of `y` and `v` per step, not one per stage.
        let mut position = y.clone();
        let mut velocity = v.clone();
        {
            let (p, vel) = (position.components_mut(), velocity.components_mut());
            let (vs, acs) = (velocity_sum.components(), acceleration_sum.components());
            for k in 0..len {
                p[k] += h * vs[k];
                vel[k] += h * acs[k];
            }
        }
        stages.acceleration[i] = acceleration.acceleration(&position);
        stages.velocity[i] = velocity;
        stages.last_position = position;
    }
    stages
}

/// `factor * sum_i weights_i slopes_i`: an increment or an error vector built from stage slopes.
#[inline(always)]
fn weighted_sum<V: Vector, const S: usize>(factor: f64, weights: &[f64; S], slopes: &[V; S]) -> V {
    let mut sum = slopes[0].zeros_like();
    {
        let out = sum.components_mut();
        for (&weight, slope) in weights.iter().zip(slopes) {
            for (o, s) in out.iter_mut().zip(slope.components()) {
                *o += weight * s;
            }
        }
        out.iter_mut().for_each(|component| *component *= factor);
    }
    sum
}

/// `sum_k (error_k / scale_k)^2`.
#[inline(always)]
fn scaled_square_sum<V: Vector>(error: &V, scale: &V) -> f64 {
    error
        .components()
        .iter()
        .zip(scale.components())
        .map(|(e, s)| (e / s) * (e / s))
        .sum()
}

/// RMS over the `2 len` position and velocity components given their scaled square sums.
#[inline(always)]
fn rms_norm(len: usize, position_squares: f64, velocity_squares: f64) -> f64 {
    ((position_squares + velocity_squares) / (2 * len) as f64).sqrt()
}

/// Problems, tableau checks and convergence measurements shared by the kernels' unit tests.
#[cfg(test)]
mod test_support {
    use super::{Acceleration, Integrator};
    use std::cell::Cell;
    use std::f64::consts::TAU;

    /// Eccentricity of the test orbit. Fixed-step error ratios of these high-order pairs only
    /// show their asymptotic order where the leading error term dominates the next ones and
    /// roundoff (1e-15 .. 1e-14 after a period) does not yet; for 12th order that window
    /// spans little more than one halving of `h`. At 0.1 (non-circular, so no symmetry hides
    /// error terms) every pair has such a window; at 0.5 the pericentre passage keeps DOP853
    /// and DPRKN12 pre-asymptotic down to roundoff.
    pub const ECCENTRICITY: f64 = 0.1;

    /// Kepler problem `y'' = -y / |y|^3` in the plane (`GM = 1`, semi-major axis 1, period `2 pi`).
    pub struct Kepler;

    impl Acceleration<[f64; 2]> for Kepler {
        fn acceleration(&self, y: &[f64; 2]) -> [f64; 2] {
            let r2 = y[0] * y[0] + y[1] * y[1];
            let inverse_r3 = 1.0 / (r2 * r2.sqrt());
            [-y[0] * inverse_r3, -y[1] * inverse_r3]
        }
    }

    /// Pericentre state of the orbit with semi-major axis 1 and [`ECCENTRICITY`].
    pub fn pericentre() -> ([f64; 2], [f64; 2]) {
        let e = ECCENTRICITY;
        ([1.0 - e, 0.0], [0.0, ((1.0 + e) / (1.0 - e)).sqrt()])
    }

    /// Largest deviation of `(y, v)` from the start after one period in `steps` fixed steps
    /// (the exact solution returns to its start).
    pub fn period_error<I: Integrator>(steps: u32) -> f64 {
        let (y0, v0) = pericentre();
        let scale = [1.0; 2];
        let h = TAU / f64::from(steps);
        let (mut y, mut v, mut a) = (y0, v0, Kepler.acceleration(&y0));
        for _ in 0..steps {
            let step = I::step(&Kepler, &y, &v, &a, h, &scale, &scale);
            (y, v, a) = (step.y, step.v, step.a);
        }
        (0..2)
            .map(|k| (y[k] - y0[k]).abs().max((v[k] - v0[k]).abs()))
            .fold(0.0, f64::max)
    }

    /// Asserts that the observed global order `log2(err(n) / err(2 n))` over one period with
    /// `n = steps` is within `tolerance` of `I::ORDER`.
    pub fn assert_observed_order<I: Integrator>(steps: u32, tolerance: f64) {
        let order = libm::log2(period_error::<I>(steps) / period_error::<I>(2 * steps));
        let want = f64::from(I::ORDER);
        assert!(
            (order - want).abs() < tolerance,
            "{}: observed order {order}, want {want}",
            I::NAME
        );
    }

    /// Asserts that the error estimate of a single step from pericentre scales as
    /// `h^(ERROR_ORDER + 1)`: `log2(est(h) / est(h / 2))` within 0.2 of `ERROR_ORDER + 1`
    /// (a wrong error weight or a wrong `ERROR_ORDER` is off by at least one).
    pub fn assert_error_estimate_exponent<I: Integrator>(h: f64) {
        let (y, v) = pericentre();
        let a = Kepler.acceleration(&y);
        let scale = [1.0; 2];
        let estimate = |h| I::step(&Kepler, &y, &v, &a, h, &scale, &scale).error;
        let exponent = libm::log2(estimate(h) / estimate(h / 2.0));
        let want = f64::from(I::ERROR_ORDER + 1);
        assert!(
            (exponent - want).abs() < 0.2,
            "{}: observed exponent {exponent}, want {want}",
            I::NAME
        );
    }

    /// `sum_i weights_i nodes_i^k`, a quadrature moment of the tableau.
    pub fn moment(weights: &[f64], nodes: &[f64], k: i32) -> f64 {
        weights.iter().zip(nodes).map(|(w, c)| w * c.powi(k)).sum()
    }

    /// Asserts `|got - want| <= tolerance` with a message naming the condition.
    pub fn assert_close(condition: &str, got: f64, want: f64, tolerance: f64) {
        assert!(
            (got - want).abs() <= tolerance,
            "{condition}: got {got:e}, want {want:e}"
        );
    }

    /// Kepler field that counts its evaluations.
    struct CountingKepler {
        calls: Cell<u32>,
    }

    impl Acceleration<[f64; 2]> for CountingKepler {
        fn acceleration(&self, y: &[f64; 2]) -> [f64; 2] {
            self.calls.set(self.calls.get() + 1);
            Kepler.acceleration(y)
        }
    }

    /// One step calls the field exactly `EVALUATIONS_PER_STEP` times, and the returned `a` is
    /// bit-for-bit the field at the returned positions.
    pub fn assert_evaluations_and_returned_acceleration<I: Integrator>() {
        let (y, v) = pericentre();
        let a = Kepler.acceleration(&y);
        let counting = CountingKepler {
            calls: Cell::new(0),
        };
        let step = I::step(&counting, &y, &v, &a, 0.1, &[1e-9; 2], &[1e-9; 2]);
        assert_eq!(counting.calls.get(), I::EVALUATIONS_PER_STEP, "{}", I::NAME);
        assert_eq!(step.a, Kepler.acceleration(&step.y), "{}", I::NAME);
    }

    /// Uniform field `y'' = g`.
    struct UniformField;

    impl Acceleration<[f64; 2]> for UniformField {
        fn acceleration(&self, _y: &[f64; 2]) -> [f64; 2] {
            [0.5, -2.0]
        }
    }

    /// A uniform field is integrated exactly (up to rounding) with a zero error estimate:
    /// `y + h v + h^2 g / 2`, `v + h g`.
    pub fn assert_uniform_field_is_exact<I: Integrator>() {
        let (y, v, g, h) = ([1.0, -3.0], [0.25, 2.0], [0.5, -2.0], 0.75);
        let step = I::step(&UniformField, &y, &v, &g, h, &[1.0; 2], &[1.0; 2]);
        // Roundings of O(1) numbers times tableau entries of up to ~50 that cancel.
        let tolerance = 1e-13;
        for k in 0..2 {
            let position = y[k] + h * v[k] + 0.5 * h * h * g[k];
            assert_close("position", step.y[k], position, tolerance);
            assert_close("velocity", step.v[k], v[k] + h * g[k], tolerance);
        }
        assert!(step.error < tolerance, "{}: error {}", I::NAME, step.error);
    }
}
