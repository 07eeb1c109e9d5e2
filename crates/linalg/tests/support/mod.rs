//! Shared test support: tolerances (relative to each method's real error) and helpers.
#![allow(dead_code)]

use nurbspring_linalg::{DenseMatrix, SparseMatrix};

/// Tolerances, in one place. Direct solvers and dense eigensolvers are backward stable, so
/// their errors are a modest multiple of ε·(condition); the tests use well-conditioned data.
pub mod tol {
    /// Exact-arithmetic operations on a few summands (assembly, products, transposes).
    pub const EXACT: f64 = 1e-14;
    /// Relative residual ‖Ax − b‖/‖b‖ of a direct solve (condition ≲ 1e2, n ≲ 500).
    pub const RESIDUAL: f64 = 1e-12;
    /// Eigenvalues from dense EVD or converged Lanczos vs analytic / dense, relative.
    pub const EIGENVALUE: f64 = 1e-10;
    /// Orthonormality ‖ΦᵀMΦ − I‖_max.
    pub const ORTHONORMAL: f64 = 1e-10;
    /// Eigenvector residual ‖Kφ − λMφ‖ / (|λ| ‖Mφ‖).
    pub const EIGENVECTOR_RESIDUAL: f64 = 1e-8;
    /// Agreement of two least-squares solutions of a problem with condition ≲ 10.
    pub const LSTSQ: f64 = 1e-11;
    /// KKT conditions of NNLS (gradient components, complementarity), scaled by ‖A‖‖b‖.
    pub const KKT: f64 = 1e-10;
}

/// Deterministic pseudo-random numbers in [-1, 1) (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    pub fn index(&mut self, n: usize) -> usize {
        (((self.next() + 1.0) * 0.5 * n as f64) as usize).min(n - 1)
    }
}

/// The 1D Laplacian tridiag(−1, 2, −1) of size n.
pub fn laplacian_1d(n: usize) -> SparseMatrix {
    let mut t = Vec::new();
    for i in 0..n {
        t.push((i, i, 2.0));
        if i + 1 < n {
            t.push((i, i + 1, -1.0));
            t.push((i + 1, i, -1.0));
        }
    }
    SparseMatrix::from_triplets(n, n, &t).unwrap()
}

/// Eigenvalue k (1-based) of the 1D Laplacian: 2 − 2cos(kπ/(n+1)).
pub fn laplacian_eigenvalue(n: usize, k: usize) -> f64 {
    2.0 - 2.0 * ((k as f64) * std::f64::consts::PI / (n as f64 + 1.0)).cos()
}

/// A random sparse symmetric positive-definite matrix: random symmetric off-diagonal entries
/// plus a diagonal that dominates each row by `margin`.
pub fn random_spd(n: usize, per_col: usize, margin: f64, rng: &mut Rng) -> SparseMatrix {
    let mut t = Vec::new();
    let mut rowsum = vec![0.0; n];
    for j in 0..n {
        for _ in 0..per_col {
            let i = rng.index(n);
            if i == j {
                continue;
            }
            let v = rng.next();
            t.push((i, j, v));
            t.push((j, i, v));
            rowsum[i] += v.abs();
            rowsum[j] += v.abs();
        }
    }
    for i in 0..n {
        t.push((i, i, rowsum[i] + margin));
    }
    SparseMatrix::from_triplets(n, n, &t).unwrap()
}

/// A random dense matrix with entries in [-1, 1).
pub fn random_dense(nrows: usize, ncols: usize, rng: &mut Rng) -> DenseMatrix {
    DenseMatrix::from_fn(nrows, ncols, |_, _| rng.next())
}

pub fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// ‖A x − b‖ / ‖b‖ for a sparse A.
pub fn relative_residual(a: &SparseMatrix, x: &[f64], b: &[f64]) -> f64 {
    let mut r = b.to_vec();
    a.mul_vec_add(-1.0, x, &mut r);
    norm(&r) / norm(b)
}

/// max_ij |A_ij − B_ij|.
pub fn max_diff(a: &DenseMatrix, b: &DenseMatrix) -> f64 {
    assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
    a.data()
        .iter()
        .zip(b.data())
        .fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}
