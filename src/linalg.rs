//! Dense linear algebra the physics needs: the symmetric eigenproblem (through
//! nalgebra, behind our own types and error), used for the dissipative projection
//! of collision generators and for the Lax matrix of the Sutherland ring;
//! the composite Simpson weights of the quadratures (bound-pair length,
//! averages over thermal starts); and the node slopes of the not-a-knot cubic
//! spline (a tridiagonal solve), the derivative of measured rates on a grid;
//! the Cholesky factor of a covariance, for chi-squares and least squares
//! with correlated entries. Pure math: no IO.

/// Eigenvalues and orthonormal eigenvectors of a symmetric matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetricEigen {
    /// Eigenvalues.
    pub values: Vec<f64>,
    /// Eigenvectors, `vectors[k]` belonging to `values[k]`.
    pub vectors: Vec<Vec<f64>>,
}

/// Implicit QR iterations [`symmetric_eigen`] allows per row before it gives
/// up: LAPACK's `dsteqr` allows 30, and needs about 2 (Golub & Van Loan,
/// Matrix Computations, §8.3).
const QR_ITERATIONS_PER_ROW: usize = 30;

/// Why [`symmetric_eigen`] returned no decomposition.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// An entry is NaN or infinite (or the squared norm overflows).
    #[error("the symmetric eigenproblem has a non-finite matrix entry")]
    NotFinite,
    /// The QR iterations did not converge.
    #[error("the symmetric eigenproblem did not converge in {iterations} QR iterations")]
    Unconverged {
        /// Iterations allowed.
        iterations: usize,
    },
}

/// Eigenvalues (in no particular order) and orthonormal eigenvectors of the
/// symmetric matrix `a` (row-major, `n x n`): nalgebra's Householder
/// tridiagonalization and implicit QR with Wilkinson shifts (Golub & Van
/// Loan, Matrix Computations, §8.3), to `eps` of the matrix. An error, never
/// a silent unconverged result, when an entry is not finite or the iterations
/// exceed `QR_ITERATIONS_PER_ROW` per row.
pub fn symmetric_eigen(a: &[f64], n: usize) -> Result<SymmetricEigen, EigenError> {
    qr_eigen(a, n, QR_ITERATIONS_PER_ROW * n)
}

/// [`symmetric_eigen`] with at most `iterations` QR iterations in all.
fn qr_eigen(a: &[f64], n: usize, iterations: usize) -> Result<SymmetricEigen, EigenError> {
    if !a.iter().all(|x| x.is_finite()) {
        return Err(EigenError::NotFinite);
    }
    let eigen = nalgebra::DMatrix::from_row_slice(n, n, a)
        .try_symmetric_eigen(f64::EPSILON, iterations)
        .ok_or(EigenError::Unconverged { iterations })?;
    Ok(SymmetricEigen {
        values: eigen.eigenvalues.iter().copied().collect(),
        vectors: eigen
            .eigenvectors
            .column_iter()
            .map(|v| v.iter().copied().collect())
            .collect(),
    })
}

/// The Cholesky factor of a symmetric positive-definite matrix, `A = L L^T`
/// with `L` lower triangular (Golub & Van Loan, Matrix Computations, §4.2).
/// For a covariance `A`, `L^(-1)` whitens: `L^(-1) d` has unit covariance,
/// so least squares on whitened rows is generalized least squares.
#[derive(Clone, Debug, PartialEq)]
pub struct Cholesky {
    /// `L`, row-major `n x n` (zero above the diagonal).
    factor: Vec<f64>,
    n: usize,
}

