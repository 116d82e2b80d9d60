//! Cluster stepping of a dilute ring (numerics.md, "Ring MD at low density"):
//! only what interacts is integrated.
//!
//! A gap shorter than the cutoff `r_c` (where the pair energy falls below the
//! tail level, `U(r_c) = epsilon`) bonds its two particles; runs of bonded
//! particles are clusters. Time advances in macro steps: during one, every
//! cluster is integrated on its own adaptive DPRKN12 steps (in its internal
//! gap coordinates, its centre of mass moving freely) and every other particle
//! flies freely and exactly. A macro step is as long as no unbonded gap can
//! close below `r_c / 2` even at the largest speeds its two ends can reach
//! (a singleton's own speed; a cluster member's centre-of-mass speed plus
//! `sqrt(2 E_rel)`), so forces neglected between clusters stay below
//! `U(r_c / 2)`; at its end the clusters are formed anew.
//!
//! Each particle also carries a velocity label, so that a velocity can be
//! followed through collisions (the tagged-velocity estimator). Particles
//! whose gap is within collision range (pair energy above `COLLISION_LEVEL`)
//! form a collision group, checked after every integration step; when no
//! gap of a group is within range any more, its labels pass from the sorted
//! incoming velocities (on joining) to the sorted outgoing ones — the
//! self/bath matching of the collision kernel, so a binary collision swaps
//! two labels with their velocities and a three-body collision gives each
//! label the kernel's kick. (Two rejected rules, measured on the published
//! ring: matching over everything that shared a cluster mixed unrelated
//! velocities and shrank large kicks; exchanging labels where neighbouring
//! velocities cross follows a three-body collision's velocity paths, not the
//! kernel's matching, and gave kicks of 0.46 v_th.)
//!
//! Potentials with a well (Lennard-Jones): the speed bound counts the depth
//! of every pair of a cluster as kinetic energy it may gain, and a bound
//! pair is a cluster that never dissolves; its collision group stays open, so
//! its labels carry the velocities they had on binding until it breaks up.
//! An isolated bound pair is periodic: a macro step skips its whole periods
//! exactly ([`bound_period`]) and integrates only the remainder.

use std::f64::consts::PI;

use super::potential::PairPotential;
use super::ring::{
    Reach, RingError, RingForces, RingState, RingWork, advance, bound_pairs, ring_velocities,
};
use crate::integrate::{Acceleration, StackVector, Vector};

/// Unbonded gaps are kept above this fraction of the cutoff.
const CLOSEST_FRACTION: f64 = 0.5;

/// Pairs bond below the separation where their energy falls to this multiple
/// of the tolerance (kT). Measured (`ternary bench md`, N = 161 to 640 ns):
/// at 1 the forces neglected between clusters dominate the energy error
/// (1.6e-7 at tolerance 1e-10), at 1e-2 it is 1.1e-9, at 1e-4 2.4e-11, below
/// whole-ring stepping's 3.2e-10, at 1.5x the cost of 1.
const TAIL_LEVEL_PER_TOLERANCE: f64 = 1e-4;

/// Forces inside one cluster: pairs at most `reach` apart around the ring
/// (`d <= reach` along the run, or `N - d <= reach` the other way round,
/// which matters on rings of a few particles only).
struct ClusterForces<'a, P> {
    forces: &'a RingForces<P>,
    reach: usize,
    particles: usize,
}

impl<P> ClusterForces<'_, P> {
    /// Whether members `d` apart along the run interact.
    fn interacts(&self, d: usize) -> bool {
        d <= self.reach || self.particles - d <= self.reach
    }

    /// Interacting pairs in a run of `m` (at most `reach` apart along it).
    fn pairs(&self, m: usize) -> usize {
        (1..=self.reach.min(m - 1)).map(|d| m - d).sum()
    }

    /// One past the last member of a run of `m` that member `i` may interact
    /// with: `i + reach`, unless the run wraps nearly around the ring.
    fn last_partner(&self, i: usize, m: usize) -> usize {
        if m + self.reach >= self.particles {
            m
        } else {
            m.min(i + self.reach + 1)
        }
    }
}

impl<P: PairPotential> ClusterForces<'_, P> {
    /// Calls `visit(i, j, arc)` for every interacting pair of a run with
    /// internal gaps `gaps`, member `j` ahead of member `i` by `arc`.
    fn for_each_pair(&self, gaps: &[f64], mut visit: impl FnMut(usize, usize, f64)) {
        let m = gaps.len() + 1;
        for i in 0..m {
            let mut arc = 0.0;
            for j in i + 1..self.last_partner(i, m) {
                arc += gaps[j - 1];
                if self.interacts(j - i) {
                    visit(i, j, arc);
                }
            }
        }
    }

    /// Particle accelerations of the run with internal gaps `gaps` into `out`.
    fn particle_accelerations(&self, gaps: &[f64], out: &mut [f64]) {
        self.for_each_pair(gaps, |i, j, arc| {
            let push = self.forces.push(arc);
            out[i] -= push;
            out[j] += push;
        });
    }

    /// Potential energy of the pairs inside the run.
    fn potential_energy(&self, gaps: &[f64]) -> f64 {
        let mut energy = 0.0;
        self.for_each_pair(gaps, |_, _, arc| {
            energy += self.forces.potential.energy(self.forces.chord(arc));
        });
        energy
    }
}

