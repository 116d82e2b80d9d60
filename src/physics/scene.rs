//! The three-body scattering scene (physics.md §3, numerics.md "Integrating a
//! three-body scene").
//!
//! A scene is given by three free asymptotic-in trajectories `x_i(t) = p_i + u_i t`
//! in scaled units. The engine back-propagates them in free flight until every
//! pair has `|U| / w^2 <= epsilon` (`w` the pair's relative speed), applies the
//! first-order tail correction for the interaction felt since `t = -inf`,
//! integrates gaps and gap rates (centre-of-mass velocity conserved by
//! construction) with an embedded high-order pair, jumps analytically across
//! free flight, and stops when the order is final, every neighbour recedes and
//! `|U| / w^2 <= epsilon` again, where the forward tail correction gives the
//! asymptotic-out velocities. The tail corrections leave errors of order
//! `epsilon^2`, which is why `n = 2` (long-ranged) is handled exactly enough.

use serde::{Deserialize, Serialize};

use super::potential::{PairPotential, Potential, PotentialVisitor};
use crate::integrate::{
    Acceleration, AfterStep, Dop853, Dopri5, Dprkn12, Drive, Ending, ErrorScales, Integrator, Span,
    Trajectory, Work, drive_lanes,
};

/// A free asymptotic trajectory `x(t) = position + velocity * t` (scaled units:
/// lengths in `l`, velocities in `v_th`, times in `l / v_th`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeLine {
    /// Position at `t = 0` of the free (non-interacting) asymptote.
    pub position: f64,
    /// Asymptotic velocity.
    pub velocity: f64,
}

/// Embedded pair used to integrate a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Dormand-Prince 5(4): the baseline.
    Dopri5,
    /// Hairer's DOP853 8(5,3).
    Dop853,
    /// Dormand, El-Mikkawy & Prince Runge-Kutta-Nystrom 12(10).
    Dprkn12,
}

impl Method {
    /// Every method, baseline first.
    pub const ALL: [Method; 3] = [Method::Dopri5, Method::Dop853, Method::Dprkn12];

    /// The name used in configuration files and tables.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => Dopri5::NAME,
            Method::Dop853 => Dop853::NAME,
            Method::Dprkn12 => Dprkn12::NAME,
        }
    }
}

/// How a scene is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EngineSettings {
    /// Integration method.
    pub method: Method,
    /// Local error per step relative to the smallest gap (positions) and to the
    /// relative-speed scale (velocities).
    pub tolerance: f64,
    /// Step attempts (accepted and rejected) before a scene counts as failed.
    pub max_steps: u32,
    /// Cross free flight between weak states in one exact step along the
    /// asymptotes (`false`: integrate it, for validation and benchmarks).
    pub free_flight: bool,
}

impl EngineSettings {
    /// Settings with free-flight skipping on.
    pub fn new(method: Method, tolerance: f64, max_steps: u32) -> EngineSettings {
        EngineSettings {
            method,
            tolerance,
            max_steps,
            free_flight: true,
        }
    }

    /// `epsilon`, the largest `|U| / w^2` of any pair when a scene starts or
    /// stops: the first-order tail correction leaves `O(epsilon^2)`, chosen
    /// 100x below the tolerance.
    pub fn tail_level(&self) -> f64 {
        0.1 * self.tolerance.sqrt()
    }
}

/// How a scene ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Three free particles leave.
    Scattered,
    /// A bound pair and a free particle leave (attractive potentials only).
    Recombined,
    /// The step budget ran out.
    StepBudgetExhausted,
    /// Two asymptotes are parallel (equal velocities): no free in-state exists.
    ParallelAsymptotes,
    /// The step size underflowed or the state became non-finite.
    Breakdown,
}

impl Outcome {
    /// The name used in tables.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Scattered => "scattered",
            Outcome::Recombined => "recombined",
            Outcome::StepBudgetExhausted => "failed_step_budget",
            Outcome::ParallelAsymptotes => "failed_parallel_asymptotes",
            Outcome::Breakdown => "failed_breakdown",
        }
    }

    /// `true` for every failure class.
    pub fn is_failure(self) -> bool {
        !matches!(self, Outcome::Scattered | Outcome::Recombined)
    }
}

