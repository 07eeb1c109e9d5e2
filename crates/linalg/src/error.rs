//! The error type of `nurbspring-linalg` and the argument checks shared by its solvers.

use crate::DenseMatrix;

/// Everything that can go wrong in `nurbspring-linalg`; every message carries the offending values.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LinalgError {
    /// Operand shapes do not fit the operation.
    #[error("dimension mismatch in {op}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// The operation that was attempted.
        op: &'static str,
        /// The shape the operation needed.
        expected: String,
        /// The shape it was given.
        found: String,
    },
    /// An entry index lies outside the matrix.
    #[error("index ({row}, {col}) is out of bounds for a {nrows}×{ncols} matrix")]
    IndexOutOfBounds {
        /// Row of the offending entry.
        row: usize,
        /// Column of the offending entry.
        col: usize,
        /// Rows of the matrix.
        nrows: usize,
        /// Columns of the matrix.
        ncols: usize,
    },
    /// A Cholesky factorization met a non-positive pivot.
    #[error("matrix is not positive definite: {detail}")]
    NotPositiveDefinite {
        /// Where the factorization failed.
        detail: String,
    },
    /// A matrix is singular (or rank deficient) to working precision.
    #[error("matrix is singular: {detail}")]
    Singular {
        /// Which pivot or rank test failed.
        detail: String,
    },
    /// An iterative method stopped before reaching its tolerance.
    #[error("{what} did not converge in {iterations} iterations")]
    NoConvergence {
        /// The method.
        what: &'static str,
        /// Iterations performed.
        iterations: usize,
    },
    /// An input or result contains NaN or infinity.
    #[error("non-finite value (NaN or infinity) in {what}")]
    NonFinite {
        /// The quantity that was not finite.
        what: &'static str,
    },
    /// An error reported by faer, as text (some faer errors do not implement `std::error::Error`).
    #[error("faer: {0}")]
    Faer(String),
}

pub(crate) fn mismatch(
    op: &'static str,
    expected: impl ToString,
    found: impl ToString,
) -> LinalgError {
    LinalgError::DimensionMismatch {
        op,
        expected: expected.to_string(),
        found: found.to_string(),
    }
}

/// Checks that `b` matches the rows of `a` and that both are finite.
pub(crate) fn check_system(
    op: &'static str,
    a: &DenseMatrix,
    b: &[f64],
) -> Result<(), LinalgError> {
    if b.len() != a.nrows() {
        return Err(mismatch(
            op,
            format!("right-hand side of length {}", a.nrows()),
            b.len(),
        ));
    }
    if !a.data().iter().chain(b).all(|v| v.is_finite()) {
        return Err(LinalgError::NonFinite { what: op });
    }
    Ok(())
}
