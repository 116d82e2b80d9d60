//! The adaptive step driver for systems of gaps: particles on a line or a ring that keep their
//! order, whose state is the gaps `g_k > 0` between neighbours and their rates `g_k'`.
//!
//! [`drive`] owns everything around a single step of an [`Integrator`]: the attempt loop, the
//! step budget (accepted and rejected attempts alike), the step-size controller and the stop
//! exactly at the end time. The caller supplies what differs: the acceleration field, the error
//! scales ([`ErrorScales`]) and what happens after an accepted step ([`AfterStep`]: go on, a
//! state moved by the caller such as a free-flight jump, or a stop).
//!
//! A step is `h = ratio * tau`: `tau` the local time scale of the fastest gap
//! ([`local_time_scale`]), `ratio` the controlled quantity. It is capped by the approach limit
//! (no approaching gap may close by more than [`APPROACH_FRACTION`] of itself in free flight) and
//! by the time left. A trial is accepted when its error estimate is at most 1 and every gap stays
//! positive; a NaN estimate (forces overflowing at a stage that nearly closed a gap) is rejected.
//! All quantities are in the caller's scaled units.

use super::{Acceleration, Integrator, Step, Trial, Vector};

/// Fraction of the free-flight time to contact that one step may cover: a step never carries
/// two approaching neighbours past each other.
const APPROACH_FRACTION: f64 = 0.5;
/// First step in units of the local time scale; the controller corrects it.
const INITIAL_STEP_RATIO: f64 = 0.1;

/// Absolute error allowed per step and component, the scales of [`Integrator::step`].
pub trait ErrorScales<V> {
    /// Allowed error of each gap in a step from `gaps`.
    fn gap_scale(&self, gaps: &V) -> V;
    /// Allowed error of each gap rate.
    fn rate_scale(&self) -> &V;
}

/// What a drive does after an accepted step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AfterStep<T> {
    /// Take the next step.
    Continue,
    /// The caller moved the gaps and rates along the trajectory (an exact free-flight jump):
    /// the acceleration is evaluated anew there. The move's own duration is the caller's
    /// business; the drive's clock counts integrated steps only.
    Moved,
    /// End the drive with `T`.
    Stop(T),
}

/// How long a drive may run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// Integration time; infinite to run until [`AfterStep::Stop`].
    pub duration: f64,
    /// Step attempts, accepted and rejected, before the drive gives up.
    pub max_attempts: u64,
}

/// Work done by a drive.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Work {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected step attempts.
    pub rejected: u64,
    /// Acceleration evaluations, including the one at the start and one per move.
    pub evaluations: u64,
}

/// How a drive ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ending<T> {
    /// The whole duration was integrated; the state is at its end exactly.
    Elapsed,
    /// The caller stopped the drive after an accepted step.
    Stopped(T),
    /// The attempt budget ran out.
    BudgetExhausted,
    /// The step collapsed to rounding: the problem is singular here.
    Collapse,
}

/// The result of [`drive`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive<T> {
    /// How the drive ended.
    pub ending: Ending<T>,
    /// What it cost.
    pub work: Work,
}

/// Integrates `gaps'' = acceleration(gaps)` from `(gaps, rates)` on adaptive steps of `I` for
/// `span.duration`, leaving the final state in `gaps` and `rates` (the last accepted one when
/// the drive fails). `after_step(gaps, rates, h)` runs after every accepted step of size `h`.
#[inline(always)]
pub fn drive<I: Integrator, V: Vector, A: Acceleration<V>, T>(
    acceleration: &A,
    scales: &impl ErrorScales<V>,
    gaps: &mut V,
    rates: &mut V,
    span: Span,
    mut after_step: impl FnMut(&mut V, &mut V, f64) -> AfterStep<T>,
) -> Drive<T> {
    let mut driving = Driving::start::<I, A>(acceleration, gaps.clone(), rates.clone());
    let ending = loop {
        let step = match driving.next_step::<T>(span) {
            Ok(step) => step,
            Err(ending) => break ending,
        };
        let gap_scale = scales.gap_scale(&driving.gaps);
        let [attempt] = I::steps(
            acceleration,
            [driving.trial(step, &gap_scale, scales.rate_scale())],
        );
        let settled = driving.settle::<I, A, T>(acceleration, span, step, attempt, &mut after_step);
        if let Some(ending) = settled {
            break ending;
        }
    };
    (*gaps, *rates) = (driving.gaps, driving.rates);
    Drive {
        ending,
        work: driving.work,
    }
}

