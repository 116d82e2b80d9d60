//! The offset measure of a launch pair between two consecutive quadrature
//! nodes, spread over the kernel bins its velocities pass through (issue 18).
//!
//! Under the offset quadrature every node of a launch pair is a scene whose
//! weight is its share of `dtau`. As point masses, a pair's nodes feed only the
//! bins they happen to land in: in the tails of the kick curve (`|kick| ~
//! tau^-(n+1)`) consecutive nodes, `h = 0.125` apart in `s`, differ by a
//! factor ~2 in kick, so a bin of width 5e-5 near `u'` is hit by a node of one
//! pair in twenty. Between two nodes the kick is a smooth, monotone function
//! of `s`: the segment's measure (half of each node's weight) is laid along
//! the kick interpolated between the nodes, `ln |kick|` quadratically in `s`
//! when both kicks have one sign (through the neighbouring nodes: exact for a
//! power-law tail, `kick ~ e^(-(n+1) s)`, and for the bend where the tail
//! meets the core), linearly otherwise, with a mass density along the segment
//! interpolated exponentially between the two node weights (`dtau/ds = T
//! cosh(s)`), and every bin the kick passes through receives the measure of
//! its share.
//!
//! Only in the tails. In the core of a collision (`|kick| >= CORE_KICK`) the
//! kick curve turns and bends within a step, interpolation moves measure
//! between bins (exponential interpolation put 2.5% of `G(0 -> u)` at `u ~
//! 0.005` that belongs at 0.0075..0.015 for n = 6, and lost 17% of `G(-3 ->
//! -2.96)`: docs/benchmarks.md), and many nodes feed every bin anyway: there
//! the nodes stay the trapezoid's point masses, which the moved node grid
//! (`OffsetRule::coarse_nodes`) makes unbiased. The split is by the value of
//! the kick, a function of the offset alone, so each part keeps its rule's
//! accuracy.
//!
//! Where the kick passes through the tails' range inside the core (through
//! zero, between a positive and a negative kick), a node in that narrow
//! window put its whole weight into one bin near `u'`, one launch pair in a
//! few: at n = 12 those point masses were half the variance of the bins at
//! `|du| ~ 1e-3`. The window's nodes keep their weight (the trapezoid's
//! estimate of the window's measure) but spread it over the whole window's
//! kicks (`lay_window`). Interpolating the window itself instead (its
//! edges on the quintic through six nodes) put ~25% too much measure there
//! at n = 12, where a step spans a third of the swing from the kick's peak
//! to zero (docs/benchmarks.md).

use crate::binning::Bins;

/// Kicks at least this large (`v_th`) belong to the core of a collision:
/// there the nodes are point masses.
pub const CORE_KICK: f64 = 2e-3;