/// Result of one scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collision {
    /// Asymptotic incoming velocities, ascending.
    pub incoming: [f64; 3],
    /// Asymptotic outgoing velocities, ascending. The members of a recombined
    /// pair both carry the pair's centre-of-mass velocity (their time average).
    pub outgoing: [f64; 3],
    /// How the scene ended; `outgoing` is meaningless for failures.
    pub outcome: Outcome,
    /// Internal energy `w^2/4 + U` of the recombined pair in `kT` (0 otherwise).
    pub binding_energy: f64,
    /// `(E_out - E_in) / (abs(E_in) + D)`: `E` the relative-motion energy, `D` the
    /// well depth (0 for inverse power laws), so that the scale is the largest
    /// kinetic energy a pair reaches.
    pub energy_error: f64,
    /// `|P_out - P_in|` in units of the relative-speed scale.
    pub momentum_error: f64,
    /// Accepted steps.
    pub steps: u32,
    /// Rejected step attempts.
    pub rejected_steps: u32,
    /// Analytic free-flight jumps.
    pub jumps: u32,
    /// Force evaluations (each evaluates all three pairs).
    pub evaluations: u32,
}

impl Collision {
    /// The special particle's own change of velocity: sorted outgoing matched to
    /// sorted incoming, taken at the rank of `special` among the incoming
    /// velocities (physics.md §3, "self" part).
    pub fn self_kick(&self, special: f64) -> f64 {
        let rank = self.incoming.iter().filter(|&&u| u < special).count();
        self.outgoing[rank] - self.incoming[rank]
    }
}

/// Scenes under way at once ([`drive_lanes`]). Four steps with their stages interleaved took
/// 0.39x the time of the same steps one by one (two: 0.69x); whole scenes take 0.53x
/// (`ternary bench integrators`, docs/benchmarks.md), each with the same bits.
const SCENE_LANES: usize = 4;

/// Integrates one scene given by three free asymptotic-in trajectories.
pub fn collide(
    potential: &Potential,
    settings: &EngineSettings,
    lines: [FreeLine; 3],
) -> Collision {
    collide_all(potential, settings, &[lines])
        .pop()
        .expect("one collision per scene")
}

/// Integrates the scenes given by their free asymptotic-in trajectories, several at a time on
/// interleaved steps: each collision is the same to the last bit as [`collide`] of its scene
/// alone, in the order of `scenes`.
pub fn collide_all(
    potential: &Potential,
    settings: &EngineSettings,
    scenes: &[[FreeLine; 3]],
) -> Vec<Collision> {
    potential.visit(ScenesRun { settings, scenes })
}

struct ScenesRun<'a> {
    settings: &'a EngineSettings,
    scenes: &'a [[FreeLine; 3]],
}

impl PotentialVisitor for ScenesRun<'_> {
    type Output = Vec<Collision>;
    fn visit<P: PairPotential>(self, potential: P) -> Vec<Collision> {
        let epsilon = self.settings.tail_level();
        let mut ended = Vec::with_capacity(self.scenes.len());
        let mut starts = Vec::with_capacity(self.scenes.len());
        for (index, &lines) in self.scenes.iter().enumerate() {
            match in_state(potential, lines, epsilon) {
                Some(start) => {
                    let energy_in = relative_kinetic_energy(&start.incoming);
                    starts.push((index, start, energy_in));
                }
                None => {
                    let mut incoming = lines.map(|line| line.velocity);
                    incoming.sort_by(f64::total_cmp);
                    let collision =
                        failed(incoming, Outcome::ParallelAsymptotes, Counters::default());
                    ended.push((index, collision));
                }
            }
        }
        ended.extend(drive_scenes(potential, self.settings, starts));
        in_batch_order(ended)
    }
}

/// The collisions of a batch in the order of their indices, without them.
fn in_batch_order(mut collisions: Vec<(usize, Collision)>) -> Vec<Collision> {
    collisions.sort_by_key(|&(index, _)| index);
    collisions
        .into_iter()
        .map(|(_, collision)| collision)
        .collect()
}

/// Relative acceleration of the two gaps `g1 = x_b - x_a`, `g2 = x_c - x_b`
/// (equal unit masses, all three pairs interacting):
/// `g1'' = 2 f(g1) - f(g2) + f(g1 + g2)`, `g2'' = 2 f(g2) - f(g1) + f(g1 + g2)`.
struct GapAcceleration<P>(P);