/// A trajectory driven by [`drive_lanes`]: the scales of its errors and what happens after each
/// of its accepted steps (the `after_step` of [`drive`]).
pub trait Trajectory<V>: ErrorScales<V> {
    /// The value a stop carries.
    type Stop;
    /// Runs after every accepted step of size `step`.
    fn after_step(&mut self, gaps: &mut V, rates: &mut V, step: f64) -> AfterStep<Self::Stop>;
}

/// Drives every trajectory that `queue` yields (with its start gaps and rates), up to `LANES`
/// at a time, and hands each to `finish` with its drive and final gaps and rates when it ends,
/// in the order they end. While `LANES` trajectories are under way, their attempts are taken
/// in one [`Integrator::steps`] call, which interleaves their stages (a step alone is bound by
/// the latency of its chain of stages); fewer take their steps one by one. Each trajectory
/// takes exactly the steps and operations it takes in [`drive`]: the same bits for any `LANES`
/// and any order of the queue.
pub fn drive_lanes<I, V, A, R, const LANES: usize>(
    acceleration: &A,
    span: Span,
    mut queue: impl Iterator<Item = (R, V, V)>,
    mut finish: impl FnMut(R, Drive<R::Stop>, V, V),
) where
    I: Integrator,
    V: Vector,
    A: Acceleration<V>,
    R: Trajectory<V>,
{
    let mut lanes: Vec<Lane<R, V>> = Vec::with_capacity(LANES);
    loop {
        while lanes.len() < LANES {
            let Some((trajectory, gaps, rates)) = queue.next() else {
                break;
            };
            let mut lane = Lane::start::<I, A>(acceleration, trajectory, gaps, rates);
            lane.prepare(span);
            lanes.push(lane);
            end_finished(&mut lanes, &mut finish);
        }
        if lanes.is_empty() {
            return;
        }
        if lanes.len() == LANES {
            let trials: [Trial<'_, V>; LANES] = std::array::from_fn(|k| lanes[k].trial());
            let attempts = I::steps(acceleration, trials);
            for (lane, attempt) in lanes.iter_mut().zip(attempts) {
                lane.advance::<I, A>(acceleration, span, attempt);
            }
        } else {
            for lane in &mut lanes {
                let [attempt] = I::steps(acceleration, [lane.trial()]);
                lane.advance::<I, A>(acceleration, span, attempt);
            }
        }
        end_finished(&mut lanes, &mut finish);
    }
}

/// Hands every ended lane of `lanes` to `finish` and removes it.
fn end_finished<R: Trajectory<V>, V>(
    lanes: &mut Vec<Lane<R, V>>,
    finish: &mut impl FnMut(R, Drive<R::Stop>, V, V),
) {
    let mut k = 0;
    while k < lanes.len() {
        if let Some(ending) = lanes[k].ended.take() {
            let Lane {
                trajectory,
                driving,
                ..
            } = lanes.swap_remove(k);
            let drive = Drive {
                ending,
                work: driving.work,
            };
            finish(trajectory, drive, driving.gaps, driving.rates);
        } else {
            k += 1;
        }
    }
}

/// One trajectory of [`drive_lanes`] under way: its drive, the attempt it takes next (`step`
/// and the gap scale there), or how it ended.
struct Lane<R: Trajectory<V>, V> {
    trajectory: R,
    driving: Driving<V>,
    step: f64,
    gap_scale: V,
    ended: Option<Ending<R::Stop>>,
}

impl<R: Trajectory<V>, V: Vector> Lane<R, V> {
    /// A lane starting `trajectory` at `(gaps, rates)`.
    #[inline(always)]
    fn start<I: Integrator, A: Acceleration<V>>(
        acceleration: &A,
        trajectory: R,
        gaps: V,
        rates: V,
    ) -> Self {
        let gap_scale = gaps.zeros_like();
        Lane {
            trajectory,
            driving: Driving::start::<I, A>(acceleration, gaps, rates),
            step: 0.0,
            gap_scale,
            ended: None,
        }
    }

    /// Sizes the next attempt, or ends the lane when its drive is over.
    #[inline(always)]
    fn prepare(&mut self, span: Span) {
        match self.driving.next_step::<R::Stop>(span) {
            Ok(step) => {
                self.step = step;
                self.gap_scale = self.trajectory.gap_scale(&self.driving.gaps);
            }
            Err(ending) => self.ended = Some(ending),
        }
    }

    /// The attempt sized by [`Lane::prepare`].
    #[inline(always)]
    fn trial(&self) -> Trial<'_, V> {
        let rate_scale = self.trajectory.rate_scale();
        self.driving.trial(self.step, &self.gap_scale, rate_scale)
    }

    /// Takes the outcome `attempt` of [`Lane::trial`] and sizes the next one.
    #[inline(always)]
    fn advance<I: Integrator, A: Acceleration<V>>(
        &mut self,
        acceleration: &A,
        span: Span,
        attempt: Step<V>,
    ) {
        let Lane {
            trajectory,
            driving,
            step,
            ..
        } = self;
        let mut after_step = |gaps: &mut V, rates: &mut V, h| trajectory.after_step(gaps, rates, h);
        match driving.settle::<I, A, R::Stop>(acceleration, span, *step, attempt, &mut after_step) {
            Some(ending) => self.ended = Some(ending),
            None => self.prepare(span),
        }
    }
}

