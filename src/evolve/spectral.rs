//! The linearized collision operator as the physics constrains it: with
//! `D = diag(f0)` it is self-adjoint in the `1/f0`-weighted inner product
//! (detailed balance, `M_ij f0_j = M_ji f0_i`), annihilates the collision
//! invariants `f0 {1, u, u^2}` and has no positive eigenvalue (H-theorem).
//! A Monte Carlo estimate keeps the conservation laws exactly, but its noise
//! breaks the other two properties, and the full operator's estimate then has
//! growing modes (measured: `||exp(t M)||_1` reaches 1e6 at `t = 10/Gamma`
//! with 6.5e4 scenes). [`Dissipative::project`] imposes them: symmetrize
//! `S = D^(-1/2) M D^(1/2)`, project out the invariants, diagonalize, and set
//! positive eigenvalues (noise) to zero. Then `exp(t M)` is exact for any `t`
//! through the eigenvectors, and conserves the invariants exactly.
//!
//! How much the clipping removed is [`Dissipative::largest_clipped`], the
//! largest eigenvalue set to zero, beside the estimate's detailed-balance
//! violation [`Dissipative::asymmetry`].

use super::propagate::Generator;
use crate::linalg::{EigenError, SymmetricEigen, symmetric_eigen};

/// A generator with detailed balance, exact invariants and no growing mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Dissipative {
    /// `sqrt(f0)` at the nodes.
    root: Vec<f64>,
    /// Eigen-decomposition of the symmetrized, projected `S`, eigenvalues as
    /// estimated (not clipped: [`Dissipative::propagate`] clips them).
    eigen: SymmetricEigen,
    /// Largest eigenvalue set to zero (noise), `rho^2 l v_th`; 0 if none.
    pub largest_clipped: f64,
    /// `||S - S^T||_F / ||S + S^T||_F` of the estimate: its detailed-balance violation.
    pub asymmetry: f64,
}

impl Dissipative {
    /// Imposes detailed balance with respect to `equilibrium` (node masses of
    /// `f0`), the invariants `invariants` (velocity polynomials at the nodes,
    /// e.g. `1, u, u^2`; the operator annihilates `f0` times each) and
    /// dissipation on the estimate `generator`. An error, never a silently
    /// wrong projection, when the symmetrized estimate cannot be
    /// diagonalized (a non-finite entry, or QR iterations that do not
    /// converge).
    pub fn project(
        generator: &Generator,
        equilibrium: &[f64],
        invariants: &[Vec<f64>],
    ) -> Result<Dissipative, EigenError> {
        let n = generator.size();
        let root: Vec<f64> = equilibrium.iter().map(|f| f.sqrt()).collect();
        let (mut sym, asymmetry) = symmetrized(generator, &root);
        project_out(&mut sym, &invariant_basis(invariants, &root));
        let eigen = symmetric_eigen(&sym, n)?;
        let largest_clipped = eigen.values.iter().copied().fold(0.0, f64::max);
        Ok(Dissipative {
            root,
            eigen,
            largest_clipped,
            asymmetry,
        })
    }

    /// `exp(t M) h0` at every time of `times`, with the positive eigenvalues
    /// set to zero: `h(t) = D^(1/2) sum_k c_k exp(min(lambda_k, 0) t) v_k`,
    /// `c_k = v_k . D^(-1/2) h0` (`v_k`, `lambda_k`: eigenvectors and
    /// eigenvalues of the projected `S`).
    pub fn propagate(&self, h0: &[f64], times: &[f64]) -> Vec<Vec<f64>> {
        times
            .iter()
            .map(|&t| self.superpose(h0, |lambda| libm::exp(lambda.min(0.0) * t)))
            .collect()
    }