impl<P: PairPotential> Acceleration<[f64; 2]> for GapAcceleration<P> {
    fn acceleration(&self, gaps: &[f64; 2]) -> [f64; 2] {
        let inner = self.0.force(gaps[0]);
        let outer = self.0.force(gaps[1]);
        let across = self.0.force(gaps[0] + gaps[1]);
        [2.0 * inner - outer + across, 2.0 * outer - inner + across]
    }
}

/// Gaps and gap rates of the three pairs `(a,b)`, `(b,c)`, `(a,c)`.
fn pairs(gaps: &[f64; 2], rates: &[f64; 2]) -> [(f64, f64); 3] {
    [
        (gaps[0], rates[0]),
        (gaps[1], rates[1]),
        (gaps[0] + gaps[1], rates[0] + rates[1]),
    ]
}

/// Distributes per-pair quantities (pushing the right member up, the left one
/// down) onto the particles `a, b, c`.
fn onto_particles(per_pair: [f64; 3]) -> [f64; 3] {
    let [ab, bc, ac] = per_pair;
    [-ab - ac, ab - bc, bc + ac]
}

/// Particle velocities from the centre-of-mass velocity and the gap rates.
fn velocities(centre: f64, rates: &[f64; 2]) -> [f64; 3] {
    [
        centre - (2.0 * rates[0] + rates[1]) / 3.0,
        centre + (rates[0] - rates[1]) / 3.0,
        centre + (rates[0] + 2.0 * rates[1]) / 3.0,
    ]
}

/// Relative-motion kinetic energy `sum_{i<j} (v_i - v_j)^2 / 6` of three unit masses.
fn relative_kinetic_energy(velocities: &[f64; 3]) -> f64 {
    let [a, b, c] = *velocities;
    ((a - b).powi(2) + (b - c).powi(2) + (a - c).powi(2)) / 6.0
}

/// Adds per-pair changes (right member up, left member down) of displacement
/// and velocity to the gaps and gap rates.
fn apply_pair_changes(
    gaps: &mut [f64; 2],
    rates: &mut [f64; 2],
    displacement: [f64; 3],
    impulse: [f64; 3],
) {
    let dx = onto_particles(displacement);
    let dv = onto_particles(impulse);
    for k in 0..2 {
        gaps[k] += dx[k + 1] - dx[k];
        rates[k] += dv[k + 1] - dv[k];
    }
}

/// Which way [`shift_tails`] moves a weak state.
#[derive(Clone, Copy, PartialEq)]
enum Tails {
    /// From the actual trajectory onto each pair's free asymptote (the line it
    /// came from if approaching, the line it leaves on if receding).
    Remove,
    /// From the free asymptotes back onto the actual trajectory.
    Restore,
}

/// First-order tails of every pair (numerics.md): an approaching pair has gained
/// velocity `U(g)/|r|` and position `Phi(g)/r^2` on its right member since
/// `t = -inf`; a receding pair still lacks them until `t = +inf`. Removing or
/// restoring them maps a weak state to free asymptotic lines and back with
/// errors `O((U/r^2)^2)`, so free flight between weak states is exact motion on
/// those lines: no error grows with the flight time.
fn shift_tails<P: PairPotential>(
    potential: P,
    gaps: &mut [f64; 2],
    rates: &mut [f64; 2],
    direction: Tails,
) {
    let sign = if direction == Tails::Remove {
        -1.0
    } else {
        1.0
    };
    let mut impulse = [0.0; 3];
    let mut displacement = [0.0; 3];
    for (k, (gap, rate)) in pairs(gaps, rates).into_iter().enumerate() {
        let approaching = if rate < 0.0 { 1.0 } else { -1.0 };
        impulse[k] = sign * approaching * potential.energy(gap) / rate.abs();
        displacement[k] = sign * approaching * potential.tail_integral(gap) / (rate * rate);
    }
    apply_pair_changes(gaps, rates, displacement, impulse);
}

/// Free flight over `duration` between two weak states: onto the asymptotes,
/// exact straight lines, back onto the trajectory.
fn free_flight<P: PairPotential>(
    potential: P,
    gaps: &mut [f64; 2],
    rates: &mut [f64; 2],
    duration: f64,
) {
    shift_tails(potential, gaps, rates, Tails::Remove);
    for k in 0..2 {
        gaps[k] += rates[k] * duration;
    }
    shift_tails(potential, gaps, rates, Tails::Restore);
}