/// Lays a launch pair's measure along one velocity track into `part`:
/// `outgoing[i]` is the track's velocity at node `i` (consecutive nodes of
/// one pair, equally spaced in `s`, relative to `u'`), `weights[i]` the
/// node's trapezoid weight, `matched` the incoming velocity the track is
/// matched with. The offsets split by the kick into the core (`|kick| >=
/// CORE_KICK`), the narrow windows where the kick passes through zero inside
/// it, and the outer tails on either side. The nodes of the core and of the
/// windows keep their whole weight (the trapezoid rule of those parts,
/// unbiased on average over the grid's move): the core's as point masses,
/// a window's spread over the whole window's kicks (`lay_window`). In the
/// outer tails each node gives the segment on either side its share of the
/// mass (`segment_masses`), and the segments, the innermost cut where the
/// interpolated kick reaches `CORE_KICK`, are spread ([`Segment::spread`]);
/// where the track turns, along the cubic through the turn
/// ([`Segment::turning`]). Returns the measure laid, also where it falls
/// outside `bins`: the loss at the incoming velocity must be the same, or
/// the track creates or destroys particles (with the nodes' trapezoid
/// weights as the loss, `h^2 / 12` of a pair's whole offset range was left
/// at the incoming velocity of every bath particle: -0.3% of `G` at `|du|`
/// 1e-2..5e-2 at 49 nodes, docs/benchmarks.md).
pub fn lay_track(
    bins: &Bins,
    part: &mut [f64],
    matched: f64,
    outgoing: &[f64],
    weights: &[f64],
) -> f64 {
    let in_core = |velocity: f64| (velocity - matched).abs() >= CORE_KICK;
    let last = outgoing.len() - 1;
    let first_core = outgoing.iter().position(|&v| in_core(v));
    let last_core = outgoing.iter().rposition(|&v| in_core(v));
    // Between the first and the last core node: the core and its windows.
    let inner = |i: usize| first_core.is_some_and(|f| i >= f) && last_core.is_some_and(|l| i <= l);
    let mut laid = 0.0;
    for (i, (&velocity, &weight)) in outgoing.iter().zip(weights).enumerate() {
        if inner(i) && in_core(velocity) {
            laid += add_point(bins, part, velocity, weight);
        } else if !inner(i) && (i == 0 || i == last) {
            laid += add_point(bins, part, velocity, 0.5 * weight);
        }
    }
    let mut track = Track::new(matched, outgoing, weights);
    if let (Some(first), Some(last_core)) = (first_core, last_core) {
        track.lay_windows(bins, part, [first, last_core], &mut laid);
    }
    let mut node = |j: usize| track.node(j);
    for i in 0..last {
        if inner(i) && inner(i + 1) {
            continue;
        }
        let halves = segment_masses(weights[i], weights[i + 1]);
        let ends = [outgoing[i], outgoing[i + 1]];
        let beside_core = inner(i) || inner(i + 1);
        let mut monotone = |part: &mut [f64]| {
            let ends = [node(i), node(i + 1)];
            let neighbours = [
                i.checked_sub(1).map(&mut node),
                (i + 2 <= last).then(|| node(i + 2)),
            ];
            Segment::monotone(matched, ends, neighbours, halves).spread_tail(bins, part)
        };
        laid += if monotone_around(outgoing, i) {
            monotone(part)
        } else if turns_once(outgoing, i) {
            Segment::turning(matched, ends, halves, neighbours(outgoing, i))
                .spread_turning(bins, part)
        } else if beside_core {
            monotone(part)
        } else {
            add_point(bins, part, ends[0], halves[0]) + add_point(bins, part, ends[1], halves[1])
        };
    }
    laid
}

/// A track's nodes as [`lay_track`] walks them: outgoing velocities, node
/// weights, and each node's `ln |kick|` taken when a segment first asks
/// (NaN: not yet).
struct Track<'a> {
    matched: f64,
    outgoing: &'a [f64],
    weights: &'a [f64],
    logs: Vec<f64>,
}

impl<'a> Track<'a> {
    fn new(matched: f64, outgoing: &'a [f64], weights: &'a [f64]) -> Track<'a> {
        Track {
            matched,
            outgoing,
            weights,
            logs: Vec::new(),
        }
    }

    /// Node `j` with its `ln |kick|`.
    fn node(&mut self, j: usize) -> Node {
        if self.logs.is_empty() {
            self.logs = vec![f64::NAN; self.outgoing.len()];
        }
        if self.logs[j].is_nan() {
            self.logs[j] = libm::log((self.outgoing[j] - self.matched).abs());
        }
        Node {
            velocity: self.outgoing[j],
            log_kick: self.logs[j],
        }
    }

    /// Adds to `laid`, one window after another, the measure of the windows
    /// between the first and the last core node (`core`): runs of nodes that
    /// kick less than `CORE_KICK` ([`lay_window`]).
    fn lay_windows(
        &self,
        bins: &Bins,
        part: &mut [f64],
        [first, last_core]: [usize; 2],
        laid: &mut f64,
    ) {
        let in_core = |j: usize| (self.outgoing[j] - self.matched).abs() >= CORE_KICK;
        let mut j = first;
        while j < last_core {
            let start = j;
            while !in_core(j) {
                j += 1;
            }
            if j > start {
                let mass = self.weights[start..j].iter().sum();
                let window = &self.outgoing[start - 1..=j];
                *laid += lay_window(bins, part, self.matched, window, mass);
            }
            j += 1;
        }
    }
}

/// `true` when [`lay_track`] would put nothing into `bins` and the loss at
/// `matched` would fall outside them too, so the track can be skipped: every
/// measure a track spreads lies within `CORE_KICK` of its matched velocity
/// (the tails, the windows through zero and the tail pieces of turning
/// segments are all cut at `|kick| = CORE_KICK`), the rest sits at its
/// nodes. So a track whose matched velocity is more than `CORE_KICK` (and a
/// bin, for the rounding of the cuts) beyond the bins and whose every node
/// is outside them leaves the histogram exactly as it was: a bath particle
/// far from `u'`, most of every launch pair's tracks.
pub fn lays_nothing(bins: &Bins, matched: f64, outgoing: &[f64]) -> bool {
    matched.abs() > bins.half_width() + CORE_KICK + bins.width
        && outgoing.iter().all(|&v| bins.index(v).is_none())
}

