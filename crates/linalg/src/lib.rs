//! Sparse and dense linear algebra for nurbspring — the only crate that touches
//! [faer](https://docs.rs/faer). Every public type is plain Rust: [`SparseMatrix`] (CSC, `f64`),
//! [`DenseMatrix`] (row-major), [`AssemblyPattern`] (pattern built once, values summed),
//! [`SpdSolver`] (symbolic Cholesky once, numeric per matrix), [`LuSolver`], symmetric and
//! generalized eigenproblems (dense, and sparse shift-invert Lanczos), least squares and NNLS.
//!
//! ```
//! use nurbspring_linalg::{generalized_eigen_sparse_lowest, AssemblyPattern, SparseMatrix, SpdSolver};
//! // A chain of 4 unit springs between two walls, assembled element by element.
//! let n: usize = 3;
//! let mut entries = Vec::new();
//! let mut values = Vec::new();
//! for e in 0..=n {
//!     // element e joins node e−1 and node e (nodes −1 and n are the fixed walls)
//!     let nodes = [e.checked_sub(1), (e < n).then_some(e)];
//!     for (a, ia) in nodes.iter().enumerate() {
//!         for (b, ib) in nodes.iter().enumerate() {
//!             if let (Some(i), Some(j)) = (ia, ib) {
//!                 entries.push((*i, *j));
//!                 values.push(if a == b { 1.0 } else { -1.0 });
//!             }
//!         }
//!     }
//! }
//! let k = AssemblyPattern::new(n, n, &entries).unwrap().assemble(&values);
//! assert_eq!(k.get(1, 1), 2.0);
//! // Static solve K u = f with the sparse Cholesky solver.
//! let u = SpdSolver::new(&k).unwrap().solve(&[1.0, 1.0, 1.0]);
//! assert!((u[1] - 2.0).abs() < 1e-14);
//! // Lowest eigenvalue 2 − 2cos(π/4) by shift-invert Lanczos.
//! let e = generalized_eigen_sparse_lowest(&k, &SparseMatrix::identity(n), 1, 0.0).unwrap();
//! assert!((e.values[0] - (2.0 - 2.0 * std::f64::consts::FRAC_PI_4.cos())).abs() < 1e-12);
//! ```
#![warn(missing_docs)]

mod assembly;
mod bridge;
mod dense;
mod eigen;
mod error;
mod lstsq;
mod solvers;
mod sparse;

pub use assembly::{AssemblyPattern, KroneckerPattern};
pub use dense::DenseMatrix;
pub use eigen::{
    SymmetricEigen, generalized_eigen_sparse_lowest, generalized_symmetric_eigen,
    largest_generalized_eigenvalue, symmetric_eigen, symmetric_eigenvalues,
    symmetric_extreme_eigenvalues,
};
pub use error::LinalgError;
pub use lstsq::{affine_solution_space, least_squares, nonnegative_least_squares};
pub use solvers::{
    LuSolver, SpdSolver, cholesky_solve_dense, cholesky_solve_dense_columns, solve_dense,
};
pub use sparse::{ShiftedSum, SparseMatrix};
