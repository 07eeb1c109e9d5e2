//! Private conversions between our plain types and faer's. Nothing here is public.

use faer::MatRef;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

use crate::{DenseMatrix, SparseMatrix};

/// A zero-copy faer view of a row-major dense matrix.
pub(crate) fn dense_ref(a: &DenseMatrix) -> MatRef<'_, f64> {
    MatRef::from_row_major_slice(a.data(), a.nrows(), a.ncols())
}

/// Copies a faer matrix into a [`DenseMatrix`].
pub(crate) fn from_faer(a: MatRef<'_, f64>) -> DenseMatrix {
    DenseMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

/// A zero-copy faer view of a CSC matrix (its invariants are checked by faer).
pub(crate) fn sparse_ref(a: &SparseMatrix) -> SparseColMatRef<'_, usize, f64> {
    let sym =
        SymbolicSparseColMatRef::new_checked(a.nrows(), a.ncols(), a.col_ptr(), None, a.row_idx());
    SparseColMatRef::new(sym, a.values())
}
