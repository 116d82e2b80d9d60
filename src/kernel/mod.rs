//! The collision kernel `G(u' -> u)` and its moments from integrated scenes
//! (physics.md §3): reweighting one event set to any `u'` and density
//! (Galilean invariance), the +-1 histogram rule, self/bath split by sorted
//! matching, per-replicate sums (their statistics live in `stats`), and the
//! kernel's consistency with relaxation to `f0` ([`equilibrium`]). Pure math:
//! no IO.
//!
//! Units: velocities in `v_th`, `G` in `rho^2 l v_th` per unit velocity, rates
//! of the scaled moments `d<u - u'>/dt`, `d<(u - u')^2>/dt` in `rho^2 l v_th`
//! (physics.md §3: `Gamma = a_n rho^2 l v_th`).

pub mod binding;
pub mod equilibrium;
pub mod fit;
pub mod model;
pub mod segments;
pub mod tail;

use rayon::prelude::*;

use crate::binning::Bins;
use crate::physics::launch::{launch_rate, thermal_density};
use crate::physics::potential::Potential;
use crate::physics::sampling::{OffsetIntegration, SamplingPlan, SceneRecord, Stratum};
use crate::physics::scene::{Collision, EngineSettings, Method, Outcome};
use crate::thresholds::DEFAULT_KICK_FLOOR;

/// One integrated scene as the kernel needs it (special particle's frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// Stratum it was drawn in.
    pub stratum: Stratum,
    /// Randomization (replicate) it belongs to.
    pub randomization: u32,
    /// Index of its launch point within the randomization and stratum.
    pub point: u32,
    /// Node of the offset rule within its launch pair (0 for sampled offsets:
    /// every event with node 0 is one drawn point).
    pub node: u32,
    /// Launch velocity of the first arrival.
    pub u2: f64,
    /// Launch velocity of the second arrival.
    pub u3: f64,
    /// Arrival offset `tau`.
    pub offset: f64,
    /// Proposal density of `(|u2|, |u3|, tau)`.
    pub proposal_density: f64,
    /// Outgoing velocities, ascending; `None` for a failed scene (it still
    /// counts as drawn, contributing zero: failures are reported, never dropped silently).
    pub outgoing: Option<[f64; 3]>,
    /// Internal energy `w^2/4 + U` (`kT`, in `(-D, 0)`) of the bound pair
    /// when a bound pair and a free atom left (three-body recombination,
    /// potentials with a well only), `None` otherwise. Such a scene is no
    /// part of the free-atom kernel `G`, which describes three atoms that
    /// leave free; its channel has its own rate ([`recombination_rates`]).
    pub bound_pair_energy: Option<f64>,
}

/// The `u'` and density an event set is reweighted to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Velocity `u'` of the special particle, `v_th`.
    pub u_prime: f64,
    /// `rho * l`; 0 is the dilute limit.
    pub density: f64,
    /// Observation region length `L` of the literal algorithm, in `l`: at finite
    /// density the delay between launches is weighted by `exp(-r |delay|)`.
    pub launch_length: f64,
    /// Velocity changes at most this large (`v_th`) are the engine's error
    /// floor and count as exactly zero. Without it, scenes at very large
    /// offsets, whose importance weights grow like `tau^2`, would turn
    /// integration noise into rare huge contributions.
    pub kick_floor: f64,
}

impl Target {
    /// The dilute limit at `u'` with the default kick floor
    /// ([`DEFAULT_KICK_FLOOR`]; `L` is then unused).
    pub fn dilute(u_prime: f64) -> Target {
        Target {
            u_prime,
            density: 0.0,
            launch_length: 0.0,
            kick_floor: DEFAULT_KICK_FLOOR,
        }
    }
}

impl Event {
    /// The event of an integrated scene (failed scenes keep no velocities).
    pub fn from_record(record: &SceneRecord) -> Event {
        Event {
            stratum: record.scene.stratum,
            randomization: record.randomization,
            point: record.point,
            node: record.node,
            u2: record.scene.u2,
            u3: record.scene.u3,
            offset: record.scene.offset,
            proposal_density: record.scene.proposal_density,
            outgoing: (!record.collision.outcome.is_failure()).then_some(record.collision.outgoing),
            bound_pair_energy: bound_pair_energy(&record.collision),
        }
    }

