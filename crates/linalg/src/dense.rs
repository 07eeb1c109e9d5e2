//! Row-major dense matrices.

use std::ops::{Index, IndexMut};

/// A row-major dense `f64` matrix: entry `(i, j)` is `data[i * ncols + j]`.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseMatrix {
    nrows: usize,
    ncols: usize,
    data: Vec<f64>,
}

impl DenseMatrix {
    /// The `nrows × ncols` zero matrix.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            data: vec![0.0; nrows * ncols],
        }
    }

    /// The `n × n` identity.
    pub fn identity(n: usize) -> Self {
        let mut a = Self::zeros(n, n);
        for i in 0..n {
            a.data[i * n + i] = 1.0;
        }
        a
    }

    /// Wraps row-major `data`.
    ///
    /// # Panics
    /// If `data.len() != nrows * ncols`.
    pub fn from_row_major(nrows: usize, ncols: usize, data: Vec<f64>) -> Self {
        assert_eq!(
            data.len(),
            nrows * ncols,
            "DenseMatrix::from_row_major: {} values for a {nrows}×{ncols} matrix",
            data.len()
        );
        Self { nrows, ncols, data }
    }

    /// The matrix with entries `f(i, j)`, filled row by row.
    pub fn from_fn(nrows: usize, ncols: usize, mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut data = Vec::with_capacity(nrows * ncols);
        for i in 0..nrows {
            for j in 0..ncols {
                data.push(f(i, j));
            }
        }
        Self { nrows, ncols, data }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// The row-major values.
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// The row-major values, mutable.
    pub fn data_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// Row `i` as a slice.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.ncols..(i + 1) * self.ncols]
    }

    /// Column `j`, copied.
    pub fn column(&self, j: usize) -> Vec<f64> {
        (0..self.nrows)
            .map(|i| self.data[i * self.ncols + j])
            .collect()
    }

    /// `Aᵀ`.
    pub fn transpose(&self) -> Self {
        Self::from_fn(self.ncols, self.nrows, |i, j| self[(j, i)])
    }

    /// The product `A B` (faer's blocked matrix multiplication).
    ///
    /// # Panics
    /// If `A.ncols() != B.nrows()`.
    pub fn matmul(&self, b: &DenseMatrix) -> Self {
        assert_eq!(
            self.ncols, b.nrows,
            "DenseMatrix::matmul: {}×{} times {}×{}",
            self.nrows, self.ncols, b.nrows, b.ncols
        );
        let c = crate::bridge::dense_ref(self) * crate::bridge::dense_ref(b);
        crate::bridge::from_faer(c.as_ref())
    }

    /// The product `A x`.
    ///
    /// # Panics
    /// If `x.len() != A.ncols()`.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(
            x.len(),
            self.ncols,
            "DenseMatrix::mul_vec: vector of length {} for {} columns",
            x.len(),
            self.ncols
        );
        (0..self.nrows)
            .map(|i| self.row(i).iter().zip(x).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// The Frobenius norm `(Σ A_ij²)^½`.
    pub fn frobenius_norm(&self) -> f64 {
        self.data.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// `‖A − Aᵀ‖_F / ‖A‖_F` (0 for the zero matrix, infinity when A is not square).
    pub fn symmetry_error(&self) -> f64 {
        if self.nrows != self.ncols {
            return f64::INFINITY;
        }
        let norm = self.frobenius_norm();
        if norm == 0.0 {
            return 0.0;
        }
        let mut diff = 0.0;
        for i in 0..self.nrows {
            for j in 0..self.ncols {
                let d = self[(i, j)] - self[(j, i)];
                diff += d * d;
            }
        }
        diff.sqrt() / norm
    }

    /// The largest absolute entry (0 for an empty matrix).
    pub fn max_abs(&self) -> f64 {
        self.data.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
    }
}

impl Index<(usize, usize)> for DenseMatrix {
    type Output = f64;
    #[inline]
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        debug_assert!(i < self.nrows && j < self.ncols);
        &self.data[i * self.ncols + j]
    }
}

impl IndexMut<(usize, usize)> for DenseMatrix {
    #[inline]
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        debug_assert!(i < self.nrows && j < self.ncols);
        &mut self.data[i * self.ncols + j]
    }
}

/// Euclidean norm `‖x‖₂`.
pub(crate) fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}
