//! The Dirichlet forms `A = sum mu Delta Delta^T` of placed collision images
//! on a velocity grid ([`super::operator::balanced_generators`]): `mu` an
//! image's equilibrium measure at every node, `Delta` its deposited change
//! seen from that node. Stored by diagonal (`form[d * n + a] = A[a][a + d]`,
//! the upper triangle of the symmetric `A`), so that a change whose pattern
//! shifts with the node adds to contiguous runs along the nodes.
//!
//! A deposit seen from node `j` is its stencil's three entries shifted to
//! `j` while they lie inside the grid, and a reflected deposit at a fixed end
//! node beyond that ([`VelocityGrid::stencil_entries`]). So the nodes fall
//! into segments on which every deposit is either shifted or fixed: on each,
//! `Delta_j = R_j + F` (`R` the shifted part, `F` the fixed one) and
//! `sum mu_j Delta_j Delta_j^T` is the runs of `R R^T`, the cross runs of
//! `R F^T`, and `F F^T` times the segment's measure. Only the one node per
//! deposit and end where a reflected stencil straddles the end is added node
//! by node.

use super::grid::{Stencil, VelocityGrid};
use super::operator::Generators;
use super::propagate::Generator;

/// At most this many deposits make one change (three particles, each from
/// its incoming to its outgoing velocity).
const DEPOSITS: usize = 6;

/// Entries of one change: three per deposit.
const ENTRIES: usize = 3 * DEPOSITS;

/// A deposit of one image: its stencil and its sign (`-1` for an incoming
/// velocity, `+1` for an outgoing one).
type Deposit = (Stencil, f64);

/// (node or node offset, weight) entries of a change, with their count.
struct Entries {
    entries: [(i64, f64); ENTRIES],
    len: usize,
}

impl Entries {
    fn new() -> Entries {
        Entries {
            entries: [(0, 0.0); ENTRIES],
            len: 0,
        }
    }

    fn push(&mut self, entry: (i64, f64)) {
        self.entries[self.len] = entry;
        self.len += 1;
    }

    /// The entries with their nodes merged (distinct nodes).
    fn merged(&mut self, merger: &mut Merger) -> &[(i64, f64)] {
        let len = merger.merged(&mut self.entries[..self.len]);
        &self.entries[..len]
    }
}

/// The summed forms of one set of images: of every particle's own change
/// (tagged) and of their sum (full).
pub struct DirichletForms {
    /// The grid's `f0` (node masses).
    equilibrium: Vec<f64>,
    /// `A` of the full changes, by diagonal.
    full: Vec<f64>,
    /// `A` of the particles' own changes, by diagonal.
    tagged: Vec<f64>,
    merger: Merger,
    /// The measure of the image being added, per node (kept for reuse).
    measures: Vec<f64>,
}

impl DirichletForms {
    /// Zero forms on `grid`.
    pub fn new(grid: &VelocityGrid) -> DirichletForms {
        let n = grid.len();
        DirichletForms {
            equilibrium: grid.maxwellian(),
            full: vec![0.0; n * n],
            tagged: vec![0.0; n * n],
            merger: Merger::new(n),
            measures: Vec::with_capacity(n),
        }
    }

    /// Adds an image with launch weight `weights` at every node's `u'` and
    /// the moves of its particles (`[from, to]` stencils, relative to the
    /// node; `None` for a particle whose velocity is unchanged): its measure
    /// at node `j` is `f0_j weights_j`.
    pub fn add(&mut self, grid: &VelocityGrid, weights: &[f64], moves: &[Option<[Stencil; 2]>]) {
        let mut measures = std::mem::take(&mut self.measures);
        measures.clear();
        measures.extend(self.equilibrium.iter().zip(weights).map(|(f0, w)| f0 * w));
        self.add_measured(grid, &measures, moves);
        self.measures = measures;
    }

    /// Adds an image of measure `measures` (one per node): to the tagged
    /// form each particle's own change, to the full form their sum.
    fn add_measured(
        &mut self,
        grid: &VelocityGrid,
        measures: &[f64],
        moves: &[Option<[Stencil; 2]>],
    ) {
        let Some([first, _]) = moves.iter().flatten().next() else {
            return;
        };
        let mut all = [(*first, 0.0); DEPOSITS];
        let mut count = 0;
        for &[from, to] in moves.iter().flatten() {
            let own = [(from, -1.0), (to, 1.0)];
            all[count..count + 2].copy_from_slice(&own);
            count += 2;
            add_pattern(&mut self.tagged, grid, &own, measures, &mut self.merger);
        }
        add_pattern(
            &mut self.full,
            grid,
            &all[..count],
            measures,
            &mut self.merger,
        );
    }

    /// `M = -A D^(-1) / 6` of both forms.
    pub fn generators(&self) -> Generators {
        let n = self.equilibrium.len();
        let generator = |form: &[f64]| {
            let columns: Vec<Vec<f64>> = (0..n)
                .map(|j| {
                    (0..n)
                        .map(|i| -entry(form, n, i, j) / (6.0 * self.equilibrium[j]))
                        .collect()
                })
                .collect();
            Generator::from_columns(&columns)
        };
        Generators {
            full: generator(&self.full),
            tagged: generator(&self.tagged),
        }
    }
}