    /// Whether a bound pair and a free atom left (three-body recombination).
    pub fn recombined(&self) -> bool {
        self.bound_pair_energy.is_some()
    }
}

/// Internal energy `w^2/4 + U` (`kT`) of the pair `collision` left bound, if
/// it recombined.
pub fn bound_pair_energy(collision: &Collision) -> Option<f64> {
    (collision.outcome == Outcome::Recombined).then_some(collision.binding_energy)
}

/// A scene's contribution seen from `u'`: velocities relative to `u'`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contribution {
    /// Importance weight (units of `rho^2 l v_th` per drawn point).
    pub weight: f64,
    /// Incoming velocities relative to `u'`: the special particle's 0 and the two launches.
    pub incoming: [f64; 3],
    /// Outgoing velocities relative to `u'`, ascending.
    pub outgoing: [f64; 3],
    /// Rank of the special particle among the sorted incoming velocities.
    pub self_rank: usize,
}

impl Contribution {
    /// The special particle's own velocity change (sorted matching).
    pub fn self_kick(&self) -> f64 {
        self.outgoing[self.self_rank]
    }

    /// Incoming velocities in ascending order (matched rank by rank with `outgoing`).
    pub fn sorted_incoming(&self) -> [f64; 3] {
        let mut sorted = self.incoming;
        sorted.sort_by(f64::total_cmp);
        sorted
    }

    /// `w(u2) w(u3)` of the two launches for a special particle at `u_prime`.
    pub fn launch_weight(&self, u_prime: f64) -> f64 {
        launch_weight(self.incoming[1], u_prime) * launch_weight(self.incoming[2], u_prime)
    }
}

/// Launch weight `w(u) = f0(u + u') |u|` of a thermal particle with relative velocity `u`.
fn launch_weight(relative: f64, u_prime: f64) -> f64 {
    thermal_density(relative + u_prime) * relative.abs()
}

/// The contributions of an event as seen from `target`: its [`images`] with
/// their launch weights `w(u2) w(u3)` at `target.u_prime` and, at finite
/// density, the literal algorithm's survival factor `exp(-r |delay|)`.
/// Empty for failed scenes.
pub fn contributions<'a>(
    event: &'a Event,
    target: &Target,
) -> impl Iterator<Item = Contribution> + 'a {
    weighed(event, target, images(event, target.kick_floor))
}

/// `images` of `event` weighed at `target`.
fn weighed<'a>(
    event: &Event,
    target: &Target,
    images: impl ExactSizeIterator<Item = Contribution> + 'a,
) -> impl Iterator<Item = Contribution> + 'a {
    let weigh = Weighing::new(event, target, images.len());
    images.map(move |image| Contribution {
        weight: weigh.weight(&image),
        ..image
    })
}

/// Per replicate, the rate at which the special particle at `target` takes
/// part in a three-body encounter that leaves a bound pair and a free atom
/// (`rho^2 l v_th`): the weights of the recombined scenes' images, which the
/// free-atom kernel leaves out. Zero without a well.
pub fn recombination_rates(events: &[Event], target: &Target, draws: &Draws) -> Vec<f64> {
    recombination_sums(events, target, draws, 1, |sums, _, rate| sums[0] += rate)
        .into_iter()
        .map(|sums| sums[0])
        .collect()
}

/// Per replicate, `slots` sums over the scenes that recombined: `add(sums,
/// E, rate)` adds one scene, of bound-pair internal energy `E` (`kT`) and
/// recombination rate `rate` at `target` (`rho^2 l v_th`: its images'
/// weights over the stratum's draws), into its replicate's `sums` (the
/// rate itself, its share in a bin of `E`, `E` times it). The rates of
/// [`recombination_rates`] split by the bound pair's energy.
pub fn recombination_sums(
    events: &[Event],
    target: &Target,
    draws: &Draws,
    slots: usize,
    add: impl Fn(&mut [f64], f64, f64) + Sync,
) -> Vec<Vec<f64>> {
    per_replicate(
        events,
        draws,
        || vec![0.0; slots],
        |sums, event, scale| {
            let Some(energy) = event.bound_pair_energy else {
                return;
            };
            let images = images_in(event, target.kick_floor, true);
            let rate = weighed(event, target, images)
                .map(|c| c.weight * scale)
                .sum::<f64>();
            add(sums, energy, rate);
        },
    )
}

