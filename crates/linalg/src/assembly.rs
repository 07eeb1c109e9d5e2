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