/// `A[a][b]` of an `n x n` form stored by diagonal.
fn entry(form: &[f64], n: usize, a: usize, b: usize) -> f64 {
    form[a.abs_diff(b) * n + a.min(b)]
}

/// Adds `sum_j mu_j Delta_j Delta_j^T` over every node `j` to the
/// diagonal-stored `form`, `Delta_j` the `deposits` seen from node `j` and
/// `mu_j` = `measures[j]`: segment by segment (module doc).
fn add_pattern(
    form: &mut [f64],
    grid: &VelocityGrid,
    deposits: &[Deposit],
    measures: &[f64],
    merger: &mut Merger,
) {
    let n = grid.len();
    let mut cuts = [0usize; 4 * DEPOSITS + 2];
    cuts[1] = n;
    for (k, (stencil, _)) in deposits.iter().enumerate() {
        let interior = grid.interior_nodes(stencil);
        let (lo, hi) = (*interior.start(), *interior.end());
        let bounds = [lo - 1, lo, hi + 1, hi + 2].map(|c| c.clamp(0, n as i64) as usize);
        cuts[2 + 4 * k..6 + 4 * k].copy_from_slice(&bounds);
    }
    let cuts = &mut cuts[..2 + 4 * deposits.len()];
    cuts.sort_unstable();
    let mut start = 0;
    for &end in cuts.iter().filter(|&&c| c > 0) {
        if end > start {
            let segment = Segment {
                first: start,
                measures: &measures[start..end],
                n,
            };
            segment.add(form, grid, deposits, merger);
            start = end;
        }
    }
}

/// Consecutive nodes `first ..` on which every deposit is either shifted
/// with the node or fixed, with their measures.
struct Segment<'a> {
    first: usize,
    measures: &'a [f64],
    n: usize,
}

impl Segment<'_> {
    /// Adds the segment's `sum mu_j Delta_j Delta_j^T`: a single node
    /// directly, a longer segment by its shifted and fixed parts.
    fn add(
        &self,
        form: &mut [f64],
        grid: &VelocityGrid,
        deposits: &[Deposit],
        merger: &mut Merger,
    ) {
        let mut fixed = Entries::new();
        if self.measures.len() == 1 {
            for &(stencil, sign) in deposits {
                for (k, w) in grid.stencil_entries(self.first, &stencil) {
                    fixed.push((k as i64, sign * w));
                }
            }
            add_at(form, self.n, fixed.merged(merger), self.measures[0]);
            return;
        }
        let mut shifted = Entries::new();
        for &(stencil, sign) in deposits {
            if grid.interior_nodes(&stencil).contains(&(self.first as i64)) {
                stencil
                    .relative_entries()
                    .into_iter()
                    .for_each(|(k, w)| shifted.push((k, sign * w)));
            } else {
                grid.stencil_entries(self.first, &stencil)
                    .into_iter()
                    .filter(|&(_, w)| w != 0.0)
                    .for_each(|(k, w)| fixed.push((k as i64, sign * w)));
            }
        }
        let shifted = shifted.merged(merger);
        self.add_shifted(form, shifted);
        let fixed = fixed.merged(merger);
        if !fixed.is_empty() {
            add_at(form, self.n, fixed, self.measures.iter().sum());
            self.add_cross(form, shifted, fixed);
        }
    }

    /// Adds `mu_j R_j R_j^T` for every node `j`, `R_j` the `shifted` entries
    /// (node offsets from `j` and weights, distinct offsets) shifted to `j`:
    /// each product along a contiguous run of one diagonal.
    fn add_shifted(&self, form: &mut [f64], shifted: &[(i64, f64)]) {
        for (p, &(a, x)) in shifted.iter().enumerate() {
            for &(b, y) in &shifted[p..] {
                let start = (self.first as i64 + a.min(b)) as usize;
                let diagonal = a.abs_diff(b) as usize * self.n + start;
                let run = &mut form[diagonal..diagonal + self.measures.len()];
                let product = x * y;
                for (slot, measure) in run.iter_mut().zip(self.measures) {
                    *slot += measure * product;
                }
            }
        }
    }

    /// Adds the cross terms `mu_j (R_j F^T + F R_j^T)` for every node `j`:
    /// each pair of a shifted entry (at node `j + a`) and a fixed one (at
    /// node `b`) once to the upper triangle, twice where they meet on the
    /// diagonal.
    fn add_cross(&self, form: &mut [f64], shifted: &[(i64, f64)], fixed: &[(i64, f64)]) {
        let n = self.n as i64;
        let nodes = self.first as i64..(self.first + self.measures.len()) as i64;
        for &(a, x) in shifted {
            for &(b, y) in fixed {
                let product = x * y;
                // The shifted entry's node `j + a` below `b`, at `b`, above it.
                let meets = (b - a).clamp(nodes.start, nodes.end);
                let measure = |j: i64| self.measures[(j - nodes.start) as usize] * product;
                for j in nodes.start..meets {
                    form[((b - j - a) * n + j + a) as usize] += measure(j);
                }
                if meets < nodes.end && meets == b - a {
                    form[b as usize] += 2.0 * measure(meets);
                }
                for j in (b - a + 1).max(nodes.start)..nodes.end {
                    form[((j + a - b) * n + b) as usize] += measure(j);
                }
            }
        }
    }
}