/// What turns an event's images into contributions at a target: the launch
/// weights at `u'`, the survival factor and the proposal density.
#[derive(Clone, Copy)]
struct Weighing {
    u_prime: f64,
    survival: f64,
    per_image: f64,
}

impl Weighing {
    /// The weighing of `event`'s `count` images at `target`.
    fn new(event: &Event, target: &Target, count: usize) -> Weighing {
        // Dilute targets skip the factor: exp(-0) = 1 exactly.
        let survival = if target.density == 0.0 {
            1.0
        } else {
            let delay = event.offset
                - 0.5 * target.launch_length * (1.0 / event.u3.abs() - 1.0 / event.u2.abs());
            libm::exp(-target.density * launch_rate(target.u_prime) * delay.abs())
        };
        Weighing {
            u_prime: target.u_prime,
            survival,
            per_image: event.proposal_density * count as f64,
        }
    }

    /// Weight of one image, `rho^2 l v_th` per drawn point.
    fn weight(&self, image: &Contribution) -> f64 {
        image.launch_weight(self.u_prime) * self.survival / self.per_image
    }
}

/// Per replicate, the self part of bin `k` of [`histograms`] for `k` off the
/// centre bin (where the special particle's incoming velocity lies): the
/// weights of the contributions whose special particle lands in bin `k`.
/// Only those are weighed: sampled scenes in the histogram's order (the same
/// bits); quadrature nodes when the bin lies in the collisions' core
/// (`|u - u'| >= segments::CORE_KICK` throughout), where the histogram holds
/// exactly their point masses (the same sum in another order). A bin
/// reaching into the tails, where segments spread the nodes' measure, takes
/// the whole histogram.
pub fn self_bin(
    events: &[Event],
    target: &Target,
    bins: &Bins,
    k: usize,
    draws: &Draws,
) -> Vec<f64> {
    debug_assert_ne!(
        k, bins.half_bins,
        "the centre bin also holds the incoming velocity"
    );
    if !takes_point_masses(events, bins, k) {
        return node_histograms(events, target, bins, draws, Parts::SelfOnly)
            .into_iter()
            .map(|h| h.self_part[k])
            .collect();
    }
    per_replicate(
        events,
        draws,
        || 0.0,
        |sum, event, scale| {
            let images = images(event, target.kick_floor);
            let weigh = Weighing::new(event, target, images.len());
            for image in images {
                if bins.index(image.self_kick()) == Some(k) {
                    *sum += weigh.weight(&image) * scale;
                }
            }
        },
    )
}

/// `true` when bin `k` holds its events' point masses: sampled scenes, or
/// quadrature nodes in a bin wholly in the collisions' core (`|u - u'| >=
/// segments::CORE_KICK`); `false` where the tails' measure is spread between nodes.
fn takes_point_masses(events: &[Event], bins: &Bins, k: usize) -> bool {
    let in_core = bins.centre(k).abs() - 0.5 * bins.width >= segments::CORE_KICK;
    in_core || !integrates_offsets(events)
}

/// The events that can feed bin `k` of [`self_bin`] at any target of kick
/// floor `kick_floor`, in their order: where the bin takes point masses
/// (sampled scenes, or a bin in the collisions' core), those with an image
/// whose special particle lands in it (a self kick does not depend on `u'`),
/// so [`self_bin`] of them is the same sum, bit for bit; all events where the
/// bin takes the tails' spread measure. A sweep over `u'` weighs only these.
pub fn self_bin_feeders(events: &[Event], bins: &Bins, k: usize, kick_floor: f64) -> Vec<Event> {
    if !takes_point_masses(events, bins, k) {
        return events.to_vec();
    }
    events
        .iter()
        .filter(|event| {
            images(event, kick_floor).any(|image| bins.index(image.self_kick()) == Some(k))
        })
        .copied()
        .collect()
}

