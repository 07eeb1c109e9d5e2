//! Finite-element style assembly: the sparsity pattern is built once, values are summed per call.

use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};

use crate::{LinalgError, SparseMatrix};

/// A sparsity pattern built once from the `(row, col)` of every local entry (element order,
/// duplicates allowed); [`AssemblyPattern::assemble`] then sums the values of repeated entries.
///
/// Internally this is faer's `SymbolicSparseColMat::try_new_from_indices` (sort the index pairs
/// once, keep the permutation "argsort") followed by `SparseColMat::new_from_argsort` per call,
/// so the result always has the same pattern and an [`crate::SpdSolver`] built on one assembled
/// matrix can be refactored with the next. For lock-free parallel filling, [`Self::slots`] gives
/// the position in the CSC value array that every entry is summed into.
///
/// ```
/// use nurbspring_linalg::AssemblyPattern;
/// // Two 1D two-node elements sharing node 1: the shared diagonal entry is summed.
/// let entries = [(0, 0), (0, 1), (1, 0), (1, 1), (1, 1), (1, 2), (2, 1), (2, 2)];
/// let pattern = AssemblyPattern::new(3, 3, &entries).unwrap();
/// let k = pattern.assemble(&[1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0]);
/// assert_eq!(k.get(1, 1), 2.0);
/// assert_eq!(k.nnz(), 7);
/// ```
#[derive(Clone, Debug)]
pub struct AssemblyPattern {
    nrows: usize,
    ncols: usize,
    n_entries: usize,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    slots: Vec<usize>,
}

impl AssemblyPattern {
    /// Builds the pattern of an `nrows × ncols` matrix from the `(row, col)` of every entry.
    ///
    /// Errors with [`LinalgError::IndexOutOfBounds`] on an index outside the matrix.
    pub fn new(
        nrows: usize,
        ncols: usize,
        entries: &[(usize, usize)],
    ) -> Result<Self, LinalgError> {
        let mut pairs = Vec::with_capacity(entries.len());
        for &(row, col) in entries {
            if row >= nrows || col >= ncols {
                return Err(LinalgError::IndexOutOfBounds {
                    row,
                    col,
                    nrows,
                    ncols,
                });
            }
            pairs.push(Pair { row, col });
        }
        let (symbolic, argsort) =
            SymbolicSparseColMat::<usize>::try_new_from_indices(nrows, ncols, &pairs)
                .map_err(|e| LinalgError::Faer(format!("building the assembly pattern: {e:?}")))?;
        let col_ptr = symbolic.col_ptr();
        let row_idx = symbolic.row_idx();
        let slots = entries
            .iter()
            .map(|&(row, col)| {
                let (s, e) = (col_ptr[col], col_ptr[col + 1]);
                s + row_idx[s..e]
                    .binary_search(&row)
                    .expect("every entry is in the pattern built from it")
            })
            .collect();
        Ok(Self {
            nrows,
            ncols,
            n_entries: entries.len(),
            symbolic,
            argsort,
            slots,
        })
    }

    /// Number of local entries the pattern was built from (the length `assemble` expects).
    pub fn n_entries(&self) -> usize {
        self.n_entries
    }

    /// Rows of the assembled matrix.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Columns of the assembled matrix.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of distinct stored entries of the assembled matrix.
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// `slots()[k]` is the index in [`SparseMatrix::values`] that entry `k` is summed into.
    pub fn slots(&self) -> &[usize] {
        &self.slots
    }