impl Cholesky {
    /// The factor of `a` (row-major, `n x n`); `None` when a pivot is not
    /// positive (`a` not positive definite to rounding) or not finite.
    pub fn of(a: &[f64], n: usize) -> Option<Cholesky> {
        assert_eq!(a.len(), n * n, "a matrix of {n} x {n} entries");
        let mut factor = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let dot: f64 = (0..j).map(|k| factor[i * n + k] * factor[j * n + k]).sum();
                let entry = a[i * n + j] - dot;
                if i == j {
                    if !entry.is_finite() || entry <= 0.0 {
                        return None;
                    }
                    factor[i * n + i] = entry.sqrt();
                } else {
                    factor[i * n + j] = entry / factor[j * n + j];
                }
            }
        }
        Some(Cholesky { factor, n })
    }

    /// `L^(-1) d` (forward substitution); `d.len()` must be `n`.
    pub fn whiten(&self, d: &[f64]) -> Vec<f64> {
        let n = self.n;
        assert_eq!(d.len(), n, "a vector of {n} entries");
        let mut y = vec![0.0; n];
        for i in 0..n {
            let dot: f64 = (0..i).map(|k| self.factor[i * n + k] * y[k]).sum();
            y[i] = (d[i] - dot) / self.factor[i * n + i];
        }
        y
    }

    /// `A^(-1) b`: forward substitution, then back substitution with `L^T`.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut x = self.whiten(b);
        for i in (0..n).rev() {
            let dot: f64 = (i + 1..n).map(|k| self.factor[k * n + i] * x[k]).sum();
            x[i] = (x[i] - dot) / self.factor[i * n + i];
        }
        x
    }
}

/// `d^T A^(-1) d` for a symmetric positive-definite `A` (row-major, `n x n`
/// with `n = d.len()`): `|L^(-1) d|^2` with the [`Cholesky`] factor. `None`
/// when `A` is not positive definite to rounding. Units: those of `d^2 / A`.
pub fn inverse_quadratic_form(a: &[f64], d: &[f64]) -> Option<f64> {
    let whitened = Cholesky::of(a, d.len())?.whiten(d);
    Some(whitened.iter().map(|v| v * v).sum())
}

/// Weight of node `k` of the composite Simpson rule over `intervals` (even)
/// equal intervals, in units of `step / 3`: 1, 4, 2, 4, ..., 4, 1.
pub fn simpson_weight(k: usize, intervals: usize) -> f64 {
    debug_assert!(
        intervals.is_multiple_of(2),
        "Simpson needs an even number of intervals"
    );
    match k {
        0 => 1.0,
        k if k == intervals => 1.0,
        k if k % 2 == 1 => 4.0,
        _ => 2.0,
    }
}

/// Slopes `S'(x_k)` at the nodes of the not-a-knot cubic spline `S` through
/// `(x_k, y_k)` (`x` strictly ascending, at least three nodes), in units of
/// `y` per unit of `x`: the derivative of the smooth interpolant of all the
/// nodes. Exact for cubics; on a uniform grid of step `h` the error is
/// `h^4 y^(5) / 180` away from the ends (the slopes solve `s_(k-1) + 4 s_k +
/// s_(k+1) = 3 (y_(k+1) - y_(k-1)) / h`, a fourth-order compact difference)
/// and `O(h^3)` at them, where the not-a-knot condition (`S'''` continuous at
/// the second and the last but one node) assumes nothing about `y''`, unlike
/// the natural spline's `S'' = 0` (de Boor, A Practical Guide to Splines,
/// ch. IV). Three nodes give the parabola through them.
pub fn spline_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    assert!(
        x.len() >= 3 && y.len() == x.len(),
        "a spline needs at least three nodes and one value per node"
    );
    let step: Vec<f64> = x.windows(2).map(|pair| pair[1] - pair[0]).collect();
    let secant: Vec<f64> = y
        .windows(2)
        .zip(&step)
        .map(|(pair, h)| (pair[1] - pair[0]) / h)
        .collect();
    let last = step.len() - 1;
    let parabola = x.len() == 3;
    let [end, neighbour, rhs] =
        spline_end_row(parabola, [step[0], step[1]], [secant[0], secant[1]]);
    let mut rows = vec![[0.0, end, neighbour, rhs]];
    rows.extend((1..=last).map(|k| {
        let (left, right) = (step[k - 1], step[k]);
        [
            right,
            2.0 * (left + right),
            left,
            3.0 * (right * secant[k - 1] + left * secant[k]),
        ]
    }));
    let [end, neighbour, rhs] = spline_end_row(
        parabola,
        [step[last], step[last - 1]],
        [secant[last], secant[last - 1]],
    );
    rows.push([neighbour, end, 0.0, rhs]);
    solve_tridiagonal(rows)
}