/// The `u'`-independent geometry of an event: the event itself and its mirror
/// image, each with weight `1 / (proposal density * images)`. For the
/// same-side stratum the mirror image stands for the both-negative sign
/// pattern; for the opposite-side stratum it is another point of the same
/// stratum (an antithetic pair: the drift, odd under mirroring, loses the noise
/// of its even part). Either way the image keeps the drawn point's proposal
/// density: `E_p[f(M x) / p(x)] = int f(M x) dx = int_{M S} f`, unbiased for any
/// proposal (the two densities coincide only when `launch_shift = 0`). The
/// literal algorithm's scenes count once. Velocity changes within `kick_floor`
/// count as zero. Empty for failed scenes and for recombined ones (the
/// free-atom kernel). A lazy iterator: nothing is allocated per event.
pub fn images(event: &Event, kick_floor: f64) -> impl ExactSizeIterator<Item = Contribution> + '_ {
    images_in(event, kick_floor, false)
}

/// The [`images`] of `event` if it ended in the channel `recombined` says
/// (a bound pair and a free atom, else three free atoms), else none.
fn images_in(
    event: &Event,
    kick_floor: f64,
    recombined: bool,
) -> impl ExactSizeIterator<Item = Contribution> + '_ {
    let signs: &'static [f64] = match (event.outgoing, event.stratum) {
        (None, _) => &[],
        _ if event.recombined() != recombined => &[],
        (Some(_), Stratum::Literal) => &[1.0],
        (Some(_), Stratum::Opposite | Stratum::SameSide) => &[1.0, -1.0],
    };
    let outgoing = event.outgoing.unwrap_or_default();
    signs.iter().map(move |&sign| {
        let (u2, u3) = (sign * event.u2, sign * event.u3);
        let mut out = outgoing.map(|v| sign * v);
        out.sort_by(f64::total_cmp);
        let incoming = [0.0, u2, u3];
        let mut sorted_in = incoming;
        sorted_in.sort_by(f64::total_cmp);
        for (velocity, matched) in out.iter_mut().zip(sorted_in) {
            if (*velocity - matched).abs() <= kick_floor {
                *velocity = matched;
            }
        }
        Contribution {
            weight: 1.0 / (event.proposal_density * signs.len() as f64),
            incoming,
            outgoing: out,
            self_rank: incoming.iter().filter(|&&u| u < 0.0).count(),
        }
    })
}

/// Weighted +-1 histograms of one replicate, split into self and bath.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Self part per bin.
    pub self_part: Vec<f64>,
    /// Bath part per bin.
    pub bath_part: Vec<f64>,
}

impl Histogram {
    fn new(bins: &Bins) -> Histogram {
        Histogram {
            self_part: vec![0.0; bins.len()],
            bath_part: vec![0.0; bins.len()],
        }
    }

    /// Self plus bath, per bin: the whole kernel.
    pub fn total(&self) -> Vec<f64> {
        self.self_part
            .iter()
            .zip(&self.bath_part)
            .map(|(s, b)| s + b)
            .collect()
    }

    /// The part that sorted rank `rank` feeds: `self_part` for the special
    /// particle's rank `self_rank`, `bath_part` for the others.
    fn part(&mut self, rank: usize, self_rank: usize) -> &mut [f64] {
        if rank == self_rank {
            &mut self.self_part
        } else {
            &mut self.bath_part
        }
    }

    /// Adds `weight` in the bin of `velocity` (if inside) of the part rank `rank` feeds.
    fn add_at(&mut self, bins: &Bins, rank: usize, self_rank: usize, velocity: f64, weight: f64) {
        if let Some(k) = bins.index(velocity) {
            self.part(rank, self_rank)[k] += weight;
        }
    }

