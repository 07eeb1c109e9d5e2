//! Compressed sparse column matrices.

use crate::error::mismatch;
use crate::{AssemblyPattern, DenseMatrix, LinalgError};

/// `S = A + βB` kept on one pattern and refilled in place: for a fixed `A` and a sequence of
/// `B`s with one pattern (a tangent stiffness along a Newton iteration), the union pattern and
/// the position in `S` of each entry of `A` and `B` are found once; [`ShiftedSum::update`] then
/// costs one pass over `S` and one over `B`, with no allocation. A `B` with another pattern
/// rebuilds the plan. The values equal [`SparseMatrix::linear_combination`]`(1, A, β, B)` to the
/// last bit (`a + βb` where both store an entry).
///
/// ```
/// use nurbspring_linalg::{ShiftedSum, SparseMatrix};
/// let a = SparseMatrix::from_diagonal(&[1.0, 2.0]);
/// let b = SparseMatrix::from_triplets(2, 2, &[(0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)]).unwrap();
/// let mut s = ShiftedSum::new(&a, 0.5, &b).unwrap();
/// assert_eq!(s.matrix().get(1, 1), 2.5);
/// assert_eq!(s.update(2.0, &b).unwrap().get(0, 1), 2.0);
/// ```
#[derive(Clone, Debug)]
pub struct ShiftedSum {
    a: SparseMatrix,
    sum: SparseMatrix,
    /// `A`'s values scattered onto the pattern of `S` (zero elsewhere).
    base: Vec<f64>,
    /// The pattern of the `B` the plan was made for.
    b_col_ptr: Vec<usize>,
    b_row_idx: Vec<usize>,
    /// Position in `S` of each stored entry of `B`.
    b_map: Vec<usize>,
}

impl ShiftedSum {
    /// The plan and the first sum `A + βB`.
    pub fn new(a: &SparseMatrix, beta: f64, b: &SparseMatrix) -> Result<Self, LinalgError> {
        let mut s = Self {
            a: a.clone(),
            sum: SparseMatrix::zeros(a.nrows, a.ncols),
            base: Vec::new(),
            b_col_ptr: Vec::new(),
            b_row_idx: Vec::new(),
            b_map: Vec::new(),
        };
        s.plan(b)?;
        s.update(beta, b)?;
        Ok(s)
    }

    fn plan(&mut self, b: &SparseMatrix) -> Result<(), LinalgError> {
        let mut sum = SparseMatrix::linear_combination(1.0, &self.a, 0.0, b)?;
        let mut base = vec![0.0; sum.nnz()];
        for j in 0..self.a.ncols {
            for p in self.a.col_ptr[j]..self.a.col_ptr[j + 1] {
                let at = sum
                    .position(self.a.row_idx[p], j)
                    .expect("the union pattern holds every entry of A");
                base[at] = self.a.values[p];
            }
        }
        self.b_map = (0..b.ncols)
            .flat_map(|j| (b.col_ptr[j]..b.col_ptr[j + 1]).map(move |p| (b.row_idx[p], j)))
            .map(|(i, j)| {
                sum.position(i, j)
                    .expect("the union pattern holds every entry of B")
            })
            .collect();
        sum.values.copy_from_slice(&base);
        self.sum = sum;
        self.base = base;
        self.b_col_ptr = b.col_ptr.clone();
        self.b_row_idx = b.row_idx.clone();
        Ok(())
    }

    /// Refills `S = A + βB` in place (a new plan when `B`'s pattern is not the planned one).
    pub fn update(&mut self, beta: f64, b: &SparseMatrix) -> Result<&SparseMatrix, LinalgError> {
        if b.nrows != self.a.nrows || b.ncols != self.a.ncols {
            return Err(mismatch(
                "ShiftedSum::update",
                format!("{}×{}", self.a.nrows, self.a.ncols),
                format!("{}×{}", b.nrows, b.ncols),
            ));
        }
        if b.col_ptr != self.b_col_ptr || b.row_idx != self.b_row_idx {
            self.plan(b)?;
        }
        self.sum.values.copy_from_slice(&self.base);
        for (&at, &v) in self.b_map.iter().zip(&b.values) {
            self.sum.values[at] += beta * v;
        }
        Ok(&self.sum)
    }

    /// The current sum.
    pub fn matrix(&self) -> &SparseMatrix {
        &self.sum
    }
}