/// Lays the `mass` of a window's nodes (the trapezoid's estimate of the
/// window's measure, unbiased over the grid's move) over the window's
/// kicks: `track` runs from the core node before the window through the
/// window's nodes to the core node after it, the kick linear between
/// nodes, cut where it reaches `CORE_KICK`, the mass uniform in `s`. Every
/// node of the window spreads over the whole window: for a kick linear
/// across it, the expected mass in each bin is then exactly its measure,
/// whereas spreading each node only around itself moves mass away from the
/// window's edges (1.7% of `G` at `|du|` from 1.5e-3 to 2e-3, n = 12, 193
/// nodes). Returns the mass laid.
fn lay_window(bins: &Bins, part: &mut [f64], matched: f64, track: &[f64], mass: f64) -> f64 {
    let last = track.len() - 1;
    let kick = |j: usize| track[j] - matched;
    // Each piece: its length in steps and the kicks at its ends.
    let edge_piece = |core: usize, inside: usize| {
        let edge = CORE_KICK.copysign(kick(core));
        let reach = (edge - kick(inside)) / (kick(core) - kick(inside));
        (reach, [edge, kick(inside)])
    };
    let pieces: Vec<(f64, [f64; 2])> = std::iter::once(edge_piece(0, 1))
        .chain((1..last - 1).map(|j| (1.0, [kick(j), kick(j + 1)])))
        .chain(std::iter::once(edge_piece(last, last - 1)))
        .collect();
    let length: f64 = pieces.iter().map(|&(reach, _)| reach).sum();
    pieces
        .into_iter()
        .map(|(reach, ends)| {
            let share = 0.5 * mass * reach / length;
            Segment::straight(
                matched,
                ends.map(|k| matched + k),
                [share, share],
                Scale::Linear,
            )
            .spread(bins, part)
        })
        .sum()
}

/// The velocities one node before and one after the segment `(i, i + 1)`.
fn neighbours(track: &[f64], i: usize) -> [Option<f64>; 2] {
    [
        i.checked_sub(1).map(|k| track[k]),
        track.get(i + 2).copied(),
    ]
}

/// `true` when exactly one of the segment `(i, i + 1)`'s nodes is extremal
/// (the track turns there); `false` when neither or both are (a zigzag, not
/// resolved by the nodes).
fn turns_once(track: &[f64], i: usize) -> bool {
    let extremal = |j: usize| {
        j >= 1 && j + 1 < track.len() && (track[j] - track[j - 1]) * (track[j + 1] - track[j]) < 0.0
    };
    extremal(i) != extremal(i + 1)
}

/// The masses two consecutive nodes of weights `first`, `second` give the
/// segment between them: together the integral of the mass density
/// interpolated exponentially between them, `first (r - 1) / ln r` with `r =
/// second / first` (exact for `dtau/ds ~ e^|s|` in the tails, where the
/// trapezoid's `(first + second) / 2` is `h^2 / 12` too large), in the ratio
/// `r`.
///
/// An end of weight 0 (a survival factor `exp(-r |delay|)` that underflowed:
/// a finite-density target and a launch so slow that its delay is ~1e6)
/// gives the segment no mass, the exponential's limit.
fn segment_masses(first: f64, second: f64) -> [f64; 2] {
    if first == 0.0 || second == 0.0 {
        return [0.0; 2];
    }
    let ratio = second / first;
    let log_ratio = libm::log(ratio);
    let mass = if log_ratio.abs() < 1e-9 {
        0.5 * (first + second)
    } else {
        first * (ratio - 1.0) / log_ratio
    };
    [mass / (1.0 + ratio), mass * ratio / (1.0 + ratio)]
}

/// Adds `mass` in the bin of `velocity`, if inside; returns `mass`.
fn add_point(bins: &Bins, part: &mut [f64], velocity: f64, mass: f64) -> f64 {
    if let Some(k) = bins.index(velocity) {
        part[k] += mass;
    }
    mass
}