    /// Adds a contribution: -1 at every incoming, +1 at every outgoing velocity,
    /// the special particle's pair into `self_part`, the others into `bath_part`.
    pub fn add(&mut self, bins: &Bins, contribution: &Contribution, scale: f64) {
        let weight = contribution.weight * scale;
        let sorted_in = contribution.sorted_incoming();
        for (rank, (incoming, outgoing)) in
            sorted_in.into_iter().zip(contribution.outgoing).enumerate()
        {
            self.add_at(bins, rank, contribution.self_rank, incoming, -weight);
            self.add_at(bins, rank, contribution.self_rank, outgoing, weight);
        }
    }
}

/// Points drawn per replicate and stratum (failed scenes included; a launch
/// pair integrated over the offset is one point, however many nodes).
#[derive(Clone, Debug, PartialEq)]
pub struct Draws {
    counts: Vec<[u64; 3]>,
}

impl Draws {
    /// Counts the events of every replicate (randomizations `0..=max`) and stratum.
    pub fn count(events: &[Event]) -> Draws {
        let replicates = events
            .iter()
            .map(|e| e.randomization as usize + 1)
            .max()
            .unwrap_or(0);
        let mut counts = vec![[0u64; 3]; replicates];
        for event in events.iter().filter(|e| e.node == 0) {
            counts[event.randomization as usize][event.stratum.index() as usize] += 1;
        }
        Draws { counts }
    }

    /// `1 / N` for the stratum of `event` in its replicate.
    pub fn scale(&self, event: &Event) -> f64 {
        1.0 / self.counts[event.randomization as usize][event.stratum.index() as usize] as f64
    }

    /// Number of replicates.
    pub fn replicates(&self) -> usize {
        self.counts.len()
    }
}

/// `true` when `events` are quadrature nodes (launch pairs integrated over
/// the offset): their pairs are runs of consecutive nodes.
fn integrates_offsets(events: &[Event]) -> bool {
    events.iter().any(|e| e.node > 0)
}

/// The kernel on `bins` around `target.u_prime`, per replicate. Quadrature
/// nodes spread their outgoing measure between consecutive nodes of a pair
/// ([`segments`]); sampled scenes are point masses.
pub fn histograms(events: &[Event], target: &Target, bins: &Bins, draws: &Draws) -> Vec<Histogram> {
    if integrates_offsets(events) {
        return node_histograms(events, target, bins, draws, Parts::Both);
    }
    per_replicate(
        events,
        draws,
        || Histogram::new(bins),
        |histogram, event, scale| {
            for contribution in contributions(event, target) {
                histogram.add(bins, &contribution, scale);
            }
        },
    )
}

/// [`histograms`] for readers of `G_self` only: its self part bit for bit.
/// Under the offset quadrature the special particle's tracks are laid as
/// there and the two bath tracks of every launch pair are not (two thirds of
/// the laying), so the bath part stays zero; sampled scenes (point masses,
/// no tracks) fill both parts as there.
pub fn self_histograms(
    events: &[Event],
    target: &Target,
    bins: &Bins,
    draws: &Draws,
) -> Vec<Histogram> {
    if integrates_offsets(events) {
        return node_histograms(events, target, bins, draws, Parts::SelfOnly);
    }
    histograms(events, target, bins, draws)
}

/// Which parts of the kernel a quadrature histogram lays.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Parts {
    /// The self and the bath part.
    Both,
    /// The self part; the bath part stays zero.
    SelfOnly,
}

/// `true` when `next` is the node after `previous` of the same launch pair.
fn is_next_node(previous: &Event, next: &Event) -> bool {
    previous.node + 1 == next.node
        && previous.randomization == next.randomization
        && previous.stratum == next.stratum
        && (previous.u2, previous.u3) == (next.u2, next.u3)
}

/// A replicate's histogram while its quadrature nodes are folded in, one
/// launch pair at a time.
struct NodeFold<'a> {
    bins: &'a Bins,
    /// The parts laid.
    parts: Parts,
    histogram: Histogram,
    /// The nodes of the current launch pair: each node's event and contributions.
    pair: Vec<(Event, Vec<Contribution>)>,
    /// One track's outgoing velocities and its nodes' weights, reused from
    /// track to track (every launch pair lays several).
    track: Vec<f64>,
    weights: Vec<f64>,
}