/// A drive under way: the state, its acceleration, the step controller and the clock.
struct Driving<V> {
    gaps: V,
    rates: V,
    accelerations: V,
    control: StepControl,
    elapsed: f64,
    work: Work,
}

impl<V: Vector> Driving<V> {
    /// A drive starting at `(gaps, rates)`, its acceleration evaluated there.
    #[inline(always)]
    fn start<I: Integrator, A: Acceleration<V>>(acceleration: &A, gaps: V, rates: V) -> Self {
        Driving {
            accelerations: acceleration.acceleration(&gaps),
            gaps,
            rates,
            // The controller adapts the step in units of the local time scale, the quantity
            // the error actually depends on (see `local_time_scale`).
            control: StepControl::new::<I>(INITIAL_STEP_RATIO),
            elapsed: 0.0,
            work: Work {
                evaluations: 1,
                ..Work::default()
            },
        }
    }

    /// The size of the next attempt of integrator `I`, or how the drive ends before it: the
    /// duration integrated, or the attempt budget spent.
    #[inline(always)]
    fn next_step<T>(&self, span: Span) -> Result<f64, Ending<T>> {
        if self.elapsed >= span.duration {
            return Err(Ending::Elapsed);
        }
        if self.work.steps + self.work.rejected >= span.max_attempts {
            return Err(Ending::BudgetExhausted);
        }
        let (g, w) = (self.gaps.components(), self.rates.components());
        let scale = local_time_scale(g, w, self.accelerations.components());
        Ok((self.control.ratio * scale)
            .min(approach_limit(g, w))
            .min(span.duration - self.elapsed))
    }

    /// The attempt of size `step` from the current state.
    #[inline(always)]
    fn trial<'a>(&'a self, step: f64, gap_scale: &'a V, rate_scale: &'a V) -> Trial<'a, V> {
        Trial {
            y: &self.gaps,
            v: &self.rates,
            a0: &self.accelerations,
            h: step,
            position_scale: gap_scale,
            velocity_scale: rate_scale,
        }
    }

    /// Takes the `attempt` of size `step`: rejects it, or accepts it and runs `after_step`.
    /// Returns how the drive ends, if it does here.
    #[inline(always)]
    fn settle<I: Integrator, A: Acceleration<V>, T>(
        &mut self,
        acceleration: &A,
        span: Span,
        step: f64,
        attempt: Step<V>,
        after_step: &mut impl FnMut(&mut V, &mut V, f64) -> AfterStep<T>,
    ) -> Option<Ending<T>> {
        self.work.evaluations += u64::from(I::EVALUATIONS_PER_STEP);
        if !admissible(&attempt) {
            self.work.rejected += 1;
            return self
                .control
                .reject(attempt.error)
                .err()
                .map(|StepCollapse| Ending::Collapse);
        }
        self.work.steps += 1;
        let remaining = span.duration - self.elapsed;
        self.elapsed = if step == remaining {
            span.duration
        } else {
            self.elapsed + step
        };
        (self.gaps, self.rates, self.accelerations) = (attempt.y, attempt.v, attempt.a);
        self.control.accept(attempt.error);
        match after_step(&mut self.gaps, &mut self.rates, step) {
            AfterStep::Continue => None,
            AfterStep::Moved => {
                self.accelerations = acceleration.acceleration(&self.gaps);
                self.work.evaluations += 1;
                None
            }
            AfterStep::Stop(value) => Some(Ending::Stopped(value)),
        }
    }
}