    /// The summed matrix `A_ij = Σ_{k: entries[k] = (i, j)} values[k]` (faer's argsort assembly).
    ///
    /// # Panics
    /// If `values.len() != self.n_entries()`.
    pub fn assemble(&self, values: &[f64]) -> SparseMatrix {
        assert_eq!(
            values.len(),
            self.n_entries,
            "AssemblyPattern::assemble: {} values for {} entries",
            values.len(),
            self.n_entries
        );
        let mat = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, values)
            .expect("faer assembly only fails when out of memory");
        let (symbolic, val) = mat.into_parts();
        let (nrows, ncols, col_ptr, _, row_idx) = symbolic.into_parts();
        SparseMatrix::from_csc_unchecked(nrows, ncols, col_ptr, row_idx, val)
    }

    /// A matrix with this pattern and all stored values zero.
    pub fn zero_matrix(&self) -> SparseMatrix {
        SparseMatrix::from_csc_unchecked(
            self.nrows,
            self.ncols,
            self.symbolic.col_ptr().to_vec(),
            self.symbolic.row_idx().to_vec(),
            vec![0.0; self.nnz()],
        )
    }

    /// Sums `values` into `out` (which must have this pattern, e.g. from [`Self::zero_matrix`]),
    /// overwriting its values; allocation free.
    ///
    /// # Panics
    /// If `values.len() != self.n_entries()` or `out` has another pattern size.
    pub fn assemble_into(&self, values: &[f64], out: &mut SparseMatrix) {
        assert_eq!(
            values.len(),
            self.n_entries,
            "AssemblyPattern::assemble_into: {} values for {} entries",
            values.len(),
            self.n_entries
        );
        assert!(
            out.nrows() == self.nrows && out.ncols() == self.ncols && out.nnz() == self.nnz(),
            "AssemblyPattern::assemble_into: output matrix does not have the assembly pattern"
        );
        let dst = out.values_mut();
        dst.fill(0.0);
        for (&slot, &v) in self.slots.iter().zip(values) {
            dst[slot] += v;
        }
    }
}