/// `true` when `track` does not turn between nodes `i - 1` and `i + 2` (as
/// far as they exist): every step has the sign of the others or is zero, so
/// no extremum of the curve lies in or next to the segment `(i, i + 1)`.
fn monotone_around(track: &[f64], i: usize) -> bool {
    let (low, high) = (i.saturating_sub(1), (i + 2).min(track.len() - 1));
    let steps = track[low..=high].windows(2).map(|w| w[1] - w[0]);
    let (mut rising, mut falling) = (false, false);
    for step in steps {
        rising |= step > 0.0;
        falling |= step < 0.0;
    }
    !(rising && falling)
}

/// A node of a velocity track as its segments see it: the outgoing
/// velocity and `ln |kick|`, the kick measured from the matched incoming
/// velocity (computed once per node: each node bends up to four segments).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Outgoing velocity, `v_th` (relative to `u'`).
    pub velocity: f64,
    /// `ln |velocity - matched|`.
    pub log_kick: f64,
}

/// How a segment's track is interpolated: in `ln |kick|` (both end kicks of
/// one sign) or in the kick itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// `g = ln |kick|`: exact for power-law tails.
    Logarithmic,
    /// `g = kick`: through a change of sign, or over a turn of the track.
    Linear,
}

/// One velocity track (a sorted rank of the outgoing velocities) between two
/// consecutive nodes of a launch pair. Velocities relative to `u'`, `v_th`;
/// masses in the kernel's weight units. Along the segment, at `t` in `[0,
/// 1]`, the track's `g` (its [`Scale`]) is `g0 + t (g1 - g0) + t (t - 1)
/// (curvature + cubic t)`: a parabola or a cubic through the two end nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The incoming velocity the track is matched with: kicks are measured from it.
    pub matched: f64,
    /// Outgoing velocities at the two nodes.
    pub ends: [f64; 2],
    /// The masses the two nodes give the segment (half their trapezoid weights).
    pub halves: [f64; 2],
    /// What is interpolated.
    pub scale: Scale,
    /// Coefficient of `t (t - 1)` in `g` (0, with `cubic`: `g` linear in `t`).
    pub curvature: f64,
    /// Coefficient of `t^2 (t - 1)` in `g` (0: a parabola).
    pub cubic: f64,
    /// `g` at the two nodes, computed once (every use of the segment asks).
    gauges: [f64; 2],
}

impl Segment {
    /// A segment over which the track is monotone: `ln |kick|` bent like the
    /// parabolas through the nodes on either side, averaged, and left
    /// straight when that bend would turn it within the segment; the kick
    /// linear when it changes sign. `neighbours`: the nodes one step before
    /// and after the segment, where they exist; each bends the segment where
    /// it kicks the same way.
    pub fn monotone(
        matched: f64,
        [first, second]: [Node; 2],
        neighbours: [Option<Node>; 2],
        halves: [f64; 2],
    ) -> Segment {
        let [a, b] = [first, second].map(|n| n.velocity - matched);
        let same_sign = a * b > 0.0;
        let mut segment = if same_sign {
            Segment::logarithmic(matched, [first, second], halves)
        } else {
            Segment::straight(
                matched,
                [first.velocity, second.velocity],
                halves,
                Scale::Linear,
            )
        };
        // Every tail segment asks: summed without allocating.
        let (bent, bends) = neighbours
            .into_iter()
            .zip([-1.0, 2.0])
            .filter_map(|(n, at)| n.map(|n| (n, at)))
            .filter(|&(n, _)| !same_sign || (n.velocity - matched) * a > 0.0)
            .map(|(n, at)| {
                let g = match segment.scale {
                    Scale::Logarithmic => n.log_kick,
                    Scale::Linear => n.velocity - matched,
                };
                segment.curvature_through(g, at)
            })
            .fold((0.0, 0_u32), |(sum, count), bend| (sum + bend, count + 1));
        if bends > 0 {
            segment.curvature = bent / f64::from(bends);
        }
        if segment.turns().iter().any(Option::is_some) {
            segment.curvature = 0.0;
        }
        segment
    }

    /// A segment whose `g` is linear in `t`.
    fn straight(matched: f64, ends: [f64; 2], halves: [f64; 2], scale: Scale) -> Segment {
        Segment::bent(matched, ends, halves, scale, [0.0, 0.0])
    }