/// A pair is colliding while its energy exceeds this, kT (a binary collision
/// of relative speed `w` reaches `U = w^2/4`, 2.5e-5 at `w = 0.01 v_th`;
/// velocities on joining are asymptotic to this level).
const COLLISION_LEVEL: f64 = 1e-8;

/// Runs of up to this many particles keep their per-particle values on the stack.
const STACK_PARTICLES: usize = 16;

/// `m` zeroed per-particle slots: the start of `stack` for a run of up to
/// [`STACK_PARTICLES`], else `heap` grown to `m` (allocation only for long runs).
fn per_particle<'a>(
    stack: &'a mut [f64; STACK_PARTICLES],
    heap: &'a mut Vec<f64>,
    m: usize,
) -> &'a mut [f64] {
    if m <= STACK_PARTICLES {
        &mut stack[..m]
    } else {
        heap.resize(m, 0.0);
        heap
    }
}

impl<P: PairPotential, V: Vector> Acceleration<V> for ClusterForces<'_, P> {
    fn acceleration(&self, gaps: &V) -> V {
        let g = gaps.components();
        let (mut stack, mut heap) = ([0.0; STACK_PARTICLES], Vec::new());
        let a = per_particle(&mut stack, &mut heap, g.len() + 1);
        self.particle_accelerations(g, a);
        let mut out = gaps.zeros_like();
        for (k, o) in out.components_mut().iter_mut().enumerate() {
            *o = a[k + 1] - a[k];
        }
        out
    }
}

/// A ring advanced by cluster stepping.
#[derive(Clone, Debug)]
pub struct ClusterRing<P> {
    forces: RingForces<P>,
    reach: usize,
    cutoff: f64,
    /// Pairs closer than this arc (`l`) are colliding: their chord is within
    /// the range beyond which `|U| <= COLLISION_LEVEL`.
    collision_arc: f64,
    tolerance: f64,
    /// `g_k = s_(k+1) - s_k`, the last wrapping around.
    pub gaps: Vec<f64>,
    /// Particle velocities, `v_th`.
    pub velocities: Vec<f64>,
    /// Velocity labels and open collision groups.
    lineages: Lineages,
    /// Integration work of all clusters so far.
    pub work: RingWork,
    /// Macro steps so far.
    pub macro_steps: u64,
    /// Pair-force evaluations so far (the cost that cluster stepping saves).
    pub pair_forces: u64,
}

impl<P: PairPotential> ClusterRing<P> {
    /// A ring of particles at arc positions `positions` (ascending within one
    /// circumference) with velocities `velocities`, forces to `reach`
    /// neighbours, DPRKN12 at `tolerance`, and bonds below the separation
    /// where the pair energy falls to `TAIL_LEVEL_PER_TOLERANCE * tolerance`.
    pub fn new(
        forces: RingForces<P>,
        positions: &[f64],
        velocities: &[f64],
        tolerance: f64,
    ) -> ClusterRing<P> {
        let tail_level = TAIL_LEVEL_PER_TOLERANCE * tolerance;
        let reach = match forces.reach {
            Reach::Neighbours(k) => k,
            Reach::All => positions.len() - 1,
        };
        let state = RingState::new(positions, velocities, forces.circumference);
        ClusterRing {
            cutoff: forces.potential.range(tail_level),
            collision_arc: forces.arc_within(forces.potential.range(COLLISION_LEVEL)),
            forces,
            reach,
            tolerance,
            gaps: state.gaps,
            velocities: velocities.to_vec(),
            lineages: Lineages::new(velocities),
            work: RingWork::default(),
            macro_steps: 0,
            pair_forces: 0,
        }
    }

    /// Bonding separation `r_c`, `l`.
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    /// Gaps shorter than this arc (`l`) are within collision range.
    pub fn collision_arc(&self) -> f64 {
        self.collision_arc
    }

    /// Total energy with the forces' reach, `kT`.
    pub fn energy(&self) -> f64 {
        let kinetic: f64 = self.velocities.iter().map(|u| 0.5 * u * u).sum();
        kinetic + self.forces.potential_energy(&self.gaps)
    }

    /// Neighbour pairs bound now ([`bound_pairs`]).
    pub fn bound_pairs(&self) -> usize {
        bound_pairs(&self.forces, &self.gaps, &self.velocities)
    }