/// Largest `|U(g)| / r^2` over the three pairs (infinite when a pair is at rest).
fn tail_strength<P: PairPotential>(potential: P, gaps: &[f64; 2], rates: &[f64; 2]) -> f64 {
    pairs(gaps, rates)
        .into_iter()
        .map(|(gap, rate)| potential.energy(gap).abs() / (rate * rate))
        .fold(0.0, f64::max)
}

/// Time until the first approaching pair enters the range where
/// `|U| / r^2 > epsilon` (0 if one already has; infinite if none approaches).
fn free_flight_time<P: PairPotential>(
    potential: P,
    gaps: &[f64; 2],
    rates: &[f64; 2],
    epsilon: f64,
) -> f64 {
    pairs(gaps, rates)
        .into_iter()
        .filter(|&(_, rate)| rate < 0.0)
        .map(|(gap, rate)| ((gap - potential.range(epsilon * rate * rate)) / -rate).max(0.0))
        .fold(f64::INFINITY, f64::min)
}

/// The state at which integration starts: asymptotic-in lines ordered as at
/// `t = -inf` (fastest leftmost), propagated back until every pair is weak, with
/// the tail felt since `t = -inf` added.
struct InState {
    incoming: [f64; 3],
    centre: f64,
    gaps: [f64; 2],
    rates: [f64; 2],
}

fn in_state<P: PairPotential>(potential: P, lines: [FreeLine; 3], epsilon: f64) -> Option<InState> {
    let mut ordered = lines;
    ordered.sort_by(|p, q| {
        q.velocity
            .total_cmp(&p.velocity)
            .then(p.position.total_cmp(&q.position))
    });
    let [a, b, c] = ordered;
    // Each pair (left, right) closes at w = u_left - u_right >= 0 with gap d - w t.
    let closing = |left: FreeLine, right: FreeLine| {
        let speed = left.velocity - right.velocity;
        let gap_at_zero = right.position - left.position;
        (gap_at_zero, speed)
    };
    let line_pairs = [closing(a, b), closing(b, c), closing(a, c)];
    if line_pairs.iter().any(|&(_, speed)| speed <= 0.0) {
        return None;
    }
    let start = line_pairs
        .iter()
        .map(|&(gap, speed)| (gap - potential.range(epsilon * speed * speed)) / speed)
        .fold(f64::INFINITY, f64::min);
    let mut gaps = [
        line_pairs[0].0 - line_pairs[0].1 * start,
        line_pairs[1].0 - line_pairs[1].1 * start,
    ];
    let mut rates = [b.velocity - a.velocity, c.velocity - b.velocity];
    // Interaction felt since t = -inf.
    shift_tails(potential, &mut gaps, &mut rates, Tails::Restore);
    let mut incoming = [a.velocity, b.velocity, c.velocity];
    incoming.sort_by(f64::total_cmp);
    Some(InState {
        incoming,
        centre: (a.velocity + b.velocity + c.velocity) / 3.0,
        gaps,
        rates,
    })
}

/// What the scene does after an accepted step.
enum Next {
    Integrate,
    Jump(f64),
    Scattered,
    Recombined { pair: usize },
}

/// Where the scene stands after an accepted step of size `step` ([`Next`]).
#[inline(always)]
fn classify<P: PairPotential>(
    potential: P,
    gaps: &[f64; 2],
    rates: &[f64; 2],
    epsilon: f64,
    step: f64,
    free_flight: bool,
) -> Next {
    if tail_strength(potential, gaps, rates) <= epsilon {
        if rates[0] > 0.0 && rates[1] > 0.0 {
            return Next::Scattered;
        }
        let flight = free_flight_time(potential, gaps, rates, epsilon);
        if free_flight && flight > step && flight.is_finite() {
            return Next::Jump(flight);
        }
    }
    if potential.well_depth() > 0.0
        && let Some(pair) = recombined_pair(potential, gaps, rates, epsilon)
    {
        return Next::Recombined { pair };
    }
    Next::Integrate
}