    /// A straight segment in `ln |kick|` between two nodes whose kicks have one sign.
    fn logarithmic(matched: f64, [first, second]: [Node; 2], halves: [f64; 2]) -> Segment {
        Segment {
            matched,
            ends: [first.velocity, second.velocity],
            halves,
            scale: Scale::Logarithmic,
            curvature: 0.0,
            cubic: 0.0,
            gauges: [first.log_kick, second.log_kick],
        }
    }

    /// A segment whose `g` has the `bends` `[curvature, cubic]`.
    fn bent(
        matched: f64,
        ends: [f64; 2],
        halves: [f64; 2],
        scale: Scale,
        [curvature, cubic]: [f64; 2],
    ) -> Segment {
        Segment {
            matched,
            ends,
            halves,
            scale,
            curvature,
            cubic,
            gauges: ends.map(|v| gauge(scale, v - matched)),
        }
    }

    /// A segment next to a turn of the track: the kick is the cubic through
    /// its two nodes and the `neighbours` (the velocities one step before and
    /// after), or the parabola through the one that exists. At a sharp
    /// extremum (a weak collision's peak, a few steps wide) the parabola
    /// through three nodes falls short of the peak and puts the offsets
    /// above it into the bins below: +1.9% of `G` at `|du|` 1.5e-3..2e-3
    /// for n = 12 at 49 nodes against 193, +0.4% with the cubic
    /// (docs/benchmarks.md).
    pub fn turning(
        matched: f64,
        ends: [f64; 2],
        halves: [f64; 2],
        neighbours: [Option<f64>; 2],
    ) -> Segment {
        let mut segment = Segment::straight(matched, ends, halves, Scale::Linear);
        let bends = neighbours.map(|v| v.map(|v| v - matched));
        match bends {
            [Some(before), Some(after)] => {
                let (early, late) = (
                    segment.curvature_through(before, -1.0),
                    segment.curvature_through(after, 2.0),
                );
                segment.cubic = (late - early) / 3.0;
                segment.curvature = early + segment.cubic;
            }
            [Some(before), None] => segment.curvature = segment.curvature_through(before, -1.0),
            [None, Some(after)] => segment.curvature = segment.curvature_through(after, 2.0),
            [None, None] => {}
        }
        segment
    }

    /// The curvature of the parabola that puts `g = value` at position `at`
    /// (-1 or 2): half the second difference of `g` over the three nodes.
    fn curvature_through(&self, value: f64, at: f64) -> f64 {
        let [g0, g1] = self.end_values();
        if at < 0.0 {
            0.5 * (value - 2.0 * g0 + g1)
        } else {
            0.5 * (value - 2.0 * g1 + g0)
        }
    }

    /// `g` at the two nodes.
    fn end_values(&self) -> [f64; 2] {
        self.gauges
    }

    /// What locating velocities and masses along the segment needs, computed once.
    fn profile(&self) -> Profile {
        let [g0, g1] = self.end_values();
        let [first, second] = self.halves;
        let log_ratio = libm::log(second / first);
        Profile {
            matched: self.matched,
            scale: self.scale,
            g0,
            linear: g1 - g0 - self.curvature,
            quadratic: self.curvature - self.cubic,
            cubic: self.cubic,
            log_ratio,
            ratio_m1: libm::expm1(log_ratio),
        }
    }

    /// Positions inside `(0, 1)`, ascending, where the track turns (`g`'s
    /// derivative vanishes): none, one or two (no allocation: every tail
    /// segment asks).
    fn turns(&self) -> [Option<f64>; 2] {
        let [g0, g1] = self.end_values();
        let roots = if self.cubic == 0.0 {
            [
                (self.curvature - (g1 - g0)) / (2.0 * self.curvature),
                f64::NAN,
            ]
        } else {
            // g'(t) = linear + 2 quadratic t + 3 cubic t^2; no real root: NaN.
            let (linear, quadratic) = (g1 - g0 - self.curvature, self.curvature - self.cubic);
            let root = (quadratic * quadratic - 3.0 * self.cubic * linear).sqrt();
            let [a, b] = [-root, root].map(|r| (-quadratic + r) / (3.0 * self.cubic));
            [a.min(b), a.max(b)]
        };
        roots.map(|t| (t > 0.0 && t < 1.0).then_some(t))
    }