impl<'a> NodeFold<'a> {
    fn new(bins: &'a Bins, parts: Parts) -> Self {
        NodeFold {
            bins,
            parts,
            histogram: Histogram::new(bins),
            pair: Vec::new(),
            track: Vec::new(),
            weights: Vec::new(),
        }
    }

    /// Folds in the next node, placing the buffered launch pair when the
    /// node starts another (a track's segment needs the nodes on both sides
    /// of it).
    fn add(&mut self, event: &Event, contributions: Vec<Contribution>) {
        if self
            .pair
            .last()
            .is_some_and(|(previous, _)| !is_next_node(previous, event))
        {
            self.place_pair();
        }
        self.pair.push((*event, contributions));
    }

    /// Places the outgoing measure of the buffered pair along its velocity
    /// tracks ([`segments::lay_track`]), run by run (a failed scene, without
    /// contributions, ends a run), and the same measure, negative, at each
    /// track's incoming velocity: every track conserves the number of
    /// particles exactly.
    fn place_pair(&mut self) {
        let mut nodes = std::mem::take(&mut self.pair);
        for run in nodes.chunk_by(|(_, a), (_, b)| a.len() == b.len()) {
            let images = run[0].1.len();
            for image in 0..images {
                let first = &run[0].1[image];
                self.weights.clear();
                self.weights
                    .extend(run.iter().map(|(_, c)| c[image].weight));
                for (rank, matched) in first.sorted_incoming().into_iter().enumerate() {
                    if self.parts == Parts::SelfOnly && rank != first.self_rank {
                        continue;
                    }
                    self.track.clear();
                    self.track
                        .extend(run.iter().map(|(_, c)| c[image].outgoing[rank]));
                    if segments::lays_nothing(self.bins, matched, &self.track) {
                        continue;
                    }
                    let laid = segments::lay_track(
                        self.bins,
                        self.histogram.part(rank, first.self_rank),
                        matched,
                        &self.track,
                        &self.weights,
                    );
                    self.histogram
                        .add_at(self.bins, rank, first.self_rank, matched, -laid);
                }
            }
        }
        nodes.clear();
        self.pair = nodes;
    }

    fn finish(mut self) -> Histogram {
        self.place_pair();
        self.histogram
    }
}

/// [`histograms`] of quadrature nodes.
fn node_histograms(
    events: &[Event],
    target: &Target,
    bins: &Bins,
    draws: &Draws,
    parts: Parts,
) -> Vec<Histogram> {
    per_replicate(
        events,
        draws,
        || NodeFold::new(bins, parts),
        |fold, event, scale| {
            let scaled = contributions(event, target)
                .map(|c| Contribution {
                    weight: c.weight * scale,
                    ..c
                })
                .collect();
            fold.add(event, scaled);
        },
    )
    .into_iter()
    .map(NodeFold::finish)
    .collect()
}

/// Folds the events of every replicate, replicates in parallel. Each replicate
/// adds its events in their stored order, so the sums are bit-identical for any
/// thread count. The events are split by replicate in one pass (not one scan
/// of all events per replicate).
pub fn per_replicate<T: Send>(
    events: &[Event],
    draws: &Draws,
    start: impl Fn() -> T + Sync,
    add: impl Fn(&mut T, &Event, f64) + Sync,
) -> Vec<T> {
    let mut members: Vec<Vec<&Event>> = vec![Vec::new(); draws.replicates()];
    for event in events {
        if let Some(own) = members.get_mut(event.randomization as usize) {
            own.push(event);
        }
    }
    members
        .into_par_iter()
        .map(|own| {
            let mut sum = start();
            for event in own {
                add(&mut sum, event, draws.scale(event));
            }
            sum
        })
        .collect()
}

