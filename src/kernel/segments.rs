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
//! the kick interpolated between the nodes, exponentially when both kicks
//! have one sign (exact for a power-law tail, `kick ~ e^(-(n+1) s)`),
//! linearly otherwise, with a mass density along the segment interpolated
//! exponentially between the two node weights (`dtau/ds = T cosh(s)`), and
//! every bin the kick passes through receives the measure of its share.

use crate::binning::Bins;

/// Most bins one segment is spread over. A segment that spans more (the kick
/// changing fast, in the core of the collision, where bins are fed by many
/// nodes anyway) keeps the trapezoid's point masses at its two nodes.
pub const MAX_SEGMENT_BINS: f64 = 64.0;

/// One velocity track (a sorted rank of the outgoing velocities) between two
/// consecutive nodes of a launch pair. Velocities relative to `u'`, `v_th`;
/// masses in the kernel's weight units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The incoming velocity the track is matched with: kicks are measured from it.
    pub matched: f64,
    /// Outgoing velocities at the two nodes.
    pub ends: [f64; 2],
    /// The masses the two nodes give the segment (half their trapezoid weights).
    pub halves: [f64; 2],
}

impl Segment {
    /// Adds the segment's mass to the bins of `part` (`bins` around `u'`).
    pub fn spread(&self, bins: &Bins, part: &mut [f64]) {
        let [a, b] = self.ends;
        let total = self.halves[0] + self.halves[1];
        let (first, last) = (bins.index(a), bins.index(b));
        if (b - a).abs() > MAX_SEGMENT_BINS * bins.width {
            for (index, half) in [first, last].into_iter().zip(self.halves) {
                if let Some(k) = index {
                    part[k] += half;
                }
            }
            return;
        }
        if first == last {
            if let Some(k) = first {
                part[k] += total;
            }
            return;
        }
        let (low, high) = (a.min(b), a.max(b));
        let (low_bin, high_bin) = (
            (low / bins.width).round() as i64,
            (high / bins.width).round() as i64,
        );
        for bin in low_bin..=high_bin {
            let Some(k) = bins.index(bin as f64 * bins.width) else {
                continue;
            };
            let centre = bins.centre(k);
            let lower = (centre - 0.5 * bins.width).max(low);
            let upper = (centre + 0.5 * bins.width).min(high);
            let share = (self.mass_fraction(self.position(upper))
                - self.mass_fraction(self.position(lower)))
            .abs();
            part[k] += total * share;
        }
    }

    /// Position `t` in `[0, 1]` along the segment where the track has the
    /// outgoing velocity `velocity` (within the segment's range).
    fn position(&self, velocity: f64) -> f64 {
        let [a, b] = self.ends.map(|v| v - self.matched);
        let kick = velocity - self.matched;
        let t = if a * b > 0.0 && kick * a > 0.0 {
            (kick / a).ln() / (b / a).ln()
        } else {
            (kick - a) / (b - a)
        };
        t.clamp(0.0, 1.0)
    }

    /// Fraction of the segment's mass between its first node and position
    /// `t`, the density interpolated exponentially between the node masses.
    fn mass_fraction(&self, t: f64) -> f64 {
        let [first, second] = self.halves;
        let log_ratio = (second / first).ln();
        if !log_ratio.is_finite() || log_ratio.abs() < 1e-9 {
            return t;
        }
        (t * log_ratio).exp_m1() / log_ratio.exp_m1()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A power-law tail `kick = c e^(-7 s)` with `dtau/ds ~ e^s`: segments
    /// between nodes 0.125 apart, each carrying its exact measure, put into
    /// each bin the exact measure of the offsets whose kick lands there (to
    /// 1e-9), where the nodes as point masses miss most bins.
    #[test]
    fn a_power_law_tail_lands_exactly() {
        let bins = Bins::for_window(0.01, 5e-5);
        let (c, h) = (2e-3, 0.125);
        let kick = |s: f64| c * (-7.0 * s).exp();
        let weight = |s: f64| h * s.exp();
        let nodes: Vec<f64> = (0..24).map(|k| f64::from(k) * h).collect();
        let mut spread = vec![0.0; bins.len()];
        let mut points = vec![0.0; bins.len()];
        for pair in nodes.windows(2) {
            // Node masses in the ratio of dtau/ds, summing to the segment's exact measure.
            let exact = pair[1].exp() - pair[0].exp();
            let scale = exact / (pair[0].exp() + pair[1].exp());
            Segment {
                matched: 0.0,
                ends: [kick(pair[0]), kick(pair[1])],
                halves: [scale * pair[0].exp(), scale * pair[1].exp()],
            }
            .spread(&bins, &mut spread);
            points[bins.index(kick(pair[0])).unwrap()] += weight(pair[0]);
        }
        // Exact: the measure int e^s ds of the s where the kick lies in the bin.
        let s_at = |velocity: f64| (c / velocity).ln() / 7.0;
        let first_full = bins.index(kick(0.0)).unwrap() - 1;
        let mut missed = 0;
        for k in bins.index(kick(nodes[23])).unwrap() + 1..=first_full {
            let centre = bins.centre(k);
            let (low, high) = (centre - 2.5e-5, centre + 2.5e-5);
            let exact = s_at(low).exp() - s_at(high).exp();
            assert!(
                (spread[k] - exact).abs() < 1e-9 * exact,
                "bin {centre}: {} vs {exact}",
                spread[k]
            );
            missed += usize::from(points[k] == 0.0);
        }
        assert!(missed > 10, "point masses missed only {missed} bins");
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
            let segment = Segment {
                matched: 0.0,
                ends,
                halves,
            };
            segment.spread(&bins, &mut part);
            let total: f64 = part.iter().sum();
            assert!(
                (total - halves[0] - halves[1]).abs() < 1e-14,
                "{ends:?}: {total}"
            );
        }
    }

    /// A segment spanning more than `MAX_SEGMENT_BINS` bins keeps point masses.
    #[test]
    fn wide_segments_keep_their_nodes() {
        let bins = Bins::for_window(0.02, 5e-5);
        let mut part = vec![0.0; bins.len()];
        Segment {
            matched: 0.0,
            ends: [1e-4, 8e-3],
            halves: [0.25, 0.75],
        }
        .spread(&bins, &mut part);
        assert_eq!(part[bins.index(1e-4).unwrap()], 0.25);
        assert_eq!(part[bins.index(8e-3).unwrap()], 0.75);
        assert_eq!(part.iter().filter(|&&v| v != 0.0).count(), 2);
    }
}