    /// Adds the mass to the bins of `part`, in monotone pieces between the
    /// points where the track turns inside the segment, each only where its
    /// kick is in the tails; returns the mass laid.
    pub fn spread_turning(&self, bins: &Bins, part: &mut [f64]) -> f64 {
        let turns = self.turns();
        if turns.iter().all(Option::is_none) {
            return self.spread_tail(bins, part);
        }
        let profile = self.profile();
        let mut laid = 0.0;
        let mut from = 0.0;
        for to in turns.into_iter().flatten().chain(std::iter::once(1.0)) {
            laid += self.restricted(&profile, from, to).spread_tail(bins, part);
            from = to;
        }
        laid
    }

    /// Adds the mass of the part of this monotone segment whose kick lies in
    /// the tails, `|kick| < CORE_KICK`, to the bins of `part` (the core's
    /// measure is its nodes' point masses); returns that mass.
    pub fn spread_tail(&self, bins: &Bins, part: &mut [f64]) -> f64 {
        let [a, b] = self.ends.map(|v| v - self.matched);
        let (a_core, b_core) = (a.abs() >= CORE_KICK, b.abs() >= CORE_KICK);
        match (a_core, b_core) {
            (false, false) => self.spread(bins, part),
            (true, true) => 0.0,
            _ => {
                let core = if a_core { a } else { b };
                let profile = self.profile();
                let edge = profile.position(self.matched + CORE_KICK.copysign(core));
                let (from, to) = if a_core { (edge, 1.0) } else { (0.0, edge) };
                self.restricted(&profile, from, to).spread(bins, part)
            }
        }
    }

    /// The velocity of the track at position `t` in `[0, 1]`.
    fn velocity_at(&self, t: f64) -> f64 {
        let [g0, g1] = self.end_values();
        let g = g0 + t * (g1 - g0) + (self.curvature + self.cubic * t) * t * (t - 1.0);
        let kick = match self.scale {
            Scale::Logarithmic => libm::exp(g).copysign(self.ends[0] - self.matched),
            Scale::Linear => g,
        };
        self.matched + kick
    }

    /// Adds the segment's mass to the bins of `part` (`bins` around `u'`);
    /// returns the mass, also the part outside the bins.
    pub fn spread(&self, bins: &Bins, part: &mut [f64]) -> f64 {
        let [a, b] = self.ends;
        let total = self.halves[0] + self.halves[1];
        let (first, last) = (bins.index(a), bins.index(b));
        if first == last {
            if let Some(k) = first {
                part[k] += total;
            }
            return total;
        }
        let (low, high) = (a.min(b), a.max(b));
        let (low_bin, high_bin) = (
            (low / bins.width).round() as i64,
            (high / bins.width).round() as i64,
        );
        let profile = self.profile();
        let fraction_at = |velocity: f64| profile.mass_fraction(profile.position(velocity));
        // The mass fraction at each bin edge, computed once: a bin's lower
        // edge is the one below's upper edge, so the shares telescope to
        // the segment's whole mass.
        let mut below: Option<f64> = None;
        for bin in low_bin..=high_bin {
            let Some(k) = bins.index(bin as f64 * bins.width) else {
                below = None;
                continue;
            };
            let centre = bins.centre(k);
            let lower = below.unwrap_or_else(|| fraction_at((centre - 0.5 * bins.width).max(low)));
            let upper = fraction_at((centre + 0.5 * bins.width).min(high));
            part[k] += total * (upper - lower).abs();
            below = Some(upper);
        }
        total
    }

    /// The part of the segment between positions `from <= to` in `[0, 1]`:
    /// the same interpolated track and mass density (both families are
    /// closed under restriction), with the mass that part carries.
    fn restricted(&self, profile: &Profile, from: f64, to: f64) -> Segment {
        let [first, second] = self.halves;
        let mass = (first + second) * (profile.mass_fraction(to) - profile.mass_fraction(from));
        let ratio = libm::pow(second / first, to - from);
        let ratio = if ratio.is_finite() { ratio } else { 1.0 };
        // The same polynomial in t' = (t - from) / (to - from).
        let length = to - from;
        let cubic = self.cubic * length.powi(3);
        let quadratic = self.curvature - self.cubic + 3.0 * self.cubic * from;
        Segment::bent(
            self.matched,
            [self.velocity_at(from), self.velocity_at(to)],
            [mass / (1.0 + ratio), mass * ratio / (1.0 + ratio)],
            self.scale,
            [cubic + quadratic * length * length, cubic],
        )
    }
}

