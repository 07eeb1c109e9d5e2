//! The refinement matrix `C` (`P^w_new = C P^w_old`) in triplet form, and homogeneous coordinates.

use super::Row;

/// A sparse `nrows × ncols` matrix in triplet form `(row, column, value)`, as returned by knot
/// insertion, refinement and degree elevation: `P^w_new = C P^w_old`.
///
/// The constructors of this crate keep the triplets sorted by row, then column, without
/// duplicates or explicit zeros; every method also accepts unsorted triplets (duplicates are
/// summed).
///
/// ```
/// use nurbspring_geom::RefinementMatrix;
/// let c = RefinementMatrix {
///     nrows: 3,
///     ncols: 2,
///     triplets: vec![(0, 0, 1.0), (1, 0, 0.5), (1, 1, 0.5), (2, 1, 1.0)],
/// };
/// assert_eq!(c.to_dense(), vec![1.0, 0.0, 0.5, 0.5, 0.0, 1.0]);
/// assert_eq!(c.apply_to(&[2.0, 4.0]), vec![2.0, 3.0, 4.0]);
/// let h = c.apply(&[[0.0, 0.0, 0.0, 1.0], [2.0, 2.0, 2.0, 2.0]]);
/// assert_eq!(h[1], [1.0, 1.0, 1.0, 1.5]);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefinementMatrix {
    /// Number of rows (new control points or basis functions).
    pub nrows: usize,
    /// Number of columns (old control points or basis functions).
    pub ncols: usize,
    /// Non-zero entries `(row, column, value)`.
    pub triplets: Vec<(usize, usize, f64)>,
}

impl RefinementMatrix {
    /// The `n × n` identity (the matrix of inserting nothing).
    pub fn identity(n: usize) -> Self {
        Self {
            nrows: n,
            ncols: n,
            triplets: (0..n).map(|i| (i, i, 1.0)).collect(),
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.triplets.len()
    }

    /// Entry `(row, col)` (0 when not stored; duplicates summed).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.triplets
            .iter()
            .filter(|&&(r, c, _)| r == row && c == col)
            .map(|&(_, _, v)| v)
            .sum()
    }

