//! Dense linear algebra the physics needs and no crate of ours provides: the
//! symmetric eigenproblem (cyclic Jacobi), used for the dissipative projection
//! of collision generators and for the Lax matrix of the Sutherland ring;
//! the composite Simpson weights of the quadratures (bound-pair length,
//! averages over thermal starts); and the node slopes of the not-a-knot cubic
//! spline (a tridiagonal solve), the derivative of measured rates on a grid;
//! the quadratic form of an inverse covariance (Cholesky), for chi-squares
//! with correlated entries. Pure math: no IO.

/// Eigenvalues and orthonormal eigenvectors of a symmetric matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetricEigen {
    /// Eigenvalues.
    pub values: Vec<f64>,
    /// Eigenvectors, `vectors[k]` belonging to `values[k]`.
    pub vectors: Vec<Vec<f64>>,
}

/// Sweeps [`symmetric_eigen`] makes before it gives up. Cyclic Jacobi
/// converges quadratically once the off-diagonal part is small (Golub & Van
/// Loan, Matrix Computations, §8.5): dense random symmetric matrices of 41,
/// 161 and 322 rows (the sizes of the `evolve` grids and of a Lax matrix)
/// reach the tolerance in 7, 9 and 10 sweeps, so 100 leaves a wide margin.
const MAX_SWEEPS: usize = 100;

/// Off-diagonal part, relative to the whole matrix (Frobenius norms), at
/// which [`symmetric_eigen`] stops: `1e-15`, a few `eps`, where further
/// rotations change the eigenvalues by less than their rounding.
const OFF_DIAGONAL_TOLERANCE: f64 = 1e-15;

/// Why [`symmetric_eigen`] returned no decomposition.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// An entry is NaN or infinite (or the squared norm overflows).
    #[error("the symmetric eigenproblem has a non-finite matrix entry")]
    NotFinite,
    /// The off-diagonal part stayed above the tolerance.
    #[error(
        "Jacobi rotations did not converge in {sweeps} sweeps: the off-diagonal part is \
         {relative_off_diagonal:e} of the matrix (tolerance {OFF_DIAGONAL_TOLERANCE:e})"
    )]
    Unconverged {
        /// Sweeps made.
        sweeps: usize,
        /// `||offdiag(A)||_F / ||A||_F` left.
        relative_off_diagonal: f64,
    },
}

/// Cyclic Jacobi rotations (Golub & Van Loan, Matrix Computations, §8.5.3)
/// until the off-diagonal part is below [`OFF_DIAGONAL_TOLERANCE`] of the
/// matrix in Frobenius norm (row-major `a`, `n x n`, symmetric). An error,
/// never a silent unconverged result, when that takes more than
/// [`MAX_SWEEPS`] sweeps or an entry is not finite.
pub fn symmetric_eigen(a: &[f64], n: usize) -> Result<SymmetricEigen, EigenError> {
    jacobi(a, n, MAX_SWEEPS)
}

/// [`symmetric_eigen`] with at most `max_sweeps` sweeps.
fn jacobi(a: &[f64], n: usize, max_sweeps: usize) -> Result<SymmetricEigen, EigenError> {
    let mut a = a.to_vec();
    let mut v = vec![0.0; n * n];
    (0..n).for_each(|i| v[i * n + i] = 1.0);
    let total: f64 = a.iter().map(|x| x * x).sum();
    if !total.is_finite() {
        return Err(EigenError::NotFinite);
    }
    for sweep in 0..=max_sweeps {
        let off: f64 = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        if off <= OFF_DIAGONAL_TOLERANCE * OFF_DIAGONAL_TOLERANCE * total {
            break;
        }
        if sweep == max_sweeps {
            return Err(EigenError::Unconverged {
                sweeps: sweep,
                relative_off_diagonal: (off / total).sqrt(),
            });
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    Ok(SymmetricEigen {
        values: (0..n).map(|k| a[k * n + k]).collect(),
        vectors: (0..n)
            .map(|k| (0..n).map(|i| v[i * n + k]).collect())
            .collect(),
    })
}

/// `d^T A^(-1) d` for a symmetric positive-definite `A` (row-major, `n x n`
/// with `n = d.len()`): with the Cholesky factor `A = L L^T` (Golub & Van
/// Loan, Matrix Computations, §4.2), `|y|^2` where `L y = d`. `None` when a
/// pivot is not positive (`A` not positive definite to rounding). Units: those
/// of `d^2 / A`.
pub fn inverse_quadratic_form(a: &[f64], d: &[f64]) -> Option<f64> {
    let n = d.len();
    assert_eq!(a.len(), n * n, "a matrix of {n} x {n} entries");
    let mut factor = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let dot: f64 = (0..j).map(|k| factor[i * n + k] * factor[j * n + k]).sum();
            let entry = a[i * n + j] - dot;
            if i == j {
                if entry.is_nan() || entry <= 0.0 {
                    return None;
                }
                factor[i * n + i] = entry.sqrt();
            } else {
                factor[i * n + j] = entry / factor[j * n + j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let dot: f64 = (0..i).map(|k| factor[i * n + k] * y[k]).sum();
        y[i] = (d[i] - dot) / factor[i * n + i];
    }
    Some(y.iter().map(|v| v * v).sum())
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
fn solve_tridiagonal(mut rows: Vec<[f64; 4]>) -> Vec<f64> {
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

/// Solves the 3x3 system `a z = b` (Cramer's rule; `None` if singular):
/// the normal equations of three-parameter least squares.
pub fn solve3(a: &[[f64; 3]; 3], b: &[f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    if !d.is_normal() {
        return None;
    }
    let mut z = [0.0; 3];
    for (k, slot) in z.iter_mut().enumerate() {
        let mut m = *a;
        for row in 0..3 {
            m[row][k] = b[row];
        }
        *slot = det(&m) / d;
    }
    Some(z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_diagonalizes_a_symmetric_matrix() {
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

    /// A matrix with a NaN entry, and one that needs more sweeps than allowed,
    /// give an error rather than a decomposition.
    #[test]
    fn jacobi_reports_what_it_cannot_diagonalize() {
        let mut a = [2.0, 1.0, 1.0, 3.0];
        a[1] = f64::NAN;
        assert_eq!(symmetric_eigen(&a, 2), Err(EigenError::NotFinite));
        let n = 5;
        let hilbert: Vec<f64> = (0..n * n)
            .map(|k| 1.0 / (1.0 + (k / n) as f64 + (k % n) as f64))
            .collect();
        match jacobi(&hilbert, n, 1) {
            Err(EigenError::Unconverged {
                sweeps: 1,
                relative_off_diagonal,
            }) => assert!(relative_off_diagonal > OFF_DIAGONAL_TOLERANCE),
            other => panic!("{other:?}"),
        }
        assert!(jacobi(&hilbert, n, MAX_SWEEPS).is_ok());
    }

    /// `A = [[4, 2], [2, 3]]` has inverse `[[3, -2], [-2, 4]] / 8`: for `d =
    /// (1, 2)`, `d^T A^-1 d = (3 - 8 + 16) / 8 = 11/8`; a diagonal matrix
    /// gives the sum of squared pulls; a singular one (rank 1) has none.
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