    /// Runs of bonded particles (two or more members, ring order), or `None`
    /// when every gap is bonded (the whole ring is one cluster).
    fn clusters(&self) -> Option<Vec<Vec<usize>>> {
        let n = self.gaps.len();
        let free = (0..n).find(|&k| self.gaps[k] >= self.cutoff)?;
        let mut runs = Vec::new();
        let mut current = Vec::new();
        for step in 1..=n {
            let particle = (free + step) % n;
            current.push(particle);
            if self.gaps[particle] >= self.cutoff {
                if current.len() > 1 {
                    runs.push(std::mem::take(&mut current));
                } else {
                    current.clear();
                }
            }
        }
        Some(runs)
    }

    /// Internal gaps of a run.
    fn internal_gaps(&self, run: &[usize]) -> Vec<f64> {
        run[..run.len() - 1].iter().map(|&p| self.gaps[p]).collect()
    }

    /// Speed bounds `[lo, hi]` of every particle over the next macro step.
    fn speed_bounds(&self, runs: &[Vec<usize>], cluster: &ClusterForces<'_, P>) -> Vec<[f64; 2]> {
        let mut bounds: Vec<[f64; 2]> = self.velocities.iter().map(|&u| [u, u]).collect();
        for run in runs {
            let m = run.len() as f64;
            let centre = run.iter().map(|&p| self.velocities[p]).sum::<f64>() / m;
            let relative: f64 = run
                .iter()
                .map(|&p| 0.5 * (self.velocities[p] - centre).powi(2))
                .sum();
            // Kinetic energy of relative motion is at most the relative
            // energy less the lowest potential energy the run can reach.
            let floor = -self.forces.potential.well_depth() * cluster.pairs(run.len()) as f64;
            let energy = relative + cluster.potential_energy(&self.internal_gaps(run)) - floor;
            // Rounding can leave a run at rest in its well a hair below zero.
            let spread = (2.0 * energy.max(0.0)).sqrt();
            for &p in run {
                bounds[p] = [centre - spread, centre + spread];
            }
        }
        bounds
    }

    /// Advances the ring by `duration`.
    pub fn advance(&mut self, duration: f64, max_steps: u64) -> Result<(), RingError> {
        let mut elapsed = 0.0;
        while elapsed < duration {
            let remaining = duration - elapsed;
            let step = match self.clusters() {
                Some(runs) => self.macro_step(&runs, remaining, max_steps)?,
                None => self.whole_ring(remaining, max_steps)?,
            };
            self.macro_steps += 1;
            elapsed = if step == remaining {
                duration
            } else {
                elapsed + step
            };
        }
        Ok(())
    }

    /// Integrates the whole ring as one cluster for at most `limit`: the time
    /// for the fastest pair to move a cutoff apart, after which the clusters
    /// are formed anew.
    fn whole_ring(&mut self, limit: f64, max_steps: u64) -> Result<f64, RingError> {
        let fastest = self.velocities.iter().fold(0.0, |m: f64, u| m.max(u.abs()));
        let duration = limit.min(self.cutoff / (2.0 * fastest).max(f64::MIN_POSITIVE));
        let mut state = RingState {
            gaps: self.gaps.clone(),
            rates: (0..self.gaps.len())
                .map(|k| self.velocities[(k + 1) % self.gaps.len()] - self.velocities[k])
                .collect(),
            momentum: self.velocities.iter().sum(),
        };
        let n = self.gaps.len();
        let collision_arc = self.collision_arc;
        let momentum = state.momentum;
        let members: Vec<usize> = (0..n).collect();
        let lineages = &mut self.lineages;
        let work = advance(
            &self.forces,
            &mut state.gaps,
            &mut state.rates,
            duration,
            self.tolerance,
            max_steps,
            |gaps, rates| {
                let velocities = ring_velocities(rates, momentum);
                lineages.observe(&members, &velocities, |k| gaps[k] < collision_arc);
            },
        )?;
        self.add_work(work, n * self.reach);
        self.velocities = state.velocities();
        self.gaps = state.gaps;
        Ok(duration)
    }

    fn add_work(&mut self, work: RingWork, pairs: usize) {
        self.pair_forces += work.evaluations * pairs as u64;
        self.work.steps += work.steps;
        self.work.rejected += work.rejected;
        self.work.evaluations += work.evaluations;
    }

