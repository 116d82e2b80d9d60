//! `h(t) = exp(t M) h(0)` for a dense generator `M` by scaling and squaring:
//! `exp(A) = exp(A / 2^s)^(2^s)` with `||A / 2^s||_1 <= 1/2`, and the Taylor
//! series of `exp(A / 2^s)` summed until a term falls below `1e-17` of the
//! sum (in the 1-norm): the remaining terms are then below that term times
//! `sum_j (1/2)^j / (k+1)^j`, at the level of rounding.
//!
//! The generators of collisions are stiff: their fastest rates are the
//! collision rates of kicks larger than a grid step (~1 in `rho^2 l v_th`),
//! their slowest the relaxation rates (~`a_n` ~ 3e-4), so a time-stepping
//! method needs ~`t * 1` steps where scaling and squaring needs ~`log2(t)`
//! matrix products, and the result is the exact semigroup for any `t`.

use crate::stats::Entries;

/// A dense square matrix, row-major: `entry(i, j)` is the rate from node `j` to node `i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Generator {
    size: usize,
    entries: Vec<f64>,
}

/// Means over replicates entry by entry (`stats::replicate_means`).
impl Entries for Generator {
    fn entries(&self) -> &[f64] {
        &self.entries
    }

    fn entries_mut(&mut self) -> &mut [f64] {
        &mut self.entries
    }

    /// `sum * (1 / count)`, not the default `sum / count`: the two differ in
    /// the last bit unless `count` is a power of two, and the `evolve`
    /// stage's files are made this way (unifying them is a version bump).
    fn mean(sum: Generator, count: usize) -> Generator {
        sum.scaled(1.0 / count as f64)
    }
}

/// Largest `||A / 2^s||_1` whose Taylor series is summed.
const SCALED_NORM: f64 = 0.5;
/// A term this small relative to the sum ends the series.
const TERM_TOLERANCE: f64 = 1e-17;
/// Safety bound on the number of Taylor terms (~16 are needed at norm 1/2).
const MAX_TERMS: usize = 40;

impl Generator {
    /// The generator whose column `j` is `columns[j]`.
    pub fn from_columns(columns: &[Vec<f64>]) -> Generator {
        let size = columns.len();
        let mut entries = vec![0.0; size * size];
        for (j, column) in columns.iter().enumerate() {
            for (i, &value) in column.iter().enumerate() {
                entries[i * size + j] = value;
            }
        }
        Generator { size, entries }
    }

    /// Number of nodes.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Rate from node `j` to node `i`.
    pub fn entry(&self, i: usize, j: usize) -> f64 {
        self.entries[i * self.size + j]
    }

    /// Column `j`.
    pub fn column(&self, j: usize) -> Vec<f64> {
        (0..self.size).map(|i| self.entry(i, j)).collect()
    }

    /// `factor * M`.
    pub fn scaled(mut self, factor: f64) -> Generator {
        self.entries.iter_mut().for_each(|a| *a *= factor);
        self
    }

    /// `M v`.
    pub fn apply(&self, v: &[f64]) -> Vec<f64> {
        self.entries
            .chunks_exact(self.size)
            .map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// `||M||_1`: the largest column sum of absolute values.
    pub fn norm_1(&self) -> f64 {
        (0..self.size)
            .map(|j| (0..self.size).map(|i| self.entry(i, j).abs()).sum::<f64>())
            .fold(0.0, f64::max)
    }

    /// The identity.
    pub fn identity(size: usize) -> Generator {
        let mut entries = vec![0.0; size * size];
        (0..size).for_each(|i| entries[i * size + i] = 1.0);
        Generator { size, entries }
    }

    /// The matrix product `self * other`.
    pub fn product(&self, other: &Generator) -> Generator {
        let n = self.size;
        let mut entries = vec![0.0; n * n];
        for (row, out) in self
            .entries
            .chunks_exact(n)
            .zip(entries.chunks_exact_mut(n))
        {
            for (&a, other_row) in row.iter().zip(other.entries.chunks_exact(n)) {
                out.iter_mut().zip(other_row).for_each(|(c, b)| *c += a * b);
            }
        }
        Generator { size: n, entries }
    }

    /// `exp(dt M)` by scaling and squaring.
    pub fn exponential(&self, dt: f64) -> Generator {
        let norm = self.norm_1() * dt;
        let squarings = libm::log2(norm / SCALED_NORM).ceil().max(0.0) as i32;
        let scaled = self.clone().scaled(dt / 2f64.powi(squarings));
        let mut sum = Generator::identity(self.size);
        let mut term = sum.clone();
        for k in 1..=MAX_TERMS {
            term = term.product(&scaled).scaled(1.0 / k as f64);
            sum.entries
                .iter_mut()
                .zip(&term.entries)
                .for_each(|(s, t)| *s += t);
            if term.norm_1() <= TERM_TOLERANCE * sum.norm_1() {
                break;
            }
        }
        (0..squarings).fold(sum, |e, _| e.product(&e))
    }

    /// `exp(t M) h0` at every time of `times` (ascending, >= 0), carrying the
    /// state from one time to the next.
    pub fn propagate(&self, h0: &[f64], times: &[f64]) -> Vec<Vec<f64>> {
        let mut state = h0.to_vec();
        let mut now = 0.0;
        times
            .iter()
            .map(|&time| {
                if time > now {
                    state = self.exponential(time - now).apply(&state);
                    now = time;
                }
                state.clone()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two states with rates `a` (0 -> 1) and `b` (1 -> 0): the population of
    /// state 0 is `b/(a+b) + a/(a+b) exp(-(a+b) t)` from `(1, 0)`, to rounding.
    #[test]
    fn two_state_relaxation_is_exact() {
        let (a, b) = (3.0, 0.5);
        let generator = Generator::from_columns(&[vec![-a, a], vec![b, -b]]);
        let times = [0.0, 0.01, 0.3, 2.0, 40.0];
        let states = generator.propagate(&[1.0, 0.0], &times);
        for (state, t) in states.iter().zip(times) {
            let exact = b / (a + b) + a / (a + b) * libm::exp(-(a + b) * t);
            // Squaring s times amplifies rounding by ~2^s < 4 ||M||_1 t.
            let bound = 1e-15 + f64::EPSILON * 4.0 * generator.norm_1() * t;
            assert!(
                (state[0] - exact).abs() < bound,
                "t {t}: {} vs {exact}",
                state[0]
            );
            assert!((state[0] + state[1] - 1.0).abs() < bound, "{state:?}");
        }
    }

    /// A rotation generator keeps the norm: `exp(t [[0, -w], [w, 0]])`.
    #[test]
    fn oscillation_is_exact_over_many_periods() {
        let w = 2.0;
        let generator = Generator::from_columns(&[vec![0.0, w], vec![-w, 0.0]]);
        let t = 100.0;
        let state = &generator.propagate(&[1.0, 0.0], &[t])[0];
        assert!((state[0] - libm::cos(w * t)).abs() < 1e-12, "{state:?}");
        assert!((state[1] - libm::sin(w * t)).abs() < 1e-12, "{state:?}");
    }
}
