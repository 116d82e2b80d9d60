//! The relaxation spectrum of a collision generator `M` on a velocity grid
//! (issue 35): how fast each velocity feature of a perturbation `df = f0 g`
//! relaxes, beyond the initial variance rate `Gamma`.
//!
//! With `D = diag(f0)`, detailed balance makes `S = D^(-1/2) M D^(1/2)`
//! symmetric and the H-theorem makes it negative semi-definite; its
//! eigenvalues `-r_k` are the relaxation rates `r_k` of the modes
//! `df_k = D^(1/2) v_k`, and the collision invariants `f0 p(u)` (`p` = 1, `u`,
//! `u^2` for the linearized three-body operator; 1 for the tagged particle)
//! are its zero modes. The estimate keeps the invariants exactly on the left
//! (`p^T M = 0` event by event: deposition keeps number, momentum and energy)
//! but only statistically on the right (`M f0 p = 0` needs detailed balance).
//! So:
//!
//! * the conserved modes are read off the symmetrized estimate before any
//!   projection: the eigenvectors lying most in the invariant subspace, their
//!   eigenvalues (zero in the exact operator) and overlaps; and per invariant
//!   the residual `||S_sym q||` (`q` the unit invariant direction), which
//!   bounds the distance from zero of an eigenvalue of `S_sym` (the Rayleigh
//!   quotient `q^T S_sym q` vanishes exactly, so by the residual theorem for
//!   symmetric matrices an eigenvalue lies within the residual of 0);
//! * the relaxation rates are the eigenvalues of `P S_sym P` (`P` removes the
//!   invariant directions, as `evolve::spectral` does before propagating)
//!   outside the invariant subspace, ascending. A negative rate is a growing
//!   mode of the noisy estimate: the physical operator has none.
//!
//! Units: rates in `rho^2 l v_th` (those of the generator). Pure math: no IO.

use super::propagate::Generator;
use super::spectral::{invariant_basis, project_out, symmetrized};
use crate::linalg::{EigenError, SymmetricEigen, symmetric_eigen};

/// The spectrum of one generator estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// Relaxation rates `r_k = -lambda_k` of the modes orthogonal to the
    /// invariants, ascending, `rho^2 l v_th` (grid nodes minus invariants).
    pub rates: Vec<f64>,
    /// Mirror parity of each mode in the order of `rates`: `sum_i v_i
    /// v_(n-1-i)` of its unit eigenvector `v`, +1 for an even shape
    /// (`g(-u) = g(u)`), -1 for an odd one (the grid is symmetric about 0).
    pub parities: Vec<f64>,
    /// `g_k(u)` at the nodes of the slowest modes (`df_k = f0 g_k`), in the
    /// order of `rates`, normalized to `sum_i f0_i g_k(u_i)^2 = 1`; the sign
    /// is arbitrary (see [`Spectrum::aligned`]).
    pub shapes: Vec<Vec<f64>>,
    /// The conserved modes of the unprojected symmetrized estimate, one per
    /// invariant, eigenvalue ascending.
    pub conserved: Vec<ConservedMode>,
    /// Per invariant, in the order given: `||S_sym q||`, an eigenvalue of
    /// `S_sym` lies within it of zero, `rho^2 l v_th`.
    pub residuals: Vec<f64>,
    /// `||S - S^T||_F / ||S + S^T||_F`: the estimate's detailed-balance violation.
    pub asymmetry: f64,
}

/// An eigenpair of the unprojected symmetrized estimate that lies in the
/// invariant subspace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConservedMode {
    /// Its eigenvalue, `rho^2 l v_th` (zero in the exact operator).
    pub eigenvalue: f64,
    /// Squared length of its projection on the invariant subspace (1: all
    /// of it lies there).
    pub overlap: f64,
}