    /// One macro step of at most `limit`; returns its length.
    fn macro_step(
        &mut self,
        runs: &[Vec<usize>],
        limit: f64,
        max_steps: u64,
    ) -> Result<f64, RingError> {
        let forces = self.forces;
        let cluster = ClusterForces {
            forces: &forces,
            reach: self.reach,
            particles: self.gaps.len(),
        };
        let n = self.gaps.len();
        let bounds = self.speed_bounds(runs, &cluster);
        let mut internal = vec![false; n];
        for run in runs {
            run[..run.len() - 1]
                .iter()
                .for_each(|&p| internal[p] = true);
        }
        let duration = (0..n)
            .filter(|&k| !internal[k])
            .map(|k| {
                let closing = bounds[k][1] - bounds[(k + 1) % n][0];
                if closing > 0.0 {
                    (self.gaps[k] - CLOSEST_FRACTION * self.cutoff) / closing
                } else {
                    f64::INFINITY
                }
            })
            .fold(limit, f64::min);
        let mut displacement: Vec<f64> = self.velocities.iter().map(|u| u * duration).collect();
        for run in runs {
            self.integrate_run(&cluster, run, duration, max_steps, &mut displacement)?;
        }
        for k in (0..n).filter(|&k| !internal[k]) {
            self.gaps[k] += displacement[(k + 1) % n] - displacement[k];
        }
        Ok(duration)
    }

    /// Integrates one run for `duration`, writing its internal gaps, its
    /// velocities and its members' displacements.
    fn integrate_run(
        &mut self,
        cluster: &ClusterForces<'_, P>,
        run: &[usize],
        duration: f64,
        max_steps: u64,
        displacement: &mut [f64],
    ) -> Result<(), RingError> {
        let m = run.len();
        let before = self.internal_gaps(run);
        let rates: Vec<f64> = run
            .windows(2)
            .map(|pair| self.velocities[pair[1]] - self.velocities[pair[0]])
            .collect();
        let centre = run.iter().map(|&p| self.velocities[p]).sum::<f64>() / m as f64;
        // An isolated bound pair is periodic: whole periods are skipped exactly.
        let period = if m == 2 {
            bound_period(&self.forces, before[0], rates[0], self.cutoff)
        } else {
            None
        };
        let integrated = match period {
            Some(period) if period < duration => duration - (duration / period).floor() * period,
            _ => duration,
        };
        let job = RunJob {
            run,
            collision_arc: self.collision_arc,
            centre,
            duration: integrated,
            tolerance: self.tolerance,
            max_steps,
        };
        let lineages = &mut self.lineages;
        let (after, rates, work) = match m - 1 {
            1 => job.integrate(cluster, lineages, fixed::<1>(&before), fixed::<1>(&rates))?,
            2 => job.integrate(cluster, lineages, fixed::<2>(&before), fixed::<2>(&rates))?,
            3 => job.integrate(cluster, lineages, fixed::<3>(&before), fixed::<3>(&rates))?,
            4 => job.integrate(cluster, lineages, fixed::<4>(&before), fixed::<4>(&rates))?,
            _ => match (
                ClusterState::from_slice(&before),
                ClusterState::from_slice(&rates),
            ) {
                (Some(g), Some(w)) => job.integrate(cluster, lineages, g, w)?,
                _ => job.integrate(cluster, lineages, before.clone(), rates)?,
            },
        };
        self.add_work(work, cluster.pairs(m));
        let offsets_before = centred_partial_sums(&before);
        let offsets_after = centred_partial_sums(&after);
        let velocity_offsets = centred_partial_sums(&rates);
        for (j, &p) in run.iter().enumerate() {
            displacement[p] = centre * duration + offsets_after[j] - offsets_before[j];
            self.velocities[p] = centre + velocity_offsets[j];
        }
        for (&p, g) in run.iter().zip(after) {
            self.gaps[p] = g;
        }
        Ok(())
    }

    /// The asymptotic velocity each label carries now: the outgoing velocity
    /// of its last finished collision, or for a particle still colliding its
    /// velocity on joining (a collision counts once it is over).
    pub fn label_velocities(&self) -> Vec<f64> {
        let lineages = &self.lineages;
        let mut carried = vec![0.0; self.velocities.len()];
        for (p, &label) in lineages.labels.iter().enumerate() {
            carried[label] = if lineages.group[p] == 0 {
                self.velocities[p]
            } else {
                lineages.incoming[p]
            };
        }
        carried
    }
}

/// Nodes of the trapezoid rule for the period of a bound pair.
const PERIOD_NODES: usize = 256;