/// Whether a trial step may be taken: its error within tolerance (`!(e <= 1)` also rejects a
/// NaN estimate) and no two neighbours carried past each other (every gap still positive).
#[inline(always)]
fn admissible<V: Vector>(trial: &Step<V>) -> bool {
    trial.error <= 1.0 && trial.y.components().iter().all(|&g| g > 0.0)
}

/// Time over which the gaps change appreciably:
/// `tau = min_k g_k / sqrt(g_k'^2 + g_k |g_k''|)`, the time to contact in free approach and
/// `sqrt(g / |g''|)` at a turning point. The local error of a step of size `h` is a steep
/// function of `h / tau` (the force is analytic within a radius of order `tau` in complex
/// time), so the controller adapts `h / tau` rather than `h`: the step then follows the
/// geometry of approach and separation instead of lagging behind it.
#[inline(always)]
fn local_time_scale(gaps: &[f64], rates: &[f64], accelerations: &[f64]) -> f64 {
    gaps.iter()
        .zip(rates)
        .zip(accelerations)
        .map(|((g, w), a)| g / (w * w + g * a.abs()).sqrt())
        .fold(f64::INFINITY, f64::min)
}

/// Largest step allowed by the free-flight time to contact `g / -g'` of approaching gaps.
#[inline(always)]
fn approach_limit(gaps: &[f64], rates: &[f64]) -> f64 {
    gaps.iter()
        .zip(rates)
        .filter(|(_, w)| **w < 0.0)
        .map(|(g, w)| APPROACH_FRACTION * g / -w)
        .fold(f64::INFINITY, f64::min)
}

/// Step-size control in units of the local time scale (the ratio `h / tau`): the classical
/// controller `ratio *= safety * error^(-1/(q+1))`, bounded per step, with no growth right
/// after a rejection (Hairer, Norsett & Wanner, II.4).
#[derive(Clone, Copy, Debug)]
struct StepControl {
    /// Current step in units of the local time scale.
    ratio: f64,
    /// `-1 / (q + 1)`, `q` the integrator's error order.
    exponent: f64,
    just_rejected: bool,
}

/// Controller safety factor and bounds on the change per step.
const SAFETY: f64 = 0.9;
const MIN_STEP_FACTOR: f64 = 0.2;
const MAX_STEP_FACTOR: f64 = 5.0;

/// The step collapsed to rounding: the problem is singular at this point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct StepCollapse;

impl StepControl {
    /// A controller for integrator `I` starting at `ratio`.
    fn new<I: Integrator>(ratio: f64) -> StepControl {
        StepControl {
            ratio,
            exponent: -1.0 / f64::from(I::ERROR_ORDER + 1),
            just_rejected: false,
        }
    }

    /// Shrinks the step after a rejected trial with estimate `error` (a trial rejected for
    /// another reason with `error <= 1`, such as two particles crossing, is halved; a NaN or
    /// infinite estimate shrinks it by the largest factor).
    fn reject(&mut self, error: f64) -> Result<(), StepCollapse> {
        self.just_rejected = true;
        let factor = if error > 1.0 && error.is_finite() {
            (SAFETY * controller_power(error, self.exponent)).clamp(MIN_STEP_FACTOR, SAFETY)
        } else if error <= 1.0 {
            0.5
        } else {
            MIN_STEP_FACTOR
        };
        self.ratio *= factor;
        if self.ratio.is_nan() || self.ratio <= f64::EPSILON {
            Err(StepCollapse)
        } else {
            Ok(())
        }
    }