/// The end condition of [`spline_slopes`] at one end, as the coefficients of
/// the end node's slope and its neighbour's and the right-hand side, from the
/// steps and secants of the interval at the end (`near`) and the next one
/// (`far`): not-a-knot, or the parabola through three nodes (`s_end +
/// s_neighbour = 2 secant_near`: with the middle node's equation, the slopes
/// of the one parabola).
fn spline_end_row(
    parabola: bool,
    [near, far]: [f64; 2],
    [near_secant, far_secant]: [f64; 2],
) -> [f64; 3] {
    if parabola {
        return [1.0, 1.0, 2.0 * near_secant];
    }
    let rhs =
        ((3.0 * near + 2.0 * far) * far * near_secant + near * near * far_secant) / (near + far);
    [far, near + far, rhs]
}

/// Solves the tridiagonal system whose rows are `[lower, diagonal, upper,
/// rhs]` (the first row's `lower` and the last's `upper` unused) by
/// elimination without pivoting (the Thomas algorithm): the pivots must stay
/// away from zero, as they do for diagonally dominant rows and for the
/// spline's (positive on uniform grids).
pub fn solve_tridiagonal(mut rows: Vec<[f64; 4]>) -> Vec<f64> {
    for k in 1..rows.len() {
        let factor = rows[k][0] / rows[k - 1][1];
        rows[k][1] -= factor * rows[k - 1][2];
        rows[k][3] -= factor * rows[k - 1][3];
    }
    let mut solution = vec![0.0; rows.len()];
    for k in (0..rows.len()).rev() {
        let next = solution.get(k + 1).copied().unwrap_or(0.0);
        solution[k] = (rows[k][3] - rows[k][2] * next) / rows[k][1];
    }
    solution
}

/// Below this reciprocal condition number (1-norm) a 3x3 system is singular
/// to working precision: the error bound `rcond^-1 * epsilon` of its
/// solution exceeds the solution itself, which then has no correct digit.
pub const SINGULAR_RCOND: f64 = f64::EPSILON;

/// Solves the 3x3 system `a z = b` (the normal equations of three-parameter
/// least squares) by LU decomposition with partial pivoting, which is
/// backward stable; `None` when `a` is singular to working precision
/// (reciprocal condition number below [`SINGULAR_RCOND`], an exactly zero
/// pivot, or entries that are not finite).
pub fn solve3(a: &[[f64; 3]; 3], b: &[f64; 3]) -> Option<[f64; 3]> {
    let lu = Lu3::new(a)?;
    let inverse = [0, 1, 2].map(|j| lu.solve(&[0, 1, 2].map(|i| f64::from(u8::from(i == j)))));
    let column_sum = |column: [f64; 3]| column.iter().map(|x| x.abs()).sum::<f64>();
    let norm = (0..3)
        .map(|j| column_sum([a[0][j], a[1][j], a[2][j]]))
        .fold(0.0, f64::max);
    let inverse_norm = inverse.into_iter().map(column_sum).fold(0.0, f64::max);
    let rcond = 1.0 / (norm * inverse_norm);
    (rcond >= SINGULAR_RCOND).then(|| lu.solve(b))
}

/// The LU decomposition `P a = L U` of a 3x3 matrix with partial pivoting:
/// `L` (unit diagonal) below the diagonal of `factors`, `U` on and above it.
struct Lu3 {
    factors: [[f64; 3]; 3],
    /// Row `k` of `P a` is row `rows[k]` of `a`.
    rows: [usize; 3],
}

impl Lu3 {
    /// The decomposition, or `None` at an exactly zero (or not finite) pivot.
    fn new(a: &[[f64; 3]; 3]) -> Option<Lu3> {
        let (mut factors, mut rows) = (*a, [0, 1, 2]);
        for k in 0..3 {
            let pivot =
                (k..3).max_by(|&i, &j| factors[i][k].abs().total_cmp(&factors[j][k].abs()))?;
            factors.swap(k, pivot);
            rows.swap(k, pivot);
            let diagonal = factors[k][k];
            if diagonal == 0.0 || !diagonal.is_finite() {
                return None;
            }
            let pivot_row = factors[k];
            for row in &mut factors[k + 1..] {
                let multiplier = row[k] / diagonal;
                row[k] = multiplier;
                for (x, &above) in row[k + 1..].iter_mut().zip(&pivot_row[k + 1..]) {
                    *x -= multiplier * above;
                }
            }
        }
        Some(Lu3 { factors, rows })
    }