    /// `D^(1/2) sum_k c_k gain(lambda_k) v_k` with `c_k = v_k . D^(-1/2) h0`.
    fn superpose(&self, h0: &[f64], gain: impl Fn(f64) -> f64) -> Vec<f64> {
        let g0: Vec<f64> = h0.iter().zip(&self.root).map(|(h, r)| h / r).collect();
        let mut g = vec![0.0; g0.len()];
        for (v, &lambda) in self.eigen.vectors.iter().zip(&self.eigen.values) {
            let factor = gain(lambda);
            if factor == 0.0 {
                continue;
            }
            let weight = factor * v.iter().zip(&g0).map(|(a, b)| a * b).sum::<f64>();
            g.iter_mut().zip(v).for_each(|(x, y)| *x += weight * y);
        }
        g.iter().zip(&self.root).map(|(x, r)| x * r).collect()
    }
}

/// The symmetric part `(S + S^T) / 2` of `S = D^(-1/2) M D^(1/2)` (`root`:
/// `sqrt(f0)` at the nodes; row-major), and the estimate's detailed-balance
/// violation `||S - S^T||_F / ||S + S^T||_F`.
pub(super) fn symmetrized(generator: &Generator, root: &[f64]) -> (Vec<f64>, f64) {
    let n = generator.size();
    let s = |i: usize, j: usize| generator.entry(i, j) * root[j] / root[i];
    let mut sym = vec![0.0; n * n];
    let (mut odd, mut even) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let (a, b) = (s(i, j), s(j, i));
            sym[i * n + j] = 0.5 * (a + b);
            odd += (a - b).powi(2);
            even += (a + b).powi(2);
        }
    }
    (sym, (odd / even).sqrt())
}

/// Orthonormal basis (Gram-Schmidt, in the order given) of the invariant
/// directions `root * p(u)`: in the symmetrized frame, `f0 p(u)`.
pub(super) fn invariant_basis(invariants: &[Vec<f64>], root: &[f64]) -> Vec<Vec<f64>> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for p in invariants {
        let mut q: Vec<f64> = p.iter().zip(root).map(|(x, r)| x * r).collect();
        for b in &basis {
            let dot: f64 = q.iter().zip(b).map(|(x, y)| x * y).sum();
            q.iter_mut().zip(b).for_each(|(x, y)| *x -= dot * y);
        }
        let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        q.iter_mut().for_each(|x| *x /= norm);
        basis.push(q);
    }
    basis
}

/// `P A P` in place, `P = 1 - sum_q q q^T` over the orthonormal `basis`
/// (`a`: row-major, square).
pub(super) fn project_out(a: &mut [f64], basis: &[Vec<f64>]) {
    let n = basis.first().map_or(0, Vec::len);
    for q in basis {
        for i in 0..n {
            let dot: f64 = (0..n).map(|j| a[i * n + j] * q[j]).sum();
            (0..n).for_each(|j| a[i * n + j] -= dot * q[j]);
        }
        for j in 0..n {
            let dot: f64 = (0..n).map(|i| a[i * n + j] * q[i]).sum();
            (0..n).for_each(|i| a[i * n + j] -= dot * q[i]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-state generator in detailed balance with `(b, a)/(a+b)` is kept
    /// as it is and propagated exactly.
    #[test]
    fn a_balanced_generator_is_unchanged() {
        let (a, b) = (3.0, 0.5);
        let generator = Generator::from_columns(&[vec![-a, a], vec![b, -b]]);
        let equilibrium = [b / (a + b), a / (a + b)];
        let projected = Dissipative::project(&generator, &equilibrium, &[vec![1.0, 1.0]]).unwrap();
        assert!(projected.asymmetry < 1e-15 && projected.largest_clipped < 1e-15);
        for t in [0.1, 2.0, 50.0] {
            let h = &projected.propagate(&[1.0, 0.0], &[t])[0];
            let exact = b / (a + b) + a / (a + b) * libm::exp(-(a + b) * t);
            assert!((h[0] - exact).abs() < 1e-14, "{} vs {exact}", h[0]);
        }
    }

    /// An estimate with a non-finite rate has no projection: an error, not a
    /// panic.
    #[test]
    fn a_non_finite_generator_is_an_error() {
        let generator = Generator::from_columns(&[vec![f64::NAN, 1.0], vec![1.0, -1.0]]);
        assert_eq!(
            Dissipative::project(&generator, &[0.5, 0.5], &[vec![1.0, 1.0]]),
            Err(EigenError::NotFinite)
        );
    }
}