/// `g` of a kick on `scale`.
fn gauge(scale: Scale, kick: f64) -> f64 {
    match scale {
        Scale::Logarithmic => libm::log(kick.abs()),
        Scale::Linear => kick,
    }
}

/// A segment's track and mass density in the form that locates velocities
/// and masses along it: `g(t) = g0 + linear t + quadratic t^2 + cubic t^3`,
/// and the node masses' ratio `e^log_ratio`. Computed once per spread segment, it saves
/// the logarithms of the ends and of the ratio at every bin edge (the same
/// numbers, so the same bits).
struct Profile {
    matched: f64,
    scale: Scale,
    g0: f64,
    linear: f64,
    quadratic: f64,
    cubic: f64,
    log_ratio: f64,
    /// `e^log_ratio - 1`.
    ratio_m1: f64,
}

impl Profile {
    /// Position `t` in `[0, 1]` along the segment where the track has the
    /// outgoing velocity `velocity` (within the range of a monotone segment):
    /// the root in `[0, 1]` of `g(t) = g`; for a parabola in the form that
    /// stays accurate as the curvature vanishes, for a cubic by bisection.
    fn position(&self, velocity: f64) -> f64 {
        let level = gauge(self.scale, velocity - self.matched) - self.g0;
        if self.cubic != 0.0 {
            return self.cubic_position(level);
        }
        let linear = self.linear;
        let root = (linear * linear + 4.0 * self.quadratic * level)
            .max(0.0)
            .sqrt();
        let near = 2.0 * level / (linear + root.copysign(linear));
        let far = (-linear - root.copysign(linear)) / (2.0 * self.quadratic);
        // The root in [0, 1], or (rounding at an end) the one nearest to it.
        let outside = |t: f64| (-t).max(t - 1.0).max(0.0);
        let t = if self.quadratic == 0.0 || outside(near) <= outside(far) {
            near
        } else {
            far
        };
        if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// The root in `[0, 1]` of `g(t) - g0 = level` on a monotone cubic (the
    /// end nearest to `level` when outside): Newton's iteration from the
    /// middle, inside a bracket that every step narrows, bisecting where
    /// Newton would leave it (at a turn the slope vanishes), until the step
    /// is below 4 ulp of 1. Bisection alone took 64 halvings (a sixth of
    /// the kernel stage's time); Newton takes ~5.
    fn cubic_position(&self, level: f64) -> f64 {
        let rise = |t: f64| t * (self.linear + t * (self.quadratic + t * self.cubic));
        let slope = |t: f64| self.linear + t * (2.0 * self.quadratic + 3.0 * t * self.cubic);
        let increasing = rise(1.0) >= 0.0;
        let (mut low, mut high, mut t) = (0.0_f64, 1.0_f64, 0.5_f64);
        for _ in 0..64 {
            let excess = rise(t) - level;
            if (excess < 0.0) == increasing {
                low = t;
            } else {
                high = t;
            }
            let newton = t - excess / slope(t);
            let next = if newton > low && newton < high {
                newton
            } else {
                0.5 * (low + high)
            };
            let step = (next - t).abs();
            t = next;
            if step <= 4.0 * f64::EPSILON {
                break;
            }
        }
        t
    }

    /// Fraction of the segment's mass between its first node and position
    /// `t`, the density interpolated exponentially between the node masses.
    fn mass_fraction(&self, t: f64) -> f64 {
        let log_ratio = self.log_ratio;
        if !log_ratio.is_finite() || log_ratio.abs() < 1e-9 {
            return t;
        }
        libm::expm1(t * log_ratio) / self.ratio_m1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A segment with an end of weight 0 (an underflowed survival factor)
    /// has no mass, not NaN; between equal weights it is their mean, and the
    /// exponential's integral otherwise (`(b - a) / ln(b / a)`).
    #[test]
    fn segment_masses_are_finite_with_an_end_of_weight_zero() {
        assert_eq!(segment_masses(0.0, 1.0), [0.0; 2]);
        assert_eq!(segment_masses(2.0, 0.0), [0.0; 2]);
        assert_eq!(segment_masses(0.0, 0.0), [0.0; 2]);
        let [a, b] = segment_masses(1.0, 1.0);
        assert!((a + b - 1.0).abs() < 1e-15);
        let [a, b] = segment_masses(1.0, 4.0);
        assert!((a + b - 3.0 / libm::log(4.0)).abs() < 1e-15);
    }

    /// A power-law tail `kick = c e^(-7 s)` with `dtau/ds ~ e^s`: segments
    /// between nodes 0.125 apart, each carrying its exact measure, put into
    /// each bin the exact measure of the offsets whose kick lands there (to
    /// 1e-9), where the nodes as point masses miss most bins.
    #[test]
    fn a_power_law_tail_lands_exactly() {
        let bins = Bins::for_window(0.01, 5e-5);
        let (c, h) = (2e-3, 0.125);
        let kick = |s: f64| c * libm::exp(-7.0 * s);
        let weight = |s: f64| h * libm::exp(s);
        let nodes: Vec<f64> = (0..24).map(|k| f64::from(k) * h).collect();
        let mut spread = vec![0.0; bins.len()];
        let mut points = vec![0.0; bins.len()];
        for pair in nodes.windows(2) {
            // Node masses in the ratio of dtau/ds, summing to the segment's exact measure.
            let exact = libm::exp(pair[1]) - libm::exp(pair[0]);
            let scale = exact / (libm::exp(pair[0]) + libm::exp(pair[1]));
            Segment::straight(
                0.0,
                [kick(pair[0]), kick(pair[1])],
                [scale * libm::exp(pair[0]), scale * libm::exp(pair[1])],
                Scale::Logarithmic,
            )
            .spread(&bins, &mut spread);
            points[bins.index(kick(pair[0])).unwrap()] += weight(pair[0]);
        }
        // Exact: the measure int e^s ds of the s where the kick lies in the bin.
        let s_at = |velocity: f64| libm::log(c / velocity) / 7.0;
        let first_full = bins.index(kick(0.0)).unwrap() - 1;
        let mut missed = 0;
        for k in bins.index(kick(nodes[23])).unwrap() + 1..=first_full {
            let centre = bins.centre(k);
            let (low, high) = (centre - 2.5e-5, centre + 2.5e-5);
            let exact = libm::exp(s_at(low)) - libm::exp(s_at(high));
            assert!(
                (spread[k] - exact).abs() < 1e-9 * exact,
                "bin {centre}: {} vs {exact}",
                spread[k]
            );
            missed += usize::from(points[k] == 0.0);
        }
        assert!(missed > 10, "point masses missed only {missed} bins");
    }

    /// On a monotone cubic the position of a level is its root to rounding,
    /// also where the cubic turns at an end (slope 0 there: Newton's steps
    /// leave the bracket and bisect), and a level beyond the ends gives the
    /// nearest end.
    #[test]
    fn cubic_positions_are_roots() {
        // g - g0 = t (1 - t + t^2 / 3): rising, slope 0 at t = 1.
        let profile = Profile {
            matched: 0.0,
            scale: Scale::Linear,
            g0: 0.0,
            linear: 1.0,
            quadratic: -1.0,
            cubic: 1.0 / 3.0,
            log_ratio: 0.0,
            ratio_m1: 0.0,
        };
        let rise = |t: f64| t * (1.0 + t * (-1.0 + t / 3.0));
        for k in 0..=64 {
            let t = f64::from(k) / 64.0;
            let found = profile.cubic_position(rise(t));
            assert!((rise(found) - rise(t)).abs() < 1e-15, "{t}: {found}");
        }
        assert!(profile.cubic_position(-0.1).abs() < 1e-14);
        assert!((profile.cubic_position(0.5) - 1.0).abs() < 1e-14);
    }

    /// The mass is conserved within the window, for a kick changing sign
    /// (linear interpolation) and for unequal node masses.
    #[test]
    fn segments_conserve_their_mass() {
        let bins = Bins::for_window(0.01, 5e-5);
        for (ends, halves) in [
            ([-3e-4, 7e-4], [0.3, 0.9]),
            ([1e-3, 1.3e-4], [2.0, 0.1]),
            ([0.2e-4, 1.0e-4], [1.0, 1.0]),
        ] {
            let mut part = vec![0.0; bins.len()];
            let scale = if ends[0] * ends[1] > 0.0 {
                Scale::Logarithmic
            } else {
                Scale::Linear
            };
            let segment = Segment::straight(0.0, ends, halves, scale);
            segment.spread(&bins, &mut part);
            let total: f64 = part.iter().sum();
            assert!(
                (total - halves[0] - halves[1]).abs() < 1e-14,
                "{ends:?}: {total}"
            );
        }
    }
}

#[cfg(test)]
mod track_tests;