/// A neighbour pair `k` (0: `ab`, 1: `bc`) with negative internal energy
/// `r^2/4 + U(g)` whose third particle recedes from the pair's centre and no
/// longer feels it (`|U_3a| + |U_3b| <= epsilon s^2`, `s` the receding speed).
fn recombined_pair<P: PairPotential>(
    potential: P,
    gaps: &[f64; 2],
    rates: &[f64; 2],
    epsilon: f64,
) -> Option<usize> {
    (0..2).find(|&k| {
        let other = 1 - k;
        let internal = 0.25 * rates[k] * rates[k] + potential.energy(gaps[k]);
        let receding = rates[other] + 0.5 * rates[k];
        let coupling =
            potential.energy(gaps[other]).abs() + potential.energy(gaps[0] + gaps[1]).abs();
        internal < 0.0 && receding > 0.0 && coupling <= epsilon * receding * receding
    })
}

/// Outgoing velocities when pair `k` is bound: both members carry the pair's
/// centre-of-mass velocity, the free particle gets its first-order tail impulse.
fn recombined_velocities<P: PairPotential>(
    potential: P,
    centre: f64,
    gaps: &[f64; 2],
    rates: &[f64; 2],
    pair: usize,
) -> [f64; 3] {
    let other = 1 - pair;
    let receding = rates[other] + 0.5 * rates[pair];
    let impulse = (potential.energy(gaps[other]) + potential.energy(gaps[0] + gaps[1])) / receding;
    let v = velocities(centre, rates);
    let free = if pair == 0 { 2 } else { 0 };
    let sign = if pair == 0 { 1.0 } else { -1.0 };
    let pair_velocity = (3.0 * centre - v[free]) / 2.0 - 0.5 * sign * impulse;
    let mut out = [pair_velocity; 3];
    out[free] = v[free] + sign * impulse;
    out
}

/// Relative-motion energy (kinetic plus all three pair energies).
fn relative_energy<P: PairPotential>(
    potential: P,
    centre: f64,
    gaps: &[f64; 2],
    rates: &[f64; 2],
) -> f64 {
    relative_kinetic_energy(&velocities(centre, rates))
        + pairs(gaps, rates)
            .into_iter()
            .map(|(gap, _)| potential.energy(gap))
            .sum::<f64>()
}

/// A moment of a scene: the gaps `x_b - x_a`, `x_c - x_b`, their rates and the
/// centre-of-mass velocity (scaled units), for scenes that do not start as
/// three free particles (a bound pair hit by an atom).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneState {
    /// Gaps `x_b - x_a`, `x_c - x_b`, `l`.
    pub gaps: [f64; 2],
    /// Gap rates, `v_th`.
    pub rates: [f64; 2],
    /// Centre-of-mass velocity, `v_th`.
    pub centre: f64,
}

/// Integrates scenes from `states` until their outcomes are final, as [`collide`] does from
/// the asymptotic-in lines, several at a time on interleaved steps as [`collide_all`] does, in
/// the order of `states` (generic: callers that draw states with the concrete potential
/// dispatch once). `incoming` of each result holds the particle velocities at its state, and
/// the energy error is measured against its relative-motion energy (kinetic plus potential).
/// The caller places any free particle where it no longer feels the others: its tail is not
/// corrected at the start.
pub fn collide_all_from<P: PairPotential>(
    potential: P,
    settings: &EngineSettings,
    states: &[SceneState],
) -> Vec<Collision> {
    let starts = states.iter().enumerate().map(|(index, state)| {
        let SceneState {
            gaps,
            rates,
            centre,
        } = *state;
        let mut incoming = velocities(centre, &rates);
        incoming.sort_by(f64::total_cmp);
        let start = InState {
            incoming,
            centre,
            gaps,
            rates,
        };
        (
            index,
            start,
            relative_energy(potential, centre, &gaps, &rates),
        )
    });
    in_batch_order(drive_scenes(potential, settings, starts.collect()))
}

/// Integrates scenes from their start states (each with its index and relative-motion energy)
/// to their ends with the settings' method, [`SCENE_LANES`] at a time: the collisions with their
/// indices, in the order they end.
fn drive_scenes<P: PairPotential>(
    potential: P,
    settings: &EngineSettings,
    starts: Vec<(usize, InState, f64)>,
) -> Vec<(usize, Collision)> {
    match settings.method {
        Method::Dopri5 => drive_scenes_with::<P, Dopri5>(potential, settings, starts),
        Method::Dop853 => drive_scenes_with::<P, Dop853>(potential, settings, starts),
        Method::Dprkn12 => drive_scenes_with::<P, Dprkn12>(potential, settings, starts),
    }
}