/// Period of the relative motion of an isolated bound pair at arc separation
/// `gap` with gap rate `rate`, in `l / v_th`; `None` unless the pair is bound
/// (`E = w^2/4 + V(g) < 0`, `V(g) = U(chord(g))`, reduced mass 1/2) with its
/// outer turning point within `limit`. `T = int_(g1)^(g2) dg / sqrt(E - V)`
/// with `g = c + h sin(phi)` between the turning points: the integrand
/// `h |cos phi| / sqrt(E - V)` is smooth and periodic in `phi`, so the
/// trapezoid rule converges exponentially (256 nodes: ~1e-14 relative).
pub fn bound_period<P: PairPotential>(
    forces: &RingForces<P>,
    gap: f64,
    rate: f64,
    limit: f64,
) -> Option<f64> {
    let potential = |g: f64| forces.potential.energy(forces.chord(g));
    let energy = 0.25 * rate * rate + potential(gap);
    let bound = energy < 0.0;
    if !bound {
        return None;
    }
    let above = |g: f64| potential(g) > energy;
    let mut low = gap;
    while !above(low) {
        low *= 0.5;
        if low < f64::MIN_POSITIVE {
            return None;
        }
    }
    let mut high = gap.max(forces.potential.range(-0.5 * energy));
    while !above(high) {
        high *= 2.0;
        if high > limit {
            return None;
        }
    }
    let inner = turning_point(&above, low, gap);
    let outer = turning_point(&above, high, gap);
    if outer > limit {
        return None;
    }
    let (centre, half) = (0.5 * (inner + outer), 0.5 * (outer - inner));
    let step = 2.0 * PI / PERIOD_NODES as f64;
    let sum: f64 = (0..PERIOD_NODES)
        .map(|j| {
            let phi = step * (j as f64 + 0.5);
            let depth = energy - potential(centre + half * libm::sin(phi));
            half * libm::cos(phi).abs() / depth.max(f64::MIN_POSITIVE).sqrt()
        })
        .sum();
    Some(0.5 * step * sum)
}

/// Bisection between `outside` (`above`) and `inside` (not `above`) to the
/// last representable separation.
fn turning_point(above: &impl Fn(f64) -> bool, mut outside: f64, mut inside: f64) -> f64 {
    loop {
        let middle = 0.5 * (outside + inside);
        if middle == outside || middle == inside {
            return inside;
        }
        if above(middle) {
            outside = middle;
        } else {
            inside = middle;
        }
    }
}

/// `x_j - mean(x)` for the partial sums `x_j = sum_(k<j) values_k`, `j = 0..=len`.
fn centred_partial_sums(values: &[f64]) -> Vec<f64> {
    let mut sums = vec![0.0; values.len() + 1];
    centred_partial_sums_into(values, &mut sums);
    sums
}

/// [`centred_partial_sums`] into `out` (one longer than `values`), without allocating.
fn centred_partial_sums_into(values: &[f64], out: &mut [f64]) {
    let mut sum = 0.0;
    out[0] = 0.0;
    for (slot, v) in out[1..].iter_mut().zip(values) {
        sum += v;
        *slot = sum;
    }
    let mean = out.iter().sum::<f64>() / out.len() as f64;
    for slot in out.iter_mut() {
        *slot -= mean;
    }
}

/// One run's integration over a macro step.
struct RunJob<'a> {
    run: &'a [usize],
    collision_arc: f64,
    centre: f64,
    duration: f64,
    tolerance: f64,
    max_steps: u64,
}

impl RunJob<'_> {
    /// [`advance`] of the run's internal gaps `g` and rates `w` (stack arrays
    /// for small runs), following its collisions in `lineages`.
    fn integrate<P: PairPotential, V: Vector>(
        &self,
        cluster: &ClusterForces<'_, P>,
        lineages: &mut Lineages,
        mut g: V,
        mut w: V,
    ) -> Result<(Vec<f64>, Vec<f64>, RingWork), RingError> {
        let work = advance(
            cluster,
            &mut g,
            &mut w,
            self.duration,
            self.tolerance,
            self.max_steps,
            |gaps, rates| {
                let (mut stack, mut heap) = ([0.0; STACK_PARTICLES], Vec::new());
                let velocities = per_particle(&mut stack, &mut heap, rates.len() + 1);
                run_velocities(rates, self.centre, velocities);
                lineages.observe(self.run, velocities, |k| gaps[k] < self.collision_arc);
            },
        )?;
        Ok((g.components().to_vec(), w.components().to_vec(), work))
    }
}

/// Gaps or rates of a run of 6 to 17 particles, on the stack. In a Lennard-Jones ring at
/// `rho l = 0.02` (theta = 1, tolerance 1e-6) runs of up to 17 particles do 99% of the
/// pair-force work, those of up to 5 (the arrays) only 38% (docs/benchmarks.md).
type ClusterState = StackVector<16>;

/// The first `D` values as a stack array.
fn fixed<const D: usize>(values: &[f64]) -> [f64; D] {
    std::array::from_fn(|k| values[k])
}

/// Velocities of a run from its gap rates and centre-of-mass velocity, into
/// `out` (one more than the rates), without allocating (it runs after every
/// step of every run).
fn run_velocities(rates: &[f64], centre: f64, out: &mut [f64]) {
    centred_partial_sums_into(rates, out);
    for slot in out.iter_mut() {
        *slot += centre;
    }
}