/// Drift `sum x` and variance `sum x^2` rates of the special particle alone
/// and of all particles, counting only velocities with `|x| <= truncation`
/// (relative to `u'`), per replicate, in units of `rho^2 l v_th`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MomentSums {
    /// Self drift rate `int G_self (u - u') du`.
    pub self_drift: f64,
    /// Self variance rate `int G_self (u - u')^2 du`.
    pub self_variance: f64,
    /// Drift rate of all particles in the window.
    pub window_drift: f64,
    /// Variance rate of all particles in the window.
    pub window_variance: f64,
    /// `sum w |sum_particles (out^2 - in^2)|` over every particle, in the
    /// untruncated slot only (0 in the others): twice the kinetic energy each scene's velocities
    /// gained or lost (the engine's error and the kick floor's snapping),
    /// summed without its sign. Energy conservation makes the untruncated
    /// `window_variance` exactly 0; this bounds its size.
    pub energy_change: f64,
}

/// Moment sums per replicate for each truncation half-width (`truncations`
/// ascending, as the stage builds them).
pub fn moments(
    events: &[Event],
    target: &Target,
    truncations: &[f64],
    draws: &Draws,
) -> Vec<Vec<MomentSums>> {
    debug_assert!(truncations.is_sorted(), "truncations ascending");
    let start = || vec![MomentSums::default(); truncations.len()];
    per_replicate(events, draws, start, |sums, event, scale| {
        for contribution in contributions(event, target) {
            add_moments(
                sums,
                truncations,
                &contribution,
                contribution.weight * scale,
            );
        }
    })
}

/// Adds one contribution of weight `weight` to the moment sums of every
/// truncation `X` (ascending), counting a velocity `x` where `|x| <= X`.
/// Each term enters the sums from the first truncation that counts it on,
/// so no sum sees the zeros of the velocities it leaves out; a particle's
/// window terms are its outgoing less its incoming value, each where it is
/// counted (either alone, then both). Every sum adds the same terms in the
/// same order as the truncation-by-truncation definition, so the same bits.
fn add_moments(
    sums: &mut [MomentSums],
    truncations: &[f64],
    contribution: &Contribution,
    weight: f64,
) {
    // The truncations below `|x|` counted, not searched: a branch-free pass
    // over a few dozen values beats a binary search's dependent steps.
    let counted_from = |x: f64| {
        let size = x.abs();
        truncations.iter().filter(|&&limit| limit < size).count()
    };
    let outgoing_from = contribution.outgoing.map(counted_from);
    let kick = contribution.self_kick();
    let (drift, variance) = (weight * kick, weight * kick * kick);
    for slot in &mut sums[outgoing_from[contribution.self_rank]..] {
        slot.self_drift += drift;
        slot.self_variance += variance;
    }
    let particles = contribution.outgoing.iter().zip(&contribution.incoming);
    for ((&out, &incoming), out_from) in particles.zip(outgoing_from) {
        let in_from = counted_from(incoming);
        let alone = if out_from <= in_from {
            [weight * out, weight * (out * out)]
        } else {
            [weight * -incoming, weight * -(incoming * incoming)]
        };
        let both = [
            weight * (out - incoming),
            weight * (out * out - incoming * incoming),
        ];
        let (first, second) = (out_from.min(in_from), out_from.max(in_from));
        let (one_counted, both_counted) = sums[first..].split_at_mut(second - first);
        for (slots, [drift, variance]) in [(one_counted, alone), (both_counted, both)] {
            for slot in slots {
                slot.window_drift += drift;
                slot.window_variance += variance;
            }
        }
    }
    let squares = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>();
    let energy_change =
        weight * (squares(&contribution.outgoing) - squares(&contribution.incoming)).abs();
    for slot in &mut sums[counted_from(f64::INFINITY)..] {
        slot.energy_change += energy_change;
    }
}

/// Engine of every pilot, fixed so that a study's engine settings do not
/// change its launch points (the pilot only estimates spreads and costs).
pub const PILOT_ENGINE: EngineSettings = EngineSettings {
    method: Method::Dprkn12,
    tolerance: 1e-10,
    max_steps: 100_000,
    free_flight: true,
};

/// Pilot scenes are drawn from a seed derived from the main one by this mask.
const PILOT_SEED_MASK: u64 = 0x5049_4c4f_545f_5345;