    /// Adapts the step after an accepted trial with estimate `error`.
    fn accept(&mut self, error: f64) {
        let growth_cap = if self.just_rejected {
            1.0
        } else {
            MAX_STEP_FACTOR
        };
        self.just_rejected = false;
        self.ratio *=
            (SAFETY * controller_power(error, self.exponent)).clamp(MIN_STEP_FACTOR, growth_cap);
    }
}

/// Bound on `|exponent ln(error)|` in [`controller_power`]: `e^2 = 7.4` lies beyond
/// `MAX_STEP_FACTOR / SAFETY` and `e^-2 = 0.14` below `MIN_STEP_FACTOR / SAFETY`, so the
/// bounded step factor is the same as with the unbounded power.
const CONTROLLER_LOG_BOUND: f64 = 2.0;

/// `error^exponent` for the step controller, with `exponent ln(error)` held to
/// `[-CONTROLLER_LOG_BOUND, CONTROLLER_LOG_BOUND]`, to 1e-7 relative (unit test): a general
/// `pow` to the last bit took 15% of a collision's time (one per step, against 17 force
/// stages), and a step factor needs no more than a few digits. Additions, multiplications and
/// one division only, so the same bits on every CPU: `ln` from the exponent bits and the
/// `atanh` series of the mantissa brought to `[sqrt(1/2), sqrt(2))`, `exp(t) = exp(t / 8)^8`
/// from the Taylor polynomial to `(t / 8)^7` (`|t / 8| <= 1/4`) evaluated in Estrin's scheme
/// (short dependency chains). Zero and subnormal errors count as the smallest normal one.
fn controller_power(error: f64, exponent: f64) -> f64 {
    let t = (exponent * natural_log(error.max(f64::MIN_POSITIVE)))
        .clamp(-CONTROLLER_LOG_BOUND, CONTROLLER_LOG_BOUND);
    let r = t / 8.0;
    let r2 = r * r;
    let eighth = (1.0 + r)
        + r2 * ((1.0 / 2.0 + r / 6.0)
            + r2 * ((1.0 / 24.0 + r / 120.0) + r2 * (1.0 / 720.0 + r / 5040.0)));
    let square = eighth * eighth;
    let fourth = square * square;
    fourth * fourth
}