/// Compressed sparse column (CSC) matrix of `f64`.
///
/// Column `j` holds the entries `row_idx[col_ptr[j]..col_ptr[j + 1]]` (strictly increasing, no
/// duplicates) with values `values[col_ptr[j]..col_ptr[j + 1]]`. Explicit zeros may be stored:
/// a pattern stays fixed when values change, which lets an [`crate::SpdSolver`] be refactored.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    nrows: usize,
    ncols: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

impl SparseMatrix {
    /// Builds a CSC matrix from its raw parts after checking the invariants (pointer
    /// monotonicity, sorted unique rows in range).
    pub fn try_from_csc(
        nrows: usize,
        ncols: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        values: Vec<f64>,
    ) -> Result<Self, LinalgError> {
        if col_ptr.len() != ncols + 1 || col_ptr[0] != 0 {
            return Err(mismatch(
                "SparseMatrix::try_from_csc",
                format!("col_ptr of length {} starting at 0", ncols + 1),
                format!("length {}", col_ptr.len()),
            ));
        }
        let nnz = col_ptr[ncols];
        if row_idx.len() != nnz || values.len() != nnz {
            return Err(mismatch(
                "SparseMatrix::try_from_csc",
                format!("{nnz} row indices and values"),
                format!("{} and {}", row_idx.len(), values.len()),
            ));
        }
        for j in 0..ncols {
            if col_ptr[j] > col_ptr[j + 1] {
                return Err(mismatch(
                    "SparseMatrix::try_from_csc",
                    "non-decreasing col_ptr",
                    format!(
                        "col_ptr[{j}] = {} > col_ptr[{}] = {}",
                        col_ptr[j],
                        j + 1,
                        col_ptr[j + 1]
                    ),
                ));
            }
            let rows = &row_idx[col_ptr[j]..col_ptr[j + 1]];
            for (k, &r) in rows.iter().enumerate() {
                if r >= nrows {
                    return Err(LinalgError::IndexOutOfBounds {
                        row: r,
                        col: j,
                        nrows,
                        ncols,
                    });
                }
                if k > 0 && rows[k - 1] >= r {
                    return Err(mismatch(
                        "SparseMatrix::try_from_csc",
                        "strictly increasing rows in each column",
                        format!("column {j} has row {} before row {r}", rows[k - 1]),
                    ));
                }
            }
        }
        Ok(Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// Builds from parts known to satisfy the invariants (crate internal).
    pub(crate) fn from_csc_unchecked(
        nrows: usize,
        ncols: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        values: Vec<f64>,
    ) -> Self {
        debug_assert_eq!(col_ptr.len(), ncols + 1);
        debug_assert_eq!(row_idx.len(), values.len());
        Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// The matrix with entries `Σ v` over the triplets `(row, col, v)`; duplicates are summed
    /// (through [`AssemblyPattern`], i.e. faer's argsort assembly).
    pub fn from_triplets(
        nrows: usize,
        ncols: usize,
        t: &[(usize, usize, f64)],
    ) -> Result<Self, LinalgError> {
        let entries: Vec<(usize, usize)> = t.iter().map(|&(r, c, _)| (r, c)).collect();
        let values: Vec<f64> = t.iter().map(|&(_, _, v)| v).collect();
        Ok(AssemblyPattern::new(nrows, ncols, &entries)?.assemble(&values))
    }

    /// The `nrows × ncols` matrix with no stored entries.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            col_ptr: vec![0; ncols + 1],
            row_idx: Vec::new(),
            values: Vec::new(),
        }
    }

    /// The `n × n` identity.
    pub fn identity(n: usize) -> Self {
        Self::from_diagonal(&vec![1.0; n])
    }

    /// The diagonal matrix `diag(d)` (every diagonal entry stored, zeros included).
    pub fn from_diagonal(d: &[f64]) -> Self {
        let n = d.len();
        Self {
            nrows: n,
            ncols: n,
            col_ptr: (0..=n).collect(),
            row_idx: (0..n).collect(),
            values: d.to_vec(),
        }
    }

    /// The entries of `a` with `|a_ij| > drop_tol` (`drop_tol = 0` keeps every non-zero).
    pub fn from_dense(a: &DenseMatrix, drop_tol: f64) -> Self {
        let (nrows, ncols) = (a.nrows(), a.ncols());
        let mut col_ptr = Vec::with_capacity(ncols + 1);
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        col_ptr.push(0);
        for j in 0..ncols {
            for i in 0..nrows {
                let v = a[(i, j)];
                if v.abs() > drop_tol {
                    row_idx.push(i);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Column pointers (length `ncols + 1`).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row index of every stored entry, column by column.
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// Value of every stored entry, column by column.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Stored values, mutable (the pattern cannot change).
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Position of `(row, col)` in [`Self::values`], if stored (binary search in the column).
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        if col >= self.ncols {
            return None;
        }
        let (s, e) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[s..e].binary_search(&row).ok().map(|k| s + k)
    }

    /// Entry `(row, col)`; 0 where nothing is stored.
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.position(row, col).map_or(0.0, |k| self.values[k])
    }

    /// `(row, col, value)` of every stored entry in column-major order.
    pub fn triplets(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.ncols).flat_map(move |j| {
            (self.col_ptr[j]..self.col_ptr[j + 1])
                .map(move |k| (self.row_idx[k], j, self.values[k]))
        })
    }

    /// `y = A x`.
    ///
    /// # Panics
    /// On size mismatch (callers validate).
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(
            y.len(),
            self.nrows,
            "SparseMatrix::mul_vec: output length {} for {} rows",
            y.len(),
            self.nrows
        );
        y.fill(0.0);
        self.mul_vec_add(1.0, x, y);
    }

    /// `y += α A x`.
    ///
    /// # Panics
    /// On size mismatch (callers validate).
    pub fn mul_vec_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        assert_eq!(
            x.len(),
            self.ncols,
            "SparseMatrix::mul_vec_add: input length {} for {} columns",
            x.len(),
            self.ncols
        );
        assert_eq!(
            y.len(),
            self.nrows,
            "SparseMatrix::mul_vec_add: output length {} for {} rows",
            y.len(),
            self.nrows
        );
        for j in 0..self.ncols {
            let xj = alpha * x[j];
            if xj == 0.0 {
                continue;
            }
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[k]] += self.values[k] * xj;
            }
        }
    }

    /// `Aᵀ` (counting sort by row, so the result's columns come out sorted).
    pub fn transpose(&self) -> Self {
        let mut count = vec![0usize; self.nrows + 1];
        for &r in &self.row_idx {
            count[r + 1] += 1;
        }
        for i in 0..self.nrows {
            count[i + 1] += count[i];
        }
        let col_ptr = count.clone();
        let mut next = count;
        let nnz = self.nnz();
        let mut row_idx = vec![0usize; nnz];
        let mut values = vec![0.0; nnz];
        for j in 0..self.ncols {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let r = self.row_idx[k];
                let dst = next[r];
                next[r] += 1;
                row_idx[dst] = j;
                values[dst] = self.values[k];
            }
        }
        Self {
            nrows: self.ncols,
            ncols: self.nrows,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// `A B`, by Gustavson's column-by-column algorithm with a dense accumulator.
    pub fn matmul(&self, b: &SparseMatrix) -> Result<Self, LinalgError> {
        if self.ncols != b.nrows {
            return Err(mismatch(
                "SparseMatrix::matmul",
                format!("B with {} rows", self.ncols),
                format!("{}×{}", b.nrows, b.ncols),
            ));
        }
        let mut acc = vec![0.0; self.nrows];
        let mut mark = vec![usize::MAX; self.nrows];
        let mut col_ptr = Vec::with_capacity(b.ncols + 1);
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        col_ptr.push(0);
        for j in 0..b.ncols {
            let start = row_idx.len();
            for kb in b.col_ptr[j]..b.col_ptr[j + 1] {
                let k = b.row_idx[kb];
                let bkj = b.values[kb];
                for ka in self.col_ptr[k]..self.col_ptr[k + 1] {
                    let i = self.row_idx[ka];
                    if mark[i] != j {
                        mark[i] = j;
                        acc[i] = 0.0;
                        row_idx.push(i);
                    }
                    acc[i] += self.values[ka] * bkj;
                }
            }
            row_idx[start..].sort_unstable();
            values.extend(row_idx[start..].iter().map(|&i| acc[i]));
            col_ptr.push(row_idx.len());
        }
        Ok(Self {
            nrows: self.nrows,
            ncols: b.ncols,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// `αA + βB` on the union of both patterns (no entry is dropped, so the pattern depends only
    /// on the patterns of A and B).
    pub fn linear_combination(
        alpha: f64,
        a: &SparseMatrix,
        beta: f64,
        b: &SparseMatrix,
    ) -> Result<Self, LinalgError> {
        if a.nrows != b.nrows || a.ncols != b.ncols {
            return Err(mismatch(
                "SparseMatrix::linear_combination",
                format!("{}×{}", a.nrows, a.ncols),
                format!("{}×{}", b.nrows, b.ncols),
            ));
        }
        let mut col_ptr = Vec::with_capacity(a.ncols + 1);
        let mut row_idx = Vec::with_capacity(a.nnz().max(b.nnz()));
        let mut values = Vec::with_capacity(a.nnz().max(b.nnz()));
        col_ptr.push(0);
        for j in 0..a.ncols {
            let (mut p, pe) = (a.col_ptr[j], a.col_ptr[j + 1]);
            let (mut q, qe) = (b.col_ptr[j], b.col_ptr[j + 1]);
            while p < pe || q < qe {
                let ra = if p < pe { a.row_idx[p] } else { usize::MAX };
                let rb = if q < qe { b.row_idx[q] } else { usize::MAX };
                if ra < rb {
                    row_idx.push(ra);
                    values.push(alpha * a.values[p]);
                    p += 1;
                } else if rb < ra {
                    row_idx.push(rb);
                    values.push(beta * b.values[q]);
                    q += 1;
                } else {
                    row_idx.push(ra);
                    values.push(alpha * a.values[p] + beta * b.values[q]);
                    p += 1;
                    q += 1;
                }
            }
            col_ptr.push(row_idx.len());
        }
        Ok(Self {
            nrows: a.nrows,
            ncols: a.ncols,
            col_ptr,
            row_idx,
            values,
        })
    }

    /// `A ← sA`.
    pub fn scale(&mut self, s: f64) {
        self.values.iter_mut().for_each(|v| *v *= s);
    }

    /// `A[rows, cols]` with rows and columns in the given order (repeats allowed).
    ///
    /// # Panics
    /// If an index is out of range.
    pub fn submatrix(&self, rows: &[usize], cols: &[usize]) -> Self {
        // For every old row, the list of new rows it maps to (CSR-like arrays).
        let mut start = vec![0usize; self.nrows + 1];
        for &r in rows {
            assert!(
                r < self.nrows,
                "SparseMatrix::submatrix: row {r} out of range for {} rows",
                self.nrows
            );
            start[r + 1] += 1;
        }
        for i in 0..self.nrows {
            start[i + 1] += start[i];
        }
        let mut targets = vec![0usize; rows.len()];
        let mut fill = start.clone();
        for (new, &r) in rows.iter().enumerate() {
            targets[fill[r]] = new;
            fill[r] += 1;
        }
        let mut col_ptr = Vec::with_capacity(cols.len() + 1);
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        let mut scratch: Vec<(usize, f64)> = Vec::new();
        col_ptr.push(0);
        for &c in cols {
            assert!(
                c < self.ncols,
                "SparseMatrix::submatrix: column {c} out of range for {} columns",
                self.ncols
            );
            scratch.clear();
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = self.row_idx[k];
                for &new in &targets[start[r]..start[r + 1]] {
                    scratch.push((new, self.values[k]));
                }
            }
            scratch.sort_unstable_by_key(|e| e.0);
            for &(r, v) in &scratch {
                row_idx.push(r);
                values.push(v);
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            nrows: rows.len(),
            ncols: cols.len(),
            col_ptr,
            row_idx,
            values,
        }
    }

    /// The dense copy.
    pub fn to_dense(&self) -> DenseMatrix {
        let mut d = DenseMatrix::zeros(self.nrows, self.ncols);
        for (i, j, v) in self.triplets() {
            d[(i, j)] += v;
        }
        d
    }

    /// The Frobenius inner product `Σ_ij A_ij B_ij` (patterns may differ).
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn frobenius_dot(&self, b: &SparseMatrix) -> f64 {
        assert!(
            self.nrows == b.nrows && self.ncols == b.ncols,
            "SparseMatrix::frobenius_dot: {}×{} and {}×{}",
            self.nrows,
            self.ncols,
            b.nrows,
            b.ncols
        );
        let mut s = 0.0;
        for j in 0..self.ncols {
            let (mut p, pe) = (self.col_ptr[j], self.col_ptr[j + 1]);
            let (mut q, qe) = (b.col_ptr[j], b.col_ptr[j + 1]);
            while p < pe && q < qe {
                match self.row_idx[p].cmp(&b.row_idx[q]) {
                    std::cmp::Ordering::Less => p += 1,
                    std::cmp::Ordering::Greater => q += 1,
                    std::cmp::Ordering::Equal => {
                        s += self.values[p] * b.values[q];
                        p += 1;
                        q += 1;
                    }
                }
            }
        }
        s
    }

    /// `‖A‖_F`.
    pub fn frobenius_norm(&self) -> f64 {
        self.values.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// `‖A − Aᵀ‖_F / ‖A‖_F`; 0 for the zero matrix, infinity for a non-square matrix.
    pub fn symmetry_error(&self) -> f64 {
        if self.nrows != self.ncols {
            return f64::INFINITY;
        }
        let norm = self.frobenius_norm();
        if norm == 0.0 {
            return 0.0;
        }
        let t = self.transpose();
        let diff = SparseMatrix::linear_combination(1.0, self, -1.0, &t)
            .expect("square matrix and its transpose have equal sizes");
        diff.frobenius_norm() / norm
    }

    /// The Kronecker product `S ⊗ I_d` in interleaved ordering: entry `(d·i + a, d·j + a) = S_ij`
    /// for `a = 0..d` (the layout of constant-weight D-NURBS matrices, docs/math.md §1).
    pub fn kron_identity(&self, d: usize) -> Self {
        let mut col_ptr = Vec::with_capacity(self.ncols * d + 1);
        let mut row_idx = Vec::with_capacity(self.nnz() * d);
        let mut values = Vec::with_capacity(self.nnz() * d);
        col_ptr.push(0);
        for j in 0..self.ncols {
            for a in 0..d {
                for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                    row_idx.push(d * self.row_idx[k] + a);
                    values.push(self.values[k]);
                }
                col_ptr.push(row_idx.len());
            }
        }
        Self {
            nrows: self.nrows * d,
            ncols: self.ncols * d,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// The `S` with `self = S ⊗ I_d` exactly ([`SparseMatrix::kron_identity`]'s inverse):
    /// every non-zero `(d·i + a, d·j + b)` has `a = b` and the same value for every `a`.
    /// `None` when `self` has no such form (stored zeros are ignored).
    pub fn kron_identity_factor(&self, d: usize) -> Option<Self> {
        if d == 0 || !self.nrows.is_multiple_of(d) || !self.ncols.is_multiple_of(d) {
            return None;
        }
        let (n, m) = (self.nrows / d, self.ncols / d);
        // S from the columns of the first copy (a = 0).
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        col_ptr.push(0);
        for j in 0..m {
            let c = d * j;
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                let (r, v) = (self.row_idx[k], self.values[k]);
                if v == 0.0 {
                    continue;
                }
                if r % d != 0 {
                    return None;
                }
                row_idx.push(r / d);
                values.push(v);
            }
            col_ptr.push(row_idx.len());
        }
        let factor = Self {
            nrows: n,
            ncols: m,
            col_ptr,
            row_idx,
            values,
        };
        // Every non-zero of self must be a copy, and there must be d copies of each.
        let mut count = 0;
        for c in 0..self.ncols {
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                let (r, v) = (self.row_idx[k], self.values[k]);
                if v == 0.0 {
                    continue;
                }
                if r % d != c % d || factor.get(r / d, c / d) != v {
                    return None;
                }
                count += 1;
            }
        }
        (count == d * factor.nnz()).then_some(factor)
    }

    /// The main diagonal (length `min(nrows, ncols)`), zeros where not stored.
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.nrows.min(self.ncols))
            .map(|i| self.get(i, i))
            .collect()
    }

    /// `Σ_ij A_ij`.
    pub fn sum(&self) -> f64 {
        self.values.iter().sum()
    }

    /// `xᵀ A x` (allocation free).
    ///
    /// # Panics
    /// If A is not square of size `x.len()`.
    pub fn quadratic_form(&self, x: &[f64]) -> f64 {
        assert!(
            self.nrows == x.len() && self.ncols == x.len(),
            "SparseMatrix::quadratic_form: vector of length {} for a {}×{} matrix",
            x.len(),
            self.nrows,
            self.ncols
        );
        let mut s = 0.0;
        for j in 0..self.ncols {
            let mut cj = 0.0;
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                cj += self.values[k] * x[self.row_idx[k]];
            }
            s += cj * x[j];
        }
        s
    }

    /// True when every stored off-diagonal value is exactly zero (a diagonal matrix in CSC form).
    pub fn is_diagonal(&self) -> bool {
        self.triplets().all(|(i, j, v)| i == j || v == 0.0)
    }

    /// True when every stored value is finite.
    pub fn all_finite(&self) -> bool {
        self.values.iter().all(|v| v.is_finite())
    }

    /// True when `self` and `other` have the same size and sparsity pattern.
    pub fn same_pattern(&self, other: &SparseMatrix) -> bool {
        self.nrows == other.nrows
            && self.ncols == other.ncols
            && self.col_ptr == other.col_ptr
            && self.row_idx == other.row_idx
    }
}