    /// `z` with `a z = b`: forward substitution through `L`, back through `U`.
    fn solve(&self, b: &[f64; 3]) -> [f64; 3] {
        let f = &self.factors;
        let mut z = self.rows.map(|row| b[row]);
        for i in 1..3 {
            let below: f64 = (0..i).map(|j| f[i][j] * z[j]).sum();
            z[i] -= below;
        }
        for i in (0..3).rev() {
            let beyond: f64 = (i + 1..3).map(|j| f[i][j] * z[j]).sum();
            z[i] = (z[i] - beyond) / f[i][i];
        }
        z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `a z - b`, largest component, over the scale of `a z`.
    fn relative_residual(a: &[[f64; 3]; 3], z: &[f64; 3], b: &[f64; 3]) -> f64 {
        let scale = (0..3)
            .map(|i| (0..3).map(|j| (a[i][j] * z[j]).abs()).sum::<f64>())
            .fold(0.0, f64::max);
        (0..3)
            .map(|i| ((0..3).map(|j| a[i][j] * z[j]).sum::<f64>() - b[i]).abs())
            .fold(0.0, f64::max)
            / scale
    }

    /// A system that needs a row exchange (zero first pivot) and the 3x3
    /// Hilbert matrix (condition ~500) solve to rounding; so does either
    /// scaled by 1e-200, whose determinant (1e-600) underflows: Cramer's
    /// rule refused it, the condition number is scale-free.
    #[test]
    fn three_by_three_systems_solve_to_rounding_at_any_scale() {
        let pivoting = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let hilbert = [0.0, 1.0, 2.0].map(|i| [0.0, 1.0, 2.0].map(|j| 1.0 / (1.0 + i + j)));
        let b = [1.0, -2.0, 0.5];
        for a in [pivoting, hilbert] {
            for scale in [1.0, 1e-200, 1e200] {
                let scaled = a.map(|row| row.map(|x| x * scale));
                let z = solve3(&scaled, &b).expect("regular");
                let residual = relative_residual(&scaled, &z, &b);
                assert!(residual < 4.0 * f64::EPSILON, "{scale}: {residual:e}");
            }
        }
    }

    /// Singular to working precision: an exactly singular matrix, one whose
    /// third row is the sum of the others but for one unit in the last place
    /// (condition ~1e17), and one with a NaN give no solution; 56 units off
    /// (condition ~7e14), the solution keeps a digit or two and is returned.
    #[test]
    fn singular_systems_have_no_solution() {
        let exact = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [5.0, 7.0, 9.0]];
        let nearly = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [5.0, 7.0, 9.0 + 2e-15]];
        let nearly_by_a_digit = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [5.0, 7.0, 9.0 + 1e-13]];
        let undefined = [[1.0, 0.0, 0.0], [0.0, f64::NAN, 0.0], [0.0, 0.0, 1.0]];
        for a in [exact, nearly, undefined] {
            assert_eq!(solve3(&a, &[1.0, 1.0, 1.0]), None, "{a:?}");
        }
        assert!(solve3(&nearly_by_a_digit, &[1.0, 1.0, 1.0]).is_some());
    }

    #[test]
    fn eigen_solver_diagonalizes_a_symmetric_matrix() {
        let n = 5;
        let a: Vec<f64> = (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                1.0 / (1.0 + i as f64 + j as f64) + if i == j { i as f64 } else { 0.0 }
            })
            .collect();
        let eigen = symmetric_eigen(&a, n).unwrap();
        for (l, v) in eigen.values.iter().zip(&eigen.vectors) {
            for i in 0..n {
                let av: f64 = (0..n).map(|j| a[i * n + j] * v[j]).sum();
                assert!((av - l * v[i]).abs() < 1e-13, "{av} vs {}", l * v[i]);
            }
        }
    }

    /// A matrix with a NaN entry, and one that needs more iterations than
    /// allowed, give an error rather than a decomposition.
    #[test]
    fn eigen_solver_reports_what_it_cannot_diagonalize() {
        let mut a = [2.0, 1.0, 1.0, 3.0];
        a[1] = f64::NAN;
        assert_eq!(symmetric_eigen(&a, 2), Err(EigenError::NotFinite));
        let n = 5;
        let hilbert: Vec<f64> = (0..n * n)
            .map(|k| 1.0 / (1.0 + (k / n) as f64 + (k % n) as f64))
            .collect();
        assert_eq!(
            qr_eigen(&hilbert, n, 1),
            Err(EigenError::Unconverged { iterations: 1 })
        );
        assert!(symmetric_eigen(&hilbert, n).is_ok());
    }

    /// `A = [[4, 2], [2, 3]]` has inverse `[[3, -2], [-2, 4]] / 8`: for `d =
    /// (1, 2)`, `d^T A^-1 d = (3 - 8 + 16) / 8 = 11/8`; a diagonal matrix
    /// gives the sum of squared pulls; a singular one (rank 1) has none; `A x
    /// = d` has `x = A^-1 d = (-1, 6) / 8`.
    #[test]
    fn inverse_quadratic_form_matches_the_closed_forms() {
        let form = inverse_quadratic_form(&[4.0, 2.0, 2.0, 3.0], &[1.0, 2.0]).unwrap();
        assert!((form - 11.0 / 8.0).abs() < 1e-15, "{form}");
        let diagonal = [2.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 4.0];
        let form = inverse_quadratic_form(&diagonal, &[1.0, 1.0, 2.0]).unwrap();
        assert!((form - (0.5 + 2.0 + 1.0)).abs() < 1e-15, "{form}");
        assert_eq!(
            inverse_quadratic_form(&[1.0, 1.0, 1.0, 1.0], &[1.0, 0.0]),
            None
        );
        let solved = Cholesky::of(&[4.0, 2.0, 2.0, 3.0], 2)
            .unwrap()
            .solve(&[1.0, 2.0]);
        let by_hand = [(3.0 - 4.0) / 8.0, (-2.0 + 8.0) / 8.0];
        assert!(
            solved
                .iter()
                .zip(by_hand)
                .all(|(x, y)| (x - y).abs() < 1e-15)
        );
    }

    /// Rounding of slopes of O(1) values on steps of ~0.2 after a tridiagonal solve.
    const SLOPE_ROUNDING: f64 = 1e-12;

    /// A cubic is its own not-a-knot spline: its slopes come out exact at
    /// every node, ends included, on uniform and uneven grids; three nodes
    /// reproduce a parabola.
    #[test]
    fn spline_slopes_are_exact_for_cubics() {
        let cubic = |x: f64| 0.5 - x + 0.75 * x * x - 0.3 * x * x * x;
        let cubic_slope = |x: f64| -1.0 + 1.5 * x - 0.9 * x * x;
        let uniform: Vec<f64> = (0..13).map(|k| -1.5 + 0.25 * f64::from(k)).collect();
        let uneven: Vec<f64> = (0..9)
            .map(|k| -1.0 + 0.2 * f64::from(k) + 0.03 * f64::from(k * k % 5))
            .collect();
        for x in [&uniform, &uneven] {
            let y: Vec<f64> = x.iter().map(|&x| cubic(x)).collect();
            for (slope, &x) in spline_slopes(x, &y).iter().zip(x) {
                assert!(
                    (slope - cubic_slope(x)).abs() < SLOPE_ROUNDING,
                    "x = {x}: {slope}"
                );
            }
        }
        let three = [-0.4, 0.1, 0.9];
        let parabola = |x: f64| 2.0 - 3.0 * x + 1.25 * x * x;
        let y = three.map(parabola);
        for (slope, x) in spline_slopes(&three, &y).iter().zip(three) {
            assert!(
                (slope - (-3.0 + 2.5 * x)).abs() < SLOPE_ROUNDING,
                "x = {x}: {slope}"
            );
        }
    }
}