/// `ln x` for a positive normal `x`, to 1e-9 absolute (see [`controller_power`]):
/// `2 atanh(s)` to `s^9`, `s = (m - 1)/(m + 1)`, `|s| <= 0.172`.
fn natural_log(x: f64) -> f64 {
    const MANTISSA: u64 = (1 << 52) - 1;
    let bits = x.to_bits();
    let mut exponent = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mut mantissa = f64::from_bits((bits & MANTISSA) | (1023 << 52));
    if mantissa > std::f64::consts::SQRT_2 {
        mantissa /= 2.0;
        exponent += 1;
    }
    let s = (mantissa - 1.0) / (mantissa + 1.0);
    let s2 = s * s;
    let s4 = s2 * s2;
    let series = (1.0 + s2 / 3.0) + s4 * ((1.0 / 5.0 + s2 / 7.0) + s4 / 9.0);
    2.0 * s * series + exponent as f64 * std::f64::consts::LN_2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::{Dop853, Dopri5, Dprkn12};
    use std::convert::Infallible;

    /// Rest length of [`Spring`].
    const REST: f64 = 2.0;

    /// The controller's power agrees with `pow` to 1e-7 relative wherever the bounded
    /// step factor depends on it, and lands on the same side of the bounds elsewhere.
    #[test]
    fn the_controller_power_is_pow_within_its_bound() {
        let exponent = -1.0 / 13.0;
        for k in -4000..=4000 {
            let error = libm::pow(10.0, f64::from(k) / 100.0);
            let (ours, exact) = (
                controller_power(error, exponent),
                libm::pow(error, exponent),
            );
            if (-CONTROLLER_LOG_BOUND..=CONTROLLER_LOG_BOUND).contains(&libm::log(exact)) {
                assert!(
                    (ours / exact - 1.0).abs() < 1e-7,
                    "{error}: {ours} vs {exact}"
                );
            } else {
                let bound = libm::exp(CONTROLLER_LOG_BOUND * libm::log(exact).signum());
                assert!(
                    (ours / bound - 1.0).abs() < 1e-7,
                    "{error}: {ours} vs {bound}"
                );
            }
        }
        assert_eq!(
            controller_power(0.0, exponent),
            controller_power(1e-300, exponent)
        );
        assert!(MAX_STEP_FACTOR / SAFETY < libm::exp(CONTROLLER_LOG_BOUND));
        assert!(MIN_STEP_FACTOR / SAFETY > libm::exp(-CONTROLLER_LOG_BOUND));
    }

    /// Two particles joined by a spring of rest length [`REST`] and unit angular frequency:
    /// `g'' = REST - g`, solved by `g(t) = REST + A cos t + B sin t`.
    struct Spring;

    impl Acceleration<[f64; 1]> for Spring {
        fn acceleration(&self, gap: &[f64; 1]) -> [f64; 1] {
            [REST - gap[0]]
        }
    }

    /// A field that is NaN everywhere, as forces overflowing at every trial stage.
    struct Overflowing;

    impl Acceleration<[f64; 1]> for Overflowing {
        fn acceleration(&self, _gap: &[f64; 1]) -> [f64; 1] {
            [f64::NAN]
        }
    }

    /// The uniform field `g'' = PULL`, integrated exactly (to rounding) by every pair.
    struct Uniform;

    const PULL: f64 = 0.5;

    impl Acceleration<[f64; 1]> for Uniform {
        fn acceleration(&self, _gap: &[f64; 1]) -> [f64; 1] {
            [PULL]
        }
    }

    /// The same absolute error `tolerance` for the gap and its rate.
    struct Absolute([f64; 1]);

    impl ErrorScales<[f64; 1]> for Absolute {
        fn gap_scale(&self, _gaps: &[f64; 1]) -> [f64; 1] {
            self.0
        }

        fn rate_scale(&self) -> &[f64; 1] {
            &self.0
        }
    }

    /// Drives `field` from `(gap, rate)` for `duration` at tolerance `tolerance`, with
    /// `after_step` after every accepted step.
    fn run<I: Integrator, A: Acceleration<[f64; 1]>, T>(
        field: &A,
        (gap, rate): (f64, f64),
        duration: f64,
        tolerance: f64,
        max_attempts: u64,
        after_step: impl FnMut(&mut [f64; 1], &mut [f64; 1], f64) -> AfterStep<T>,
    ) -> ([f64; 1], [f64; 1], Drive<T>) {
        let (mut gaps, mut rates) = ([gap], [rate]);
        let span = Span {
            duration,
            max_attempts,
        };
        let scales = Absolute([tolerance]);
        let drive = drive::<I, _, _, _>(field, &scales, &mut gaps, &mut rates, span, after_step);
        (gaps, rates, drive)
    }

    /// An observer that never stops a drive.
    fn go_on(_: &mut [f64; 1], _: &mut [f64; 1], _: f64) -> AfterStep<Infallible> {
        AfterStep::Continue
    }

    /// Largest deviation of `(gap, rate)` from the spring released at rest at `REST + 1`,
    /// `(REST + cos t, -sin t)`, at time `t`.
    fn spring_error(gaps: [f64; 1], rates: [f64; 1], t: f64) -> f64 {
        (gaps[0] - (REST + libm::cos(t)))
            .abs()
            .max((rates[0] + libm::sin(t)).abs())
    }

    /// A spring released at a given gap that stops after a given number of steps, for
    /// [`drive_lanes`].
    struct Released {
        index: u32,
        scales: Absolute,
        stop_after: u32,
        steps: u32,
    }

    impl ErrorScales<[f64; 1]> for Released {
        fn gap_scale(&self, gaps: &[f64; 1]) -> [f64; 1] {
            self.scales.gap_scale(gaps)
        }

        fn rate_scale(&self) -> &[f64; 1] {
            self.scales.rate_scale()
        }
    }

    impl Trajectory<[f64; 1]> for Released {
        type Stop = u32;
        fn after_step(&mut self, _: &mut [f64; 1], _: &mut [f64; 1], _: f64) -> AfterStep<u32> {
            self.steps += 1;
            if self.steps == self.stop_after {
                AfterStep::Stop(self.steps)
            } else {
                AfterStep::Continue
            }
        }
    }

    /// Trajectories driven three at a time are the trajectories driven one by one, to the
    /// bit: the same end state, ending and work, whether they stop, run out of time or of
    /// budget, handed over with their own state.
    #[test]
    fn lanes_drive_each_trajectory_as_alone() {
        let span = Span {
            duration: 6.0,
            max_attempts: 7,
        };
        let released = |k: u32| {
            let trajectory = Released {
                index: k,
                scales: Absolute([libm::pow(10.0, -4.0 - f64::from(k))]),
                stop_after: if k.is_multiple_of(3) { 3 + k } else { u32::MAX },
                steps: 0,
            };
            (trajectory, [REST + 0.1 * f64::from(k + 1)], [0.0])
        };
        let mut together = Vec::new();
        drive_lanes::<Dprkn12, _, _, _, 3>(
            &Spring,
            span,
            (0..8).map(released),
            |lane, drive, gaps, rates| {
                together.push((lane.index, drive, gaps[0].to_bits(), rates[0].to_bits()));
            },
        );
        together.sort_by_key(|&(index, ..)| index);
        let alone: Vec<_> = (0..8)
            .map(|k| {
                let (mut trajectory, mut gaps, mut rates) = released(k);
                let scales = Absolute(trajectory.scales.0);
                let drive = drive::<Dprkn12, _, _, _>(
                    &Spring,
                    &scales,
                    &mut gaps,
                    &mut rates,
                    span,
                    |g, r, h| trajectory.after_step(g, r, h),
                );
                (
                    trajectory.index,
                    drive,
                    gaps[0].to_bits(),
                    rates[0].to_bits(),
                )
            })
            .collect();
        assert_eq!(together, alone);
        let endings: Vec<_> = alone.iter().map(|(_, drive, ..)| drive.ending).collect();
        assert!(endings.contains(&Ending::Stopped(3)), "{endings:?}");
        assert!(endings.contains(&Ending::Elapsed), "{endings:?}");
        assert!(endings.contains(&Ending::BudgetExhausted), "{endings:?}");
    }

    /// Over three periods the spring stays on its closed form within the local tolerance
    /// summed over the accepted steps (the oscillator neither damps nor amplifies errors),
    /// with every integrator.
    fn assert_spring_follows_its_closed_form<I: Integrator>() {
        let (duration, tolerance) = (6.0 * std::f64::consts::PI, 1e-10);
        let (gaps, rates, drive) = run::<I, _, _>(
            &Spring,
            (REST + 1.0, 0.0),
            duration,
            tolerance,
            100_000,
            go_on,
        );
        assert_eq!(drive.ending, Ending::Elapsed, "{}", I::NAME);
        let error = spring_error(gaps, rates, duration);
        let bound = drive.work.steps as f64 * tolerance;
        assert!(error <= bound, "{}: error {error:e} > {bound:e}", I::NAME);
    }

    #[test]
    fn spring_follows_its_closed_form_at_the_tolerance() {
        assert_spring_follows_its_closed_form::<Dopri5>();
        assert_spring_follows_its_closed_form::<Dop853>();
        assert_spring_follows_its_closed_form::<Dprkn12>();
    }

    /// The last accepted step is exactly the time left (the steps before it summed as the
    /// drive sums them), so the state is the one at `duration`: in a uniform field, which
    /// every step integrates exactly, `g + w T + PULL T^2 / 2` to rounding.
    #[test]
    fn the_drive_stops_exactly_at_its_duration() {
        let ((gap, rate), duration) = ((1.0, 0.3), 7.3);
        let mut steps = Vec::new();
        let (gaps, rates, drive) = run::<Dprkn12, _, _>(
            &Uniform,
            (gap, rate),
            duration,
            1e-12,
            1000,
            |_, _, step| {
                steps.push(step);
                AfterStep::<Infallible>::Continue
            },
        );
        assert_eq!(drive.ending, Ending::Elapsed);
        let (last, before) = steps.split_last().unwrap();
        assert!(!before.is_empty(), "a single step tests nothing: {steps:?}");
        let elapsed = before.iter().fold(0.0, |t, h| t + h);
        assert_eq!(*last, duration - elapsed, "{steps:?}");
        // Rounding of O(10) numbers over a few steps.
        let tolerance = 1e-13;
        let exact_gap = gap + rate * duration + 0.5 * PULL * duration * duration;
        assert!((gaps[0] - exact_gap).abs() < tolerance, "{gaps:?}");
        assert!(
            (rates[0] - (rate + PULL * duration)).abs() < tolerance,
            "{rates:?}"
        );
    }

    /// Accepted and rejected attempts alike use up the budget; each costs the integrator's
    /// evaluations on top of the one at the start.
    #[test]
    fn the_budget_counts_accepted_and_rejected_attempts() {
        let (_, _, accepted) = run::<Dprkn12, _, _>(&Spring, (3.0, 0.0), 1e3, 1e-10, 7, go_on);
        let (_, _, rejected) = run::<Dprkn12, _, _>(&Overflowing, (3.0, 0.0), 1e3, 1e-10, 7, go_on);
        for drive in [accepted, rejected] {
            assert_eq!(drive.ending, Ending::BudgetExhausted);
            let work = drive.work;
            assert_eq!(work.steps + work.rejected, 7);
            assert_eq!(
                work.evaluations,
                1 + 7 * u64::from(Dprkn12::EVALUATIONS_PER_STEP)
            );
        }
        assert!(accepted.work.steps > 0);
        assert_eq!(rejected.work.steps, 0);
    }

    /// A NaN error estimate is never accepted: the state stays put while the step shrinks
    /// to rounding, and the drive reports the collapse.
    #[test]
    fn a_nan_error_estimate_is_rejected() {
        let (gaps, rates, drive) =
            run::<Dprkn12, _, _>(&Overflowing, (3.0, 0.5), 1e3, 1e-10, 1000, go_on);
        assert_eq!(drive.ending, Ending::Collapse);
        assert_eq!(drive.work.steps, 0);
        assert!(drive.work.rejected > 1);
        assert_eq!((gaps, rates), ([3.0], [0.5]));
    }

    /// A step never carries two neighbours past each other: approaching in free flight
    /// towards contact at `t = 1`, the gap only shrinks (by at most half per step) and the
    /// drive runs out of budget short of contact.
    #[test]
    fn approaching_neighbours_are_never_carried_past_each_other() {
        let mut previous = 1.0;
        let (gaps, _, drive) = run::<Dprkn12, _, _>(
            &Uniform,
            (1.0, -1.0 - PULL),
            2.0,
            1e-10,
            200,
            |gaps, _, _| {
                assert!(gaps[0] >= 0.5 * previous, "{} after {previous}", gaps[0]);
                previous = gaps[0];
                AfterStep::<Infallible>::Continue
            },
        );
        assert_eq!(drive.ending, Ending::BudgetExhausted);
        assert!(gaps[0] > 0.0);
    }

    /// After [`AfterStep::Moved`] the drive goes on from the moved state with its
    /// acceleration evaluated anew (one evaluation more), and [`AfterStep::Stop`] ends it
    /// right after the step: a compressed spring moved to its release point after the first
    /// step and stopped after the tenth is on the closed form at the time integrated since the
    /// move.
    #[test]
    fn a_moved_state_is_continued_and_a_stop_ends_the_drive() {
        let tolerance = 1e-10;
        let (mut accepted, mut since_move) = (0, 0.0);
        let (gaps, rates, drive) = run::<Dprkn12, _, _>(
            &Spring,
            (REST - 1.5, 0.0),
            1e3,
            tolerance,
            1000,
            |gaps, rates, step| {
                accepted += 1;
                match accepted {
                    1 => {
                        (*gaps, *rates) = ([REST + 1.0], [0.0]);
                        AfterStep::Moved
                    }
                    10 => {
                        since_move += step;
                        AfterStep::Stop(accepted)
                    }
                    _ => {
                        since_move += step;
                        AfterStep::Continue
                    }
                }
            },
        );
        assert_eq!(drive.ending, Ending::Stopped(10));
        let work = drive.work;
        assert_eq!(work.steps, 10);
        let attempts = work.steps + work.rejected;
        let evaluations = 1 + attempts * u64::from(Dprkn12::EVALUATIONS_PER_STEP) + 1;
        assert_eq!(work.evaluations, evaluations);
        let error = spring_error(gaps, rates, since_move);
        // DPRKN12 propagates its 12th-order solution, far more accurate than the 10th-order
        // estimate the tolerance bounds (here ~1e-13); continuing with the acceleration from
        // before the move would leave ~3e-10.
        assert!(error <= 0.01 * tolerance, "error {error:e}");
    }
}