/// Velocity labels and the collision groups that pass them on.
#[derive(Clone, Debug)]
struct Lineages {
    /// The label each particle carries.
    labels: Vec<usize>,
    /// Open collision group of each particle (0: none).
    group: Vec<u32>,
    /// Velocity of each particle on joining its group.
    incoming: Vec<f64>,
    /// Velocity of each particle when last seen (constant while it flies freely).
    latest: Vec<f64>,
    next_group: u32,
}

impl Lineages {
    fn new(velocities: &[f64]) -> Lineages {
        Lineages {
            labels: (0..velocities.len()).collect(),
            group: vec![0; velocities.len()],
            incoming: velocities.to_vec(),
            latest: velocities.to_vec(),
            next_group: 0,
        }
    }

    /// After a step of the chain `members` (ring order) with `velocities`:
    /// joins colliding neighbours (`touching(k)` for members `k`, `k + 1`)
    /// into groups and closes the groups of the chain no longer colliding.
    fn observe(&mut self, members: &[usize], velocities: &[f64], touching: impl Fn(usize) -> bool) {
        for (&p, &v) in members.iter().zip(velocities) {
            self.latest[p] = v;
        }
        let mut active = Vec::new();
        for k in 0..members.len() - 1 {
            if !touching(k) {
                continue;
            }
            let (a, b) = (members[k], members[k + 1]);
            for (p, v) in [(a, velocities[k]), (b, velocities[k + 1])] {
                if self.group[p] == 0 {
                    self.incoming[p] = v;
                }
            }
            let id = match (self.group[a], self.group[b]) {
                (0, 0) => {
                    self.next_group += 1;
                    self.next_group
                }
                (0, g) | (g, 0) => g,
                (g, h) => {
                    let (keep, drop) = (g.min(h), g.max(h));
                    for &p in members {
                        if self.group[p] == drop {
                            self.group[p] = keep;
                        }
                    }
                    keep
                }
            };
            self.group[a] = id;
            self.group[b] = id;
            active.push(id);
        }
        let mut open: Vec<u32> = members
            .iter()
            .map(|&p| self.group[p])
            .filter(|&g| g != 0)
            .collect();
        open.sort_unstable();
        open.dedup();
        for id in open.into_iter().filter(|id| !active.contains(id)) {
            self.close(id);
        }
    }