/// The spectrum of `generator` with equilibrium node masses `equilibrium`
/// (`f0`) and collision invariants `invariants` (velocity polynomials at the
/// nodes), with the shapes of the `shapes` slowest modes. An error when the
/// symmetrized estimate cannot be diagonalized.
pub fn spectrum(
    generator: &Generator,
    equilibrium: &[f64],
    invariants: &[Vec<f64>],
    shapes: usize,
) -> Result<Spectrum, EigenError> {
    let n = generator.size();
    let root: Vec<f64> = equilibrium.iter().map(|f| f.sqrt()).collect();
    let (sym, asymmetry) = symmetrized(generator, &root);
    let basis = invariant_basis(invariants, &root);
    let residuals = basis
        .iter()
        .map(|q| {
            norm(
                &(0..n)
                    .map(|i| dot(&sym[i * n..(i + 1) * n], q))
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    let mut conserved: Vec<ConservedMode> = most_invariant(&symmetric_eigen(&sym, n)?, &basis)
        .into_iter()
        .map(|(eigenvalue, overlap)| ConservedMode {
            eigenvalue,
            overlap,
        })
        .collect();
    conserved.sort_by(|a, b| a.eigenvalue.total_cmp(&b.eigenvalue));
    let mut projected = sym;
    project_out(&mut projected, &basis);
    let (rates, vectors) = relaxing_modes(&symmetric_eigen(&projected, n)?, &basis);
    Ok(Spectrum {
        rates,
        parities: vectors.iter().map(|v| parity(v)).collect(),
        shapes: vectors
            .iter()
            .take(shapes)
            .map(|v| v.iter().zip(&root).map(|(x, r)| x / r).collect())
            .collect(),
        conserved,
        residuals,
        asymmetry,
    })
}

impl Spectrum {
    /// The same spectrum with every shape's sign chosen to agree with the
    /// same-rank shape of `reference` (`sum_i f0_i g_i g_ref_i >= 0`), so that
    /// shapes from different replicates can be averaged.
    pub fn aligned(mut self, reference: &Spectrum, equilibrium: &[f64]) -> Spectrum {
        for (shape, other) in self.shapes.iter_mut().zip(&reference.shapes) {
            let agreement: f64 = shape
                .iter()
                .zip(other)
                .zip(equilibrium)
                .map(|((a, b), f)| a * b * f)
                .sum();
            if agreement < 0.0 {
                shape.iter_mut().for_each(|g| *g = -*g);
            }
        }
        self
    }
}

/// Squared length of `v`'s projection on the span of `basis` (orthonormal).
fn overlap(v: &[f64], basis: &[Vec<f64>]) -> f64 {
    basis.iter().map(|q| dot(v, q).powi(2)).sum()
}

/// Indices of the `basis.len()` eigenvectors with the largest overlap with
/// the invariant subspace, largest first.
fn invariant_indices(eigen: &SymmetricEigen, basis: &[Vec<f64>]) -> Vec<usize> {
    let mut order: Vec<(usize, f64)> = eigen
        .vectors
        .iter()
        .enumerate()
        .map(|(k, v)| (k, overlap(v, basis)))
        .collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    order.iter().take(basis.len()).map(|&(k, _)| k).collect()
}

/// `(eigenvalue, overlap)` of the eigenpairs lying most in the invariant subspace.
fn most_invariant(eigen: &SymmetricEigen, basis: &[Vec<f64>]) -> Vec<(f64, f64)> {
    invariant_indices(eigen, basis)
        .into_iter()
        .map(|k| (eigen.values[k], overlap(&eigen.vectors[k], basis)))
        .collect()
}

/// Rates `-lambda` ascending and the eigenvectors of the modes outside the
/// invariant subspace.
fn relaxing_modes(eigen: &SymmetricEigen, basis: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let invariant = invariant_indices(eigen, basis);
    let mut modes: Vec<(f64, &Vec<f64>)> = (0..eigen.values.len())
        .filter(|k| !invariant.contains(k))
        .map(|k| (-eigen.values[k], &eigen.vectors[k]))
        .collect();
    modes.sort_by(|a, b| a.0.total_cmp(&b.0));
    modes.into_iter().map(|(r, v)| (r, v.clone())).unzip()
}

/// `sum_i v_i v_(n-1-i)`: the overlap of `v` with its mirror image.
fn parity(v: &[f64]) -> f64 {
    v.iter().zip(v.iter().rev()).map(|(a, b)| a * b).sum()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(v: &[f64]) -> f64 {
    dot(v, v).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evolve::grid::VelocityGrid;
    use crate::evolve::operator::balanced_fokker_planck;

    /// The Ornstein-Uhlenbeck generator `D1 = -D u / 2`, `D2 = D` has the
    /// Hermite spectrum `r_k = k D / 2` with `g_k = He_k(u) / sqrt(k!)`; on a
    /// fine grid the slowest rates and shapes approach it, and the number
    /// mode is conserved to rounding (the detailed-balance form keeps the
    /// grid's `f0` stationary exactly).
    #[test]
    fn ornstein_uhlenbeck_has_the_hermite_spectrum() {
        let grid = VelocityGrid::covering(7.0, 0.05);
        let d = 0.3;
        let u = grid.velocities();
        let generator = balanced_fokker_planck(&grid, &vec![d; grid.len()]);
        let equilibrium = grid.maxwellian();
        let found = spectrum(&generator, &equilibrium, &[vec![1.0; grid.len()]], 2).unwrap();
        for k in 1..=4 {
            let exact = f64::from(k) * 0.5 * d;
            let rate = found.rates[k as usize - 1];
            assert!(
                (rate / exact - 1.0).abs() < 2e-3,
                "k = {k}: {rate} vs {exact}"
            );
        }
        let hermite = [
            u.clone(),
            u.iter().map(|x| (x * x - 1.0) / 2f64.sqrt()).collect(),
        ];
        for (shape, exact) in found.shapes.iter().zip(&hermite) {
            let projection: f64 = (0..grid.len())
                .map(|i| equilibrium[i] * shape[i] * exact[i])
                .sum();
            assert!(projection.abs() > 0.999, "{projection}");
        }
        assert_eq!(found.conserved.len(), 1);
        // The detailed-balance form keeps f0 stationary to rounding: the
        // residual, and the eigen-solver's rounding of n EPSILON of the
        // largest rate, bound the number mode's eigenvalue.
        let [mode] = found.conserved[..] else {
            panic!("one invariant")
        };
        let residual = found.residuals[0];
        assert!(residual < 1e-12 * found.rates[0], "{residual}");
        let largest = found.rates.iter().fold(0.0, |m: f64, r| m.max(*r));
        let rounding = grid.len() as f64 * f64::EPSILON * largest;
        assert!(mode.eigenvalue.abs() <= residual + rounding, "{mode:?}");
        assert!(mode.overlap > 1.0 - 1e-6, "{mode:?}");
    }
}