/// [`drive_scenes`] with integrator `I`.
fn drive_scenes_with<P: PairPotential, I: Integrator>(
    potential: P,
    settings: &EngineSettings,
    starts: Vec<(usize, InState, f64)>,
) -> Vec<(usize, Collision)> {
    let span = Span {
        duration: f64::INFINITY,
        max_attempts: u64::from(settings.max_steps),
    };
    let mut collisions = Vec::with_capacity(starts.len());
    let queue = starts.into_iter().map(|(index, start, energy_in)| {
        SceneLane::new(potential, settings, index, start, energy_in)
    });
    drive_lanes::<I, _, _, _, SCENE_LANES>(
        &GapAcceleration(potential),
        span,
        queue,
        |lane, drive, _, _| collisions.push((lane.index, lane.collision(drive))),
    );
    collisions
}

/// A scene under way: what it started from and what decides its course.
struct SceneLane<P> {
    /// Position of the scene in its batch.
    index: usize,
    incoming: [f64; 3],
    /// Relative-motion energy at the start.
    energy_in: f64,
    scales: Scales,
    error_scales: SceneErrorScales,
    course: Course<P>,
    /// Free-flight jumps so far.
    jumps: u32,
}

impl<P: PairPotential> SceneLane<P> {
    /// The scene `index` starting at `start` with relative-motion energy `energy_in`, with
    /// its start gaps and rates.
    fn new(
        potential: P,
        settings: &EngineSettings,
        index: usize,
        start: InState,
        energy_in: f64,
    ) -> (SceneLane<P>, [f64; 2], [f64; 2]) {
        let InState {
            incoming,
            centre,
            gaps,
            rates,
        } = start;
        let scales = Scales {
            speed: (incoming[2] - incoming[0]).max((4.0 * potential.well_depth()).sqrt()),
            well_depth: potential.well_depth(),
        };
        let lane = SceneLane {
            index,
            incoming,
            energy_in,
            scales,
            error_scales: SceneErrorScales {
                tolerance: settings.tolerance,
                rate_scale: [settings.tolerance * scales.speed; 2],
            },
            course: Course {
                potential,
                epsilon: settings.tail_level(),
                free_flight: settings.free_flight,
                centre,
            },
            jumps: 0,
        };
        (lane, gaps, rates)
    }

    /// The collision of this scene, whose drive ended as `drive`.
    fn collision(self, drive: Drive<End>) -> Collision {
        let Drive { ending, work } = drive;
        let counters = Counters::new(work, self.jumps);
        let incoming = self.incoming;
        match ending {
            Ending::Stopped(end) => {
                end.into_collision(incoming, self.energy_in, self.scales, counters)
            }
            Ending::BudgetExhausted => failed(incoming, Outcome::StepBudgetExhausted, counters),
            Ending::Collapse => failed(incoming, Outcome::Breakdown, counters),
            Ending::Elapsed => unreachable!("a scene has no end time"),
        }
    }
}

impl<P> ErrorScales<[f64; 2]> for SceneLane<P> {
    #[inline(always)]
    fn gap_scale(&self, gaps: &[f64; 2]) -> [f64; 2] {
        self.error_scales.gap_scale(gaps)
    }

    #[inline(always)]
    fn rate_scale(&self) -> &[f64; 2] {
        self.error_scales.rate_scale()
    }
}

impl<P: PairPotential> Trajectory<[f64; 2]> for SceneLane<P> {
    type Stop = End;

    #[inline(always)]
    fn after_step(
        &mut self,
        gaps: &mut [f64; 2],
        rates: &mut [f64; 2],
        step: f64,
    ) -> AfterStep<End> {
        let next = self.course.after_step(gaps, rates, step);
        if matches!(next, AfterStep::Moved) {
            self.jumps += 1;
        }
        next
    }
}

/// A scene's error scales: both gaps to `tolerance` times the smallest gap, both rates to
/// `tolerance` times the relative-speed scale (numerics.md: absolute positions can be huge).
struct SceneErrorScales {
    tolerance: f64,
    rate_scale: [f64; 2],
}

impl ErrorScales<[f64; 2]> for SceneErrorScales {
    fn gap_scale(&self, gaps: &[f64; 2]) -> [f64; 2] {
        [self.tolerance * gaps[0].min(gaps[1]); 2]
    }