/// The CSC pattern of a Kronecker product `A ⊗ B ⊗ 1_{m×m}` of two banded patterns, written
/// directly (no sort): column `k` of `A` (`n_a × n_a`) holds the rows `ranges_a[k]` (a half-open
/// range, possibly empty), likewise `B`, and `1_{m×m}` is a full `m × m` block. Row and column
/// `(i, j, r)` of the product is `(i · n_b + j) · m + r`.
///
/// This is the pattern of a tensor-product spline matrix: with `A`, `B` the 1-D patterns of two
/// B-spline bases (the functions overlapping each one on a non-empty knot span) and `m` dofs per
/// control point, every matrix assembled from products of basis functions lives in it. The
/// position of an entry is arithmetic ([`Self::position`]), so assemblers can write values in
/// place, and the stored rows of every column are sorted.
///
/// ```
/// use nurbspring_linalg::KroneckerPattern;
/// // Two 1-D linear elements per direction (3 functions, tridiagonal), 1 dof per point.
/// let band = [(0, 2), (0, 3), (1, 3)];
/// let p = KroneckerPattern::new(&band, &band, 1).unwrap();
/// assert_eq!(p.n(), 9);
/// assert_eq!(p.nnz(), 7 * 7);
/// let m = p.matrix(vec![1.0; 49]);
/// assert_eq!(m.get(4, 0), 1.0); // (1, 1) couples with (0, 0)
/// assert_eq!(m.get(8, 0), 0.0); // (2, 2) does not
/// assert_eq!(p.position(4, 0), m.position(4, 0).unwrap());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct KroneckerPattern {
    ranges_a: Vec<(usize, usize)>,
    ranges_b: Vec<(usize, usize)>,
    m: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl KroneckerPattern {
    /// The pattern of `A ⊗ B ⊗ 1_{m×m}`; errors with [`LinalgError::IndexOutOfBounds`] on a
    /// range past the end of its factor and with [`LinalgError::DimensionMismatch`] on
    /// `m = 0` or a decreasing range.
    pub fn new(
        ranges_a: &[(usize, usize)],
        ranges_b: &[(usize, usize)],
        m: usize,
    ) -> Result<Self, LinalgError> {
        if m == 0 {
            return Err(LinalgError::DimensionMismatch {
                op: "KroneckerPattern::new",
                expected: "at least one dof per point".into(),
                found: "m = 0".into(),
            });
        }
        for ranges in [ranges_a, ranges_b] {
            let n = ranges.len();
            for (col, &(start, end)) in ranges.iter().enumerate() {
                if start > end {
                    return Err(LinalgError::DimensionMismatch {
                        op: "KroneckerPattern::new",
                        expected: "row ranges start ≤ end".into(),
                        found: format!("column {col}: rows {start}..{end}"),
                    });
                }
                if end > n {
                    return Err(LinalgError::IndexOutOfBounds {
                        row: end - 1,
                        col,
                        nrows: n,
                        ncols: n,
                    });
                }
            }
        }
        let (n_a, n_b) = (ranges_a.len(), ranges_b.len());
        let n = n_a * n_b * m;
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut nnz = 0usize;
        for &(a0, a1) in ranges_a {
            for &(b0, b1) in ranges_b {
                let len = (a1 - a0) * (b1 - b0) * m;
                for _ in 0..m {
                    nnz += len;
                    col_ptr.push(nnz);
                }
            }
        }
        // The rows of column (k, l, r) do not depend on r; write them once per (k, l) and copy.
        let mut row_idx = Vec::with_capacity(nnz);
        for &(a0, a1) in ranges_a {
            for &(b0, b1) in ranges_b {
                let start = row_idx.len();
                for i in a0..a1 {
                    for j in b0..b1 {
                        let base = (i * n_b + j) * m;
                        row_idx.extend(base..base + m);
                    }
                }
                let end = row_idx.len();
                for _ in 1..m {
                    row_idx.extend_from_within(start..end);
                }
            }
        }
        debug_assert_eq!(row_idx.len(), nnz);
        Ok(Self {
            ranges_a: ranges_a.to_vec(),
            ranges_b: ranges_b.to_vec(),
            m,
            col_ptr,
            row_idx,
        })
    }

    /// Rows (and columns) of the matrix: `n_a · n_b · m`.
    pub fn n(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Dofs per point `m`.
    pub fn dofs_per_point(&self) -> usize {
        self.m
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// CSC column pointers (`n + 1` entries).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// CSC row indices, sorted within each column.
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// The row range of column `k` of `A`.
    pub fn range_a(&self, k: usize) -> (usize, usize) {
        self.ranges_a[k]
    }

    /// The row range of column `l` of `B`.
    pub fn range_b(&self, l: usize) -> (usize, usize) {
        self.ranges_b[l]
    }

    /// Index in the value array of the stored entry `(row, col)`, computed from the ranges (no
    /// search).
    ///
    /// # Panics
    /// In debug builds, if `(row, col)` is not in the pattern; in release builds the result is
    /// then meaningless.
    #[inline]
    pub fn position(&self, row: usize, col: usize) -> usize {
        let (m, n_b) = (self.m, self.ranges_b.len());
        let (ij, s) = (row / m, row % m);
        let (i, j) = (ij / n_b, ij % n_b);
        let kl = col / m;
        let (k, l) = (kl / n_b, kl % n_b);
        let (a0, a1) = self.ranges_a[k];
        let (b0, b1) = self.ranges_b[l];
        debug_assert!(
            (a0..a1).contains(&i) && (b0..b1).contains(&j),
            "KroneckerPattern::position: ({row}, {col}) is not in the pattern"
        );
        self.col_ptr[col] + ((i - a0) * (b1 - b0) + (j - b0)) * m + s
    }

    /// `(base, stride)` for writing a block into column `col`: the stored entry of row
    /// `((i0 + di) · n_b + j0 + dj) · m + s` is at `base + di · stride + dj · m + s`, for every
    /// such row inside the pattern. `(i0, j0)` must not precede the start of the column's ranges.
    ///
    /// # Panics
    /// In debug builds, if `i0` or `j0` precedes the start of its range.
    #[inline]
    pub fn column_origin(&self, col: usize, i0: usize, j0: usize) -> (usize, usize) {
        let (m, n_b) = (self.m, self.ranges_b.len());
        let kl = col / m;
        let (a0, _) = self.ranges_a[kl / n_b];
        let (b0, b1) = self.ranges_b[kl % n_b];
        debug_assert!(
            i0 >= a0 && j0 >= b0,
            "KroneckerPattern::column_origin: before the range"
        );
        let stride = (b1 - b0) * m;
        (
            self.col_ptr[col] + (i0 - a0) * stride + (j0 - b0) * m,
            stride,
        )
    }

    /// The matrix with this pattern and the given values (in CSC order, `nnz` of them).
    ///
    /// # Panics
    /// If `values.len() != self.nnz()`.
    pub fn matrix(&self, values: Vec<f64>) -> SparseMatrix {
        assert_eq!(
            values.len(),
            self.nnz(),
            "KroneckerPattern::matrix: {} values for {} entries",
            values.len(),
            self.nnz()
        );
        let n = self.n();
        SparseMatrix::from_csc_unchecked(n, n, self.col_ptr.clone(), self.row_idx.clone(), values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Half-open row ranges of a 1-D pattern made of `spans` overlapping windows of `w`
    /// consecutive functions starting at `starts` (non-decreasing), as B-spline spans give.
    fn band(starts: &[usize], w: usize) -> Vec<(usize, usize)> {
        let n = starts.last().map_or(0, |&s| s + w);
        let mut r = vec![(usize::MAX, 0usize); n];
        for &s in starts {
            for k in s..s + w {
                r[k] = (r[k].0.min(s), r[k].1.max(s + w));
            }
        }
        r.into_iter()
            .map(|(a, b)| if a == usize::MAX { (0, 0) } else { (a, b) })
            .collect()
    }

    /// Every `(row, col)` of `A ⊗ B ⊗ 1_m` by brute force over the dense index space.
    fn entries(ra: &[(usize, usize)], rb: &[(usize, usize)], m: usize) -> Vec<(usize, usize)> {
        let nb = rb.len();
        let n = ra.len() * nb * m;
        let inside = |r: (usize, usize), x: usize| r.0 <= x && x < r.1;
        let mut out = Vec::new();
        for col in 0..n {
            let (k, l) = ((col / m) / nb, (col / m) % nb);
            for row in 0..n {
                let (i, j) = ((row / m) / nb, (row / m) % nb);
                if inside(ra[k], i) && inside(rb[l], j) {
                    out.push((row, col));
                }
            }
        }
        out
    }

    proptest! {
        #[test]
        fn kronecker_pattern_matches_the_sorted_pattern(
            steps_a in proptest::collection::vec(0usize..2, 1..5),
            steps_b in proptest::collection::vec(0usize..2, 1..4),
            wa in 1usize..4, wb in 1usize..3, m in 1usize..4,
        ) {
            // Repeated windows (step 0) stand for repeated knots' empty spans.
            let starts = |steps: &[usize]| -> Vec<usize> {
                steps.iter().scan(0, |s, &d| { *s += d; Some(*s) }).collect()
            };
            let (ra, rb) = (band(&starts(&steps_a), wa), band(&starts(&steps_b), wb));
            let p = KroneckerPattern::new(&ra, &rb, m).unwrap();
            let e = entries(&ra, &rb, m);
            let reference = AssemblyPattern::new(p.n(), p.n(), &e).unwrap().zero_matrix();
            prop_assert_eq!(p.col_ptr(), reference.col_ptr());
            prop_assert_eq!(p.row_idx(), reference.row_idx());
            for &(row, col) in &e {
                prop_assert_eq!(Some(p.position(row, col)), reference.position(row, col));
            }
        }
    }

    #[test]
    fn kronecker_pattern_rejects_bad_ranges() {
        assert!(matches!(
            KroneckerPattern::new(&[(0, 3)], &[(0, 1)], 1),
            Err(LinalgError::IndexOutOfBounds { .. })
        ));
        assert!(matches!(
            KroneckerPattern::new(&[(1, 0)], &[(0, 1)], 1),
            Err(LinalgError::DimensionMismatch { .. })
        ));
        assert!(KroneckerPattern::new(&[(0, 1)], &[(0, 1)], 0).is_err());
    }
}