    /// Passes the labels of finished group `id` (all its members, also those
    /// that have left the chain and fly freely) from the sorted incoming to
    /// the sorted outgoing velocities.
    fn close(&mut self, id: u32) {
        let members: Vec<usize> = (0..self.group.len())
            .filter(|&p| self.group[p] == id)
            .collect();
        let mut incoming: Vec<(f64, usize)> = members
            .iter()
            .map(|&p| (self.incoming[p], self.labels[p]))
            .collect();
        incoming.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut outgoing = members;
        outgoing.sort_by(|&a, &b| self.latest[a].total_cmp(&self.latest[b]));
        for (p, (_, label)) in outgoing.into_iter().zip(incoming) {
            self.labels[p] = label;
            self.group[p] = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::potential::{InverseIntegerPower, LennardJones};
    use crate::physics::ring::{evolve, thermal_start};
    use rand::SeedableRng;

    /// Twelve particles on a ring of 24000 l (rho l = 5e-4, as in the
    /// published rings), bonding below 464 l (tail level 1e-16): binary and
    /// occasional three-body encounters.
    fn dilute_ring() -> (Vec<f64>, Vec<f64>, f64) {
        let positions: Vec<f64> = (0..12)
            .map(|k| 2000.0 * k as f64 + 70.0 * ((k * 7) % 5) as f64)
            .collect();
        let velocities = vec![
            1.3, -0.7, 0.4, -1.9, 0.8, 0.35, -0.2, 1.1, -1.2, 0.05, 0.6, -0.9,
        ];
        (positions, velocities, 24000.0)
    }

    fn forces(circumference: f64) -> RingForces<InverseIntegerPower<6>> {
        RingForces {
            potential: InverseIntegerPower::<6>,
            circumference,
            reach: Reach::Neighbours(3),
        }
    }

    /// Cluster stepping follows the trajectory of whole-ring stepping for
    /// `duration`: its velocities are as close to a whole-ring reference at a
    /// 10x tighter tolerance as whole-ring stepping's own (within 3x); its
    /// energy drifts no more than whole-ring stepping's (within 2x, above a
    /// rounding floor of 1e-13) and momentum is exact. Returns the ring and
    /// its relative energy drift.
    fn assert_cluster_matches_whole_ring<P: PairPotential>(
        forces: RingForces<P>,
        positions: &[f64],
        velocities: &[f64],
        duration: f64,
    ) -> (ClusterRing<P>, f64) {
        let circumference = forces.circumference;
        let mut clusters = ClusterRing::new(forces, positions, velocities, 1e-12);
        let start = RingState::new(positions, velocities, circumference);
        let (mut whole, mut reference) = (start.clone(), start);
        let energy = clusters.energy();
        clusters.advance(duration, 10_000_000).unwrap();
        evolve(&forces, &mut whole, duration, 1e-12, 100_000_000).unwrap();
        evolve(&forces, &mut reference, duration, 1e-13, 100_000_000).unwrap();
        let distance = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        let exact = reference.velocities();
        let (own, cluster) = (
            distance(&whole.velocities(), &exact),
            distance(&clusters.velocities, &exact),
        );
        assert!(
            cluster <= 3.0 * own,
            "cluster {cluster:e} vs whole ring {own:e}"
        );
        let drift = (clusters.energy() - energy).abs() / energy;
        let whole_drift = (whole.energy(&forces) - energy).abs() / energy;
        assert!(
            drift <= 2.0 * whole_drift + 1e-13,
            "energy drift {drift:e}, whole ring {whole_drift:e}"
        );
        let momentum: f64 = velocities.iter().sum();
        assert!((clusters.velocities.iter().sum::<f64>() - momentum).abs() < 1e-12);
        assert!(clusters.macro_steps > 10, "{}", clusters.macro_steps);
        (clusters, drift)
    }

    /// Through many encounters of a dilute inverse-power-law ring, with the
    /// energy conserved to 1e-12.
    #[test]
    fn cluster_stepping_agrees_with_whole_ring_stepping() {
        let (positions, velocities, circumference) = dilute_ring();
        let (_, drift) = assert_cluster_matches_whole_ring(
            forces(circumference),
            &positions,
            &velocities,
            4000.0,
        );
        assert!(drift < 1e-12, "{drift:e}");
    }

    /// On a dilute Lennard-Jones ring (kT = eps/10, rho l = 5e-4) with a
    /// bound pair, a cluster that never dissolves and whose members may gain
    /// the well depth in speed.
    #[test]
    fn cluster_stepping_agrees_with_whole_ring_stepping_with_bound_pairs() {
        let forces = RingForces {
            potential: LennardJones { theta: 0.1 },
            circumference: 24000.0,
            reach: Reach::Neighbours(3),
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let (positions, velocities) = (0..)
            .map(|_| thermal_start(&forces, 12, None, &mut rng, 1).unwrap())
            .find(|(positions, velocities)| {
                let state = RingState::new(positions, velocities, forces.circumference);
                bound_pairs(&forces, &state.gaps, velocities) > 0
            })
            .unwrap();
        let (ring, _) = assert_cluster_matches_whole_ring(forces, &positions, &velocities, 4000.0);
        assert!(
            ring.bound_pairs() > 0,
            "the bound pair broke up: test another start"
        );
    }

    /// A Lennard-Jones pair (theta = 0.1) at `gap` with gap rate `rate` on a
    /// ring too large for its curvature to matter.
    fn lj_pair() -> RingForces<LennardJones> {
        RingForces {
            potential: LennardJones { theta: 0.1 },
            circumference: 1e6,
            reach: Reach::Neighbours(1),
        }
    }

    /// A run of seven members integrates to the same bits with its state on
    /// the stack ([`ClusterState`]) as on the heap, and one too long for the
    /// stack stays on the heap.
    #[test]
    fn a_run_on_the_stack_keeps_the_bits_of_the_heap() {
        let forces = RingForces {
            reach: Reach::Neighbours(3),
            ..lj_pair()
        };
        let cluster = ClusterForces {
            forces: &forces,
            reach: 3,
            particles: 7,
        };
        let gaps = [0.9, 1.3, 0.8, 2.1, 1.1, 0.95];
        let rates = [0.3, -0.7, 0.2, 0.05, -0.4, 0.6];
        fn run<V: Vector>(cluster: &ClusterForces<'_, LennardJones>, mut g: V, mut w: V) -> (V, V) {
            advance(cluster, &mut g, &mut w, 5.0, 1e-10, 1_000_000, |_, _| ()).unwrap();
            (g, w)
        }
        let (heap_gaps, heap_rates) = run(&cluster, gaps.to_vec(), rates.to_vec());
        let stack = |values: &[f64]| ClusterState::from_slice(values).unwrap();
        let (stack_gaps, stack_rates) = run(&cluster, stack(&gaps), stack(&rates));
        let bits = |values: &[f64]| values.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(stack_gaps.components()), bits(&heap_gaps));
        assert_eq!(bits(stack_rates.components()), bits(&heap_rates));
        assert_ne!(bits(&heap_gaps), bits(&gaps), "the run did not move");
        assert!(ClusterState::from_slice(&[0.0; 17]).is_none());
    }

    /// Integrating a bound pair's relative motion for one computed period
    /// returns it to its start (to 1e-9), at small and large amplitude;
    /// unbound pairs have no period.
    #[test]
    fn bound_pair_returns_after_one_period() {
        let forces = lj_pair();
        let cluster = ClusterForces {
            forces: &forces,
            reach: 1,
            particles: 2,
        };
        for (gap, rate) in [(0.77, 0.05), (0.8, 1.0), (0.72, 2.0)] {
            let period = bound_period(&forces, gap, rate, 1e3).unwrap();
            let (mut g, mut w) = ([gap], [rate]);
            advance(
                &cluster,
                &mut g,
                &mut w,
                period,
                1e-14,
                10_000_000,
                |_, _| (),
            )
            .unwrap();
            assert!(
                (g[0] - gap).abs() < 1e-9 && (w[0] - rate).abs() < 1e-9,
                "{g:?} {w:?}"
            );
        }
        assert!(bound_period(&forces, 0.8, 4.0, 1e3).is_none());
    }

    /// An isolated bound pair advanced by cluster stepping (whole periods
    /// skipped) ends where whole-ring stepping, which integrates all ~12000
    /// oscillations, ends: as close to a 10x tighter reference as whole-ring
    /// stepping itself (within 3x), at a small fraction of its steps.
    #[test]
    fn skipping_whole_periods_of_a_bound_pair_keeps_its_trajectory() {
        let forces = RingForces {
            circumference: 20000.0,
            reach: Reach::Neighbours(3),
            ..lj_pair()
        };
        let positions = [0.0, 0.8, 5000.0, 10000.0];
        let velocities = [0.3, 1.3, -0.2, 0.25];
        let mut clusters = ClusterRing::new(forces, &positions, &velocities, 1e-12);
        clusters.advance(3000.0, 10_000_000).unwrap();
        let start = RingState::new(&positions, &velocities, forces.circumference);
        let (mut whole, mut reference) = (start.clone(), start);
        let work = evolve(&forces, &mut whole, 3000.0, 1e-12, 100_000_000).unwrap();
        evolve(&forces, &mut reference, 3000.0, 1e-13, 100_000_000).unwrap();
        let exact = reference.velocities();
        let distance = |a: &[f64]| {
            a.iter()
                .zip(&exact)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        let (own, cluster) = (
            distance(&whole.velocities()),
            distance(&clusters.velocities),
        );
        assert!(
            cluster <= 3.0 * own.max(1e-12),
            "cluster {cluster:e} vs whole ring {own:e}"
        );
        assert!(clusters.bound_pairs() == 1);
        assert!(
            100 * clusters.work.steps < work.steps,
            "{} steps against {}",
            clusters.work.steps,
            work.steps
        );
    }

    /// In binary collisions velocities only swap, so labels carry them
    /// unchanged: with four particles far apart every label keeps its velocity
    /// (to the integration error) through the collisions of a long run.
    #[test]
    fn labels_follow_velocities_through_binary_collisions() {
        let forces = forces(4000.0);
        let velocities = [0.9, -0.6, 0.2, -0.4];
        let positions = [0.0, 1000.0, 2000.0, 3000.0];
        let mut ring = ClusterRing::new(forces, &positions, &velocities, 1e-12);
        ring.advance(5000.0, 1_000_000).unwrap();
        let carried = ring.label_velocities();
        for (a, b) in carried.iter().zip(velocities) {
            assert!((a - b).abs() < 1e-10, "{carried:?}");
        }
        // The particles themselves exchanged velocities.
        assert!(
            ring.velocities
                .iter()
                .zip(velocities)
                .any(|(a, b)| (a - b).abs() > 0.1),
            "{:?}",
            ring.velocities
        );
    }

    /// On the published ring (N = 161, rho l = 7.3e-4) every label carries a
    /// velocity within 0.05 of its start after 2e5 time units: only three-body
    /// kicks (~0.02 v_th, rare at Gamma t ~ 4e-5) change what a label carries,
    /// never the thousands of binary swaps.
    #[test]
    fn labels_survive_a_crowd_of_collisions() {
        let forces = forces(219_171.0);
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let (positions, velocities) =
            thermal_start(&forces, 161, Some(0.0), &mut rng, 100).unwrap();
        let mut ring = ClusterRing::new(forces, &positions, &velocities, 1e-10);
        ring.advance(2e5, 10_000_000).unwrap();
        let carried = ring.label_velocities();
        let wrong: Vec<usize> = (0..carried.len())
            .filter(|&k| (carried[k] - velocities[k]).abs() > 0.05)
            .collect();
        assert!(wrong.is_empty(), "labels {wrong:?} carry other velocities");
        assert!(ring.macro_steps > 1000);
    }
}
