//! Dense linear algebra the physics needs and no crate of ours provides: the
//! symmetric eigenproblem (cyclic Jacobi), used for the dissipative projection
//! of collision generators and for the Lax matrix of the Sutherland ring;
//! and the composite Simpson weights of the quadratures (bound-pair length,
//! averages over thermal starts). Pure math: no IO.

/// Eigenvalues and orthonormal eigenvectors of a symmetric matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetricEigen {
    /// Eigenvalues.
    pub values: Vec<f64>,
    /// Eigenvectors, `vectors[k]` belonging to `values[k]`.
    pub vectors: Vec<Vec<f64>>,
}

/// Cyclic Jacobi rotations until the off-diagonal part is below `1e-15` of the
/// matrix (row-major `a`, `n x n`, symmetric).
pub fn symmetric_eigen(a: &[f64], n: usize) -> SymmetricEigen {
    let mut a = a.to_vec();
    let mut v = vec![0.0; n * n];
    (0..n).for_each(|i| v[i * n + i] = 1.0);
    let total: f64 = a.iter().map(|x| x * x).sum();
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        if off <= 1e-30 * total {
            break;
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
    SymmetricEigen {
        values: (0..n).map(|k| a[k * n + k]).collect(),
        vectors: (0..n)
            .map(|k| (0..n).map(|i| v[i * n + k]).collect())
            .collect(),
    }
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
        let eigen = symmetric_eigen(&a, n);
        for (l, v) in eigen.values.iter().zip(&eigen.vectors) {
            for i in 0..n {
                let av: f64 = (0..n).map(|j| a[i * n + j] * v[j]).sum();
                assert!((av - l * v[i]).abs() < 1e-13, "{av} vs {}", l * v[i]);
            }
        }
    }
}