/// Adds `measure Delta Delta^T` to the diagonal-stored `n x n` `form`,
/// `Delta` given as (node, weight) entries with distinct nodes.
fn add_at(form: &mut [f64], n: usize, change: &[(i64, f64)], measure: f64) {
    for (p, &(a, x)) in change.iter().enumerate() {
        let scaled = measure * x;
        for &(b, y) in &change[p..] {
            form[a.abs_diff(b) as usize * n + a.min(b) as usize] += scaled * y;
        }
    }
}

/// Sums (node, weight) entries by node in place, the nodes in the order
/// they first appear (no sorting: a change has at most 18 entries).
struct Merger {
    /// Per node (offset by `offset`), the call that last saw it.
    seen: Vec<u64>,
    /// Per node, where its sum stands.
    slot: Vec<usize>,
    call: u64,
    /// Added to a node (or a node offset, from `-n`) to index `seen`.
    offset: i64,
}

impl Merger {
    fn new(n: usize) -> Merger {
        Merger {
            seen: vec![0; 3 * n],
            slot: vec![0; 3 * n],
            call: 0,
            offset: n as i64,
        }
    }

    /// Merges `entries` into their leading part, whose length it returns.
    fn merged(&mut self, entries: &mut [(i64, f64)]) -> usize {
        self.call += 1;
        let mut merged = 0;
        for i in 0..entries.len() {
            let (node, weight) = entries[i];
            let key = (node + self.offset) as usize;
            if self.seen[key] == self.call {
                entries[self.slot[key]].1 += weight;
            } else {
                self.seen[key] = self.call;
                self.slot[key] = merged;
                entries[merged] = (node, weight);
                merged += 1;
            }
        }
        merged
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// `sum_j mu_j Delta_j Delta_j^T` node by node, every deposit through
    /// [`VelocityGrid::stencil_entries`]: the definition.
    fn node_by_node(grid: &VelocityGrid, deposits: &[Deposit], measures: &[f64]) -> Vec<Vec<f64>> {
        let n = grid.len();
        let mut form = vec![vec![0.0; n]; n];
        for (j, &measure) in measures.iter().enumerate() {
            let mut change = vec![0.0; n];
            for &(stencil, sign) in deposits {
                for (k, w) in grid.stencil_entries(j, &stencil) {
                    change[k] += sign * w;
                }
            }
            for a in 0..n {
                for b in 0..n {
                    form[a][b] += measure * change[a] * change[b];
                }
            }
        }
        form
    }

    /// The segmented sums equal the node-by-node definition to rounding,
    /// for moves that stay inside the grid, reach beyond either end, or
    /// straddle an end (stencils at every offset up to twice the grid), on
    /// both forms.
    #[test]
    fn segments_add_what_the_nodes_add() {
        let grid = VelocityGrid::covering(1.5, 0.1);
        let n = grid.len();
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let measures: Vec<f64> = (0..n).map(|_| rng.random_range(0.1..1.0)).collect();
        for _ in 0..200 {
            let moves: Vec<Option<[Stencil; 2]>> = (0..rng.random_range(1..=3))
                .map(|_| {
                    let from = rng.random_range(-3.2..3.2);
                    let to = from + rng.random_range(-0.4..0.4);
                    Some([grid.stencil(from), grid.stencil(to)])
                })
                .collect();
            let mut forms = DirichletForms::new(&grid);
            forms.add_measured(&grid, &measures, &moves);
            let all: Vec<Deposit> = moves
                .iter()
                .flatten()
                .flat_map(|&[from, to]| [(from, -1.0), (to, 1.0)])
                .collect();
            let full = node_by_node(&grid, &all, &measures);
            let mut tagged = vec![vec![0.0; n]; n];
            for own in all.chunks(2) {
                let part = node_by_node(&grid, own, &measures);
                (0..n).for_each(|a| (0..n).for_each(|b| tagged[a][b] += part[a][b]));
            }
            for (form, expected) in [(&forms.full, full), (&forms.tagged, tagged)] {
                let scale = expected
                    .iter()
                    .flatten()
                    .fold(0.0f64, |m, x| m.max(x.abs()));
                for (a, row) in expected.iter().enumerate() {
                    for (b, &wanted) in row.iter().enumerate().skip(a) {
                        let found = entry(form, n, a, b);
                        assert!(
                            (found - wanted).abs() <= 1e-13 * scale,
                            "A[{a}][{b}] = {found}, node by node {wanted}"
                        );
                    }
                }
            }
        }
    }
}