/// Same-side fraction of the Neyman allocation for `a_n` (numerics.md):
/// `N_s ~ sigma_s / sqrt(c_s)` for sampled offsets, `(sigma_s^2 / c_s)^(1/3)`
/// for launch pairs integrated by quadrature (whose randomized quasi-Monte
/// Carlo errors fall about as `N^-1`, not `N^-1/2`), with `sigma_s^2` the variance of one
/// point's contribution `sum w k^2` to the self variance rate (a sampled
/// scene, or a launch pair's offset integral) relative to the rate, summed
/// over `targets` (a launch mixture serves every `u'` its components reach:
/// the sweep's wide sets pass one target per component), and `c_s` its mean cost
/// in force evaluations, both from plain Monte Carlo points of a separate seed
/// (the main points are not reused): `pilot_points` per stratum when offsets
/// are sampled, `pilot_points / nodes` launch pairs (at least 16; `nodes` per pair) when
/// each pair is integrated by quadrature, about the same number of scenes.
/// Clamped to [0.02, 0.5] so that neither stratum starves; `None` when neither
/// stratum contributes (the integrable n = 2).
pub fn pilot_same_side_fraction(
    plan: &SamplingPlan,
    potential: &Potential,
    engine: &EngineSettings,
    targets: &[Target],
    pilot_points: u32,
) -> Option<f64> {
    let points = match plan.offsets {
        OffsetIntegration::Sampled => pilot_points,
        OffsetIntegration::Quadrature(rule) => (pilot_points / rule.nodes()).max(16),
    };
    let pilot = SamplingPlan {
        seed: plan.seed ^ PILOT_SEED_MASK,
        randomizations: 1,
        opposite_points: points,
        same_side_points: points,
        quasi_random: false,
        ..*plan
    };
    let records = pilot.integrate_all(potential, engine, |_| ());
    let count = f64::from(points);
    let mean = |values: &[f64]| values.iter().sum::<f64>() / count;
    let variance = |values: &[f64]| {
        let mean = mean(values);
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (count - 1.0)
    };
    // Per stratum: each point's contribution at every target, and the mean cost.
    let sample = |stratum: Stratum| {
        let mut values = vec![vec![0.0; points as usize]; targets.len()];
        let mut costs = vec![0.0; points as usize];
        for record in records.iter().filter(|r| r.scene.stratum == stratum) {
            let point = record.point as usize;
            let event = Event::from_record(record);
            for (values, target) in values.iter_mut().zip(targets) {
                values[point] += contributions(&event, target)
                    .map(|c| c.weight * c.self_kick().powi(2))
                    .sum::<f64>();
            }
            costs[point] += f64::from(record.collision.evaluations);
        }
        (values, mean(&costs))
    };
    let strata = [sample(Stratum::Opposite), sample(Stratum::SameSide)];
    // Each target's rate (both strata), so that every target weighs by its
    // relative variance: the rates at the mixture's outer components are
    // several times the centre's.
    let rates: Vec<f64> = (0..targets.len())
        .map(|t| strata.iter().map(|(values, _)| mean(&values[t])).sum())
        .collect();
    let merit = |(values, cost): &(Vec<Vec<f64>>, f64)| {
        let relative: f64 = values
            .iter()
            .zip(&rates)
            .filter(|(_, rate)| **rate != 0.0)
            .map(|(values, rate)| variance(values) / (rate * rate))
            .sum();
        relative.sqrt() / cost.sqrt()
    };
    let [opposite, same] = strata.each_ref().map(merit);
    // Errors falling as N^-p split a fixed cost as N_s ~ (sigma_s^2 / c_s)^(1 / (2p + 1)):
    // Neyman's sigma_s / sqrt(c_s) for Monte Carlo (p = 1/2); launch pairs under the
    // offset quadrature converge as N^-1.1 .. N^-1.75 (docs/benchmarks.md), p = 1 taken.
    let exponent = match plan.offsets {
        OffsetIntegration::Sampled => 1.0,
        OffsetIntegration::Quadrature(_) => 2.0 / 3.0,
    };
    let (opposite, same) = (libm::pow(opposite, exponent), libm::pow(same, exponent));
    let fraction = same / (opposite + same);
    fraction.is_finite().then(|| fraction.clamp(0.02, 0.5))
}

#[cfg(test)]
mod moment_tests;