    /// Row-major dense copy, `nrows × ncols`.
    pub fn to_dense(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.nrows * self.ncols];
        for &(r, c, v) in &self.triplets {
            out[r * self.ncols + c] += v;
        }
        out
    }

    /// `C P^w` for homogeneous points `(w x, w y, w z, w)` (`points.len() == ncols`).
    ///
    /// # Panics
    /// If `points.len() != ncols`.
    pub fn apply(&self, points: &[[f64; 4]]) -> Vec<[f64; 4]> {
        assert_eq!(
            points.len(),
            self.ncols,
            "apply: {} points for {} columns",
            points.len(),
            self.ncols
        );
        let mut out = vec![[0.0; 4]; self.nrows];
        for &(r, c, v) in &self.triplets {
            let p = points[c];
            let o = &mut out[r];
            o[0] += v * p[0];
            o[1] += v * p[1];
            o[2] += v * p[2];
            o[3] += v * p[3];
        }
        out
    }

    /// `C x` for a vector of length `ncols`.
    ///
    /// # Panics
    /// If `x.len() != ncols`.
    pub fn apply_to(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(
            x.len(),
            self.ncols,
            "apply_to: length {} for {} columns",
            x.len(),
            self.ncols
        );
        let mut out = vec![0.0; self.nrows];
        for &(r, c, v) in &self.triplets {
            out[r] += v * x[c];
        }
        out
    }

    /// `Cᵀ y` for a vector of length `nrows`.
    ///
    /// # Panics
    /// If `y.len() != nrows`.
    pub fn apply_transpose(&self, y: &[f64]) -> Vec<f64> {
        assert_eq!(
            y.len(),
            self.nrows,
            "apply_transpose: length {} for {} rows",
            y.len(),
            self.nrows
        );
        let mut out = vec![0.0; self.ncols];
        for &(r, c, v) in &self.triplets {
            out[c] += v * y[r];
        }
        out
    }

    /// `Cᵀ`.
    pub fn transpose(&self) -> Self {
        let mut triplets: Vec<_> = self.triplets.iter().map(|&(r, c, v)| (c, r, v)).collect();
        triplets.sort_by_key(|&(r, c, _)| (r, c));
        Self {
            nrows: self.ncols,
            ncols: self.nrows,
            triplets,
        }
    }

    /// Row sums (each is 1 for the matrices of this module: the new basis is a partition of
    /// unity and reproduces the old one).
    pub fn row_sums(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.nrows];
        for &(r, _, v) in &self.triplets {
            out[r] += v;
        }
        out
    }

    /// Entries grouped by row: `rows[r]` lists `(column, value)` with columns ascending and
    /// duplicates summed.
    pub(super) fn rows(&self) -> Vec<Vec<(usize, f64)>> {
        let mut rows = vec![Vec::new(); self.nrows];
        for &(r, c, v) in &self.triplets {
            rows[r].push((c, v));
        }
        for row in &mut rows {
            row.sort_by_key(|&(c, _)| c);
            row.dedup_by(|b, a| {
                if a.0 == b.0 {
                    a.1 += b.1;
                    true
                } else {
                    false
                }
            });
        }
        rows
    }

    pub(super) fn from_rows(rows: Vec<Vec<(usize, f64)>>, ncols: usize) -> Self {
        let nrows = rows.len();
        let triplets = rows
            .into_iter()
            .enumerate()
            .flat_map(|(r, row)| {
                row.into_iter()
                    .filter(|&(_, v)| v != 0.0)
                    .map(move |(c, v)| (r, c, v))
            })
            .collect();
        Self {
            nrows,
            ncols,
            triplets,
        }
    }

    /// The product `self · rhs` (first `rhs`, then `self`): the matrix of two successive
    /// refinements.
    ///
    /// # Panics
    /// If `self.ncols != rhs.nrows`.
    pub fn compose(&self, rhs: &Self) -> Self {
        assert_eq!(
            self.ncols, rhs.nrows,
            "compose: {} columns times {} rows",
            self.ncols, rhs.nrows
        );
        let right = rhs.rows();
        let rows = self
            .rows()
            .into_iter()
            .map(|row| {
                let mut acc = Row::default();
                for (k, v) in row {
                    acc.add_scaled(v, &Row(right[k].clone()));
                }
                acc.0
            })
            .collect();
        Self::from_rows(rows, rhs.ncols)
    }

    /// The Kronecker product `self ⊗ rhs`: entry `((i, k), (j, l))` at row `i · rhs.nrows + k`,
    /// column `j · rhs.ncols + l` is `self_ij rhs_kl`. For surfaces `C = C_u ⊗ C_v` matches the
    /// flat control point index `i · n_v + j`.
    pub fn kron(&self, rhs: &Self) -> Self {
        let (left, right) = (self.rows(), rhs.rows());
        let mut triplets = Vec::with_capacity(self.nnz() * rhs.nnz());
        for (i, li) in left.iter().enumerate() {
            for (k, rk) in right.iter().enumerate() {
                let row = i * rhs.nrows + k;
                for &(j, a) in li {
                    for &(l, b) in rk {
                        triplets.push((row, j * rhs.ncols + l, a * b));
                    }
                }
            }
        }
        Self {
            nrows: self.nrows * rhs.nrows,
            ncols: self.ncols * rhs.ncols,
            triplets,
        }
    }

    /// `C ⊗ I_d`: the matrix acting on generalized coordinates interleaved per control point
    /// (`d = 3` for `[x0, y0, z0, x1, …]`; docs/math.md §1). With constant weights all equal to 1 this
    /// maps coarse to fine generalized coordinates exactly; for other weights use
    /// [`RefinementMatrix::to_cartesian`] first.
    pub fn kron_identity(&self, d: usize) -> Self {
        self.kron(&Self::identity(d))
    }

    /// The matrix acting on Cartesian control points for fixed weights: with
    /// `w_new = C w_old`, `P_new = diag(w_new)⁻¹ C diag(w_old) P_old`. Returns that matrix and
    /// `w_new`. Its rows also sum to one.
    ///
    /// # Panics
    /// If `old_weights.len() != ncols`.
    pub fn to_cartesian(&self, old_weights: &[f64]) -> (Self, Vec<f64>) {
        let new_weights = self.apply_to(old_weights);
        let triplets = self
            .triplets
            .iter()
            .map(|&(r, c, v)| (r, c, v * old_weights[c] / new_weights[r]))
            .collect();
        (
            Self {
                nrows: self.nrows,
                ncols: self.ncols,
                triplets,
            },
            new_weights,
        )
    }
}

/// Homogeneous control points `(w x, w y, w z, w)`.
pub fn to_homogeneous(points: &[[f64; 3]], weights: &[f64]) -> Vec<[f64; 4]> {
    points
        .iter()
        .zip(weights)
        .map(|(p, &w)| [w * p[0], w * p[1], w * p[2], w])
        .collect()
}

/// Cartesian points and weights from homogeneous ones (the inverse of [`to_homogeneous`]).
pub fn from_homogeneous(points: &[[f64; 4]]) -> (Vec<[f64; 3]>, Vec<f64>) {
    points
        .iter()
        .map(|h| ([h[0] / h[3], h[1] / h[3], h[2] / h[3]], h[3]))
        .unzip()
}