    fn rate_scale(&self) -> &[f64; 2] {
        &self.rate_scale
    }
}

/// What decides a scene's course between steps: its potential, the tail level `epsilon`
/// at which it starts and stops, whether free flight is jumped, and the centre-of-mass velocity.
struct Course<P> {
    potential: P,
    epsilon: f64,
    free_flight: bool,
    centre: f64,
}

impl<P: PairPotential> Course<P> {
    /// What the scene does after an accepted step of size `step` ([`classify`]): integrate
    /// on, jump across free flight, or end with its asymptotic-out state. Inlined, with
    /// [`classify`], into the driver's step loop: out of line the two calls added 3% to the
    /// instructions of `ternary bench integrators` (cachegrind).
    #[inline(always)]
    fn after_step(&self, gaps: &mut [f64; 2], rates: &mut [f64; 2], step: f64) -> AfterStep<End> {
        let (potential, centre) = (self.potential, self.centre);
        match classify(potential, gaps, rates, self.epsilon, step, self.free_flight) {
            Next::Integrate => AfterStep::Continue,
            Next::Jump(duration) => {
                free_flight(potential, gaps, rates, duration);
                AfterStep::Moved
            }
            Next::Scattered => {
                shift_tails(potential, gaps, rates, Tails::Remove);
                let outgoing = velocities(centre, rates);
                AfterStep::Stop(End {
                    outgoing,
                    outcome: Outcome::Scattered,
                    binding_energy: 0.0,
                    energy: relative_kinetic_energy(&outgoing),
                })
            }
            Next::Recombined { pair } => {
                let mut outgoing = recombined_velocities(potential, centre, gaps, rates, pair);
                outgoing.sort_by(f64::total_cmp);
                AfterStep::Stop(End {
                    outgoing,
                    outcome: Outcome::Recombined,
                    binding_energy: 0.25 * rates[pair] * rates[pair] + potential.energy(gaps[pair]),
                    energy: relative_energy(potential, centre, gaps, rates),
                })
            }
        }
    }
}

/// Scales of a scene: the largest relative speed (asymptotic spread, or the
/// speed gained falling into the well) and the well depth.
#[derive(Clone, Copy, Debug)]
struct Scales {
    speed: f64,
    well_depth: f64,
}

#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    steps: u32,
    rejected_steps: u32,
    jumps: u32,
    evaluations: u32,
}

impl Counters {
    /// The counters of a scene whose drive did `work` and made `jumps` free-flight jumps.
    /// Steps plus rejections are bounded by the `u32` step budget; evaluations, at most 17
    /// per attempt plus one per jump, fit any budget below 2.5e8.
    fn new(work: Work, jumps: u32) -> Counters {
        Counters {
            steps: work.steps as u32,
            rejected_steps: work.rejected as u32,
            jumps,
            evaluations: work.evaluations as u32,
        }
    }
}

/// The asymptotic-out state of a completed scene.
struct End {
    outgoing: [f64; 3],
    outcome: Outcome,
    binding_energy: f64,
    /// Relative-motion energy of the out-state.
    energy: f64,
}

impl End {
    /// The collision that ends so, from `incoming` velocities with relative-motion energy `energy_in`.
    fn into_collision(
        self,
        incoming: [f64; 3],
        energy_in: f64,
        scales: Scales,
        counters: Counters,
    ) -> Collision {
        let momentum = |v: &[f64; 3]| v.iter().sum::<f64>();
        Collision {
            incoming,
            outgoing: self.outgoing,
            outcome: self.outcome,
            binding_energy: self.binding_energy,
            energy_error: (self.energy - energy_in) / (energy_in.abs() + scales.well_depth),
            momentum_error: (momentum(&self.outgoing) - momentum(&incoming)).abs() / scales.speed,
            steps: counters.steps,
            rejected_steps: counters.rejected_steps,
            jumps: counters.jumps,
            evaluations: counters.evaluations,
        }
    }
}

fn failed(incoming: [f64; 3], outcome: Outcome, counters: Counters) -> Collision {
    Collision {
        incoming,
        outgoing: [f64::NAN; 3],
        outcome,
        binding_energy: 0.0,
        energy_error: f64::NAN,
        momentum_error: f64::NAN,
        steps: counters.steps,
        rejected_steps: counters.rejected_steps,
        jumps: counters.jumps,
        evaluations: counters.evaluations,
    }
}
