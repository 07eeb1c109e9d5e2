//! Direct solvers: sparse Cholesky and LU (faer), dense Cholesky and partial-pivoting LU.

use faer::linalg::solvers::Solve;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::linalg::{LltError, LuError};
use faer::{MatMut, Side};

use crate::bridge::{dense_ref, sparse_ref};
use crate::dense::norm;
use crate::error::mismatch;
use crate::{DenseMatrix, LinalgError, SparseMatrix};

fn check_square(op: &'static str, nrows: usize, ncols: usize) -> Result<(), LinalgError> {
    if nrows != ncols {
        return Err(mismatch(op, "a square matrix", format!("{nrows}×{ncols}")));
    }
    Ok(())
}

fn llt_error(e: LltError) -> LinalgError {
    match e {
        LltError::Numeric(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot {
            index,
        }) => LinalgError::NotPositiveDefinite {
            detail: format!(
                "non-positive pivot at elimination step {index} of the sparse Cholesky factorization"
            ),
        },
        LltError::Generic(g) => LinalgError::Faer(format!("{g:?}")),
    }
}

/// Sparse symmetric positive-definite solver: `A = L Lᵀ` by faer's sparse Cholesky (AMD
/// ordering, supernodal or simplicial). The symbolic analysis is done once in [`SpdSolver::new`];
/// [`SpdSolver::refactor`] redoes only the numeric factorization for a matrix with the same
/// pattern (a different pattern triggers a new symbolic analysis). Only the lower triangle of
/// A is read, so A must be symmetric.
///
/// ```
/// use nurbspring_linalg::{SparseMatrix, SpdSolver};
/// let a = SparseMatrix::from_triplets(2, 2, &[(0, 0, 4.0), (1, 0, 1.0), (0, 1, 1.0), (1, 1, 3.0)]).unwrap();
/// let x = SpdSolver::new(&a).unwrap().solve(&[1.0, 2.0]);
/// assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-14 && (x[0] + 3.0 * x[1] - 2.0).abs() < 1e-14);
/// ```
#[derive(Clone, Debug)]
pub struct SpdSolver {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: Option<SymbolicLlt<usize>>,
    llt: Option<Llt<usize, f64>>,
}

impl SpdSolver {
    /// Symbolic analysis and numeric Cholesky factorization of the symmetric matrix `a`.
    ///
    /// Errors: [`LinalgError::NotPositiveDefinite`] when a pivot is not positive,
    /// [`LinalgError::NonFinite`] on NaN or infinite values, `DimensionMismatch` if not square.
    pub fn new(a: &SparseMatrix) -> Result<Self, LinalgError> {
        check_square("SpdSolver::new", a.nrows(), a.ncols())?;
        let mut s = Self {
            n: a.nrows(),
            col_ptr: Vec::new(),
            row_idx: Vec::new(),
            symbolic: None,
            llt: None,
        };
        s.refactor(a)?;
        Ok(s)
    }

    fn analyze(a: &SparseMatrix) -> Result<Option<SymbolicLlt<usize>>, LinalgError> {
        if a.nrows() == 0 {
            return Ok(None);
        }
        let sym = SymbolicSparseColMatRef::new_checked(
            a.nrows(),
            a.ncols(),
            a.col_ptr(),
            None,
            a.row_idx(),
        );
        Ok(Some(SymbolicLlt::try_new(sym, Side::Lower).map_err(
            |e| LinalgError::Faer(format!("symbolic Cholesky: {e:?}")),
        )?))
    }

    /// Numeric refactorization for new values; the symbolic analysis of [`SpdSolver::new`] is
    /// reused when the pattern is the same (another pattern gets a new analysis). On error the
    /// previous factorization is kept unchanged.
    pub fn refactor(&mut self, a: &SparseMatrix) -> Result<(), LinalgError> {
        check_square("SpdSolver::refactor", a.nrows(), a.ncols())?;
        if !a.all_finite() {
            return Err(LinalgError::NonFinite {
                what: "matrix given to SpdSolver",
            });
        }
        let same_pattern = self.llt.is_some()
            && a.nrows() == self.n
            && a.col_ptr() == self.col_ptr.as_slice()
            && a.row_idx() == self.row_idx.as_slice();
        let symbolic = if same_pattern {
            self.symbolic.clone()
        } else {
            Self::analyze(a)?
        };
        let llt = match &symbolic {
            Some(sym) => Some(
                Llt::try_new_with_symbolic(sym.clone(), sparse_ref(a), Side::Lower)
                    .map_err(llt_error)?,
            ),
            None => None,
        };
        if !same_pattern {
            self.n = a.nrows();
            self.col_ptr = a.col_ptr().to_vec();
            self.row_idx = a.row_idx().to_vec();
        }
        self.symbolic = symbolic;
        self.llt = llt;
        Ok(())
    }

    /// Dimension of the factored matrix.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `rhs` with `A⁻¹ rhs` (forward and back substitution with the Cholesky factor).
    ///
    /// # Panics
    /// If `rhs.len() != self.dim()`.
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        assert_eq!(
            rhs.len(),
            self.n,
            "SpdSolver::solve_in_place: right-hand side of length {} for dimension {}",
            rhs.len(),
            self.n
        );
        if let Some(llt) = &self.llt {
            llt.solve_in_place(MatMut::from_column_major_slice_mut(rhs, self.n, 1));
        }
    }

    /// `A⁻¹ rhs`.
    pub fn solve(&self, rhs: &[f64]) -> Vec<f64> {
        let mut x = rhs.to_vec();
        self.solve_in_place(&mut x);
        x
    }
}

/// General sparse LU with partial pivoting (faer's supernodal/simplicial sparse LU, COLAMD
/// ordering), for indefinite or unsymmetric systems, e.g. Newton steps with compressed springs.
///
/// ```
/// use nurbspring_linalg::{LuSolver, SparseMatrix};
/// // Symmetric indefinite: Cholesky would fail.
/// let a = SparseMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 1.0)]).unwrap();
/// let mut x = vec![3.0, 3.0];
/// LuSolver::new(&a).unwrap().solve_in_place(&mut x);
/// assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
/// ```
#[derive(Clone, Debug)]
pub struct LuSolver {
    n: usize,
    lu: Option<Lu<usize, f64>>,
}

impl LuSolver {
    /// Factors `a = P L U Q`. Errors with [`LinalgError::Singular`] when the matrix is
    /// structurally singular or when a test solve `A x = A·1` gives a non-finite or inaccurate
    /// `x` (relative residual above 1e-6, i.e. numerically singular).
    pub fn new(a: &SparseMatrix) -> Result<Self, LinalgError> {
        check_square("LuSolver::new", a.nrows(), a.ncols())?;
        if !a.all_finite() {
            return Err(LinalgError::NonFinite {
                what: "matrix given to LuSolver",
            });
        }
        let n = a.nrows();
        if n == 0 {
            return Ok(Self { n, lu: None });
        }
        let view = sparse_ref(a);
        let symbolic = SymbolicLu::try_new(view.symbolic())
            .map_err(|e| LinalgError::Faer(format!("symbolic LU: {e:?}")))?;
        let lu = Lu::try_new_with_symbolic(symbolic, view).map_err(|e| match e {
            LuError::SymbolicSingular { index } => LinalgError::Singular {
                detail: format!("structurally singular at LU step {index}"),
            },
            LuError::Generic(g) => LinalgError::Faer(format!("{g:?}")),
        })?;
        let s = Self { n, lu: Some(lu) };
        // Numerical singularity shows up as non-finite or wrong solutions: probe with b = A·1.
        let mut b = vec![0.0; n];
        let ones: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * ((i % 7) as f64)).collect();
        a.mul_vec(&ones, &mut b);
        let mut x = b.clone();
        s.solve_in_place(&mut x);
        let mut r = b.clone();
        a.mul_vec_add(-1.0, &x, &mut r);
        let (rn, bn) = (norm(&r), norm(&b));
        if !x.iter().all(|v| v.is_finite()) || rn > 1e-6 * bn.max(f64::MIN_POSITIVE) {
            return Err(LinalgError::Singular {
                detail: format!(
                    "sparse LU of a {n}×{n} matrix is numerically singular (probe residual {:.3e})",
                    rn / bn.max(f64::MIN_POSITIVE)
                ),
            });
        }
        Ok(s)
    }

    /// Dimension of the factored matrix.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `rhs` with `A⁻¹ rhs`.
    ///
    /// # Panics
    /// If `rhs.len() != self.dim()`.
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        assert_eq!(
            rhs.len(),
            self.n,
            "LuSolver::solve_in_place: right-hand side of length {} for dimension {}",
            rhs.len(),
            self.n
        );
        if let Some(lu) = &self.lu {
            lu.solve_in_place(MatMut::from_column_major_slice_mut(rhs, self.n, 1));
        }
    }

    /// `A⁻¹ rhs`.
    pub fn solve(&self, rhs: &[f64]) -> Vec<f64> {
        let mut x = rhs.to_vec();
        self.solve_in_place(&mut x);
        x
    }
}

fn check_rhs(op: &'static str, a: &DenseMatrix, b: &[f64]) -> Result<(), LinalgError> {
    check_square(op, a.nrows(), a.ncols())?;
    crate::error::check_system(op, a, b)
}

/// Solves `A x = b` for a dense symmetric positive-definite A by Cholesky `A = L Lᵀ` (faer,
/// lower triangle read). Errors with [`LinalgError::NotPositiveDefinite`] naming the pivot.
///
/// ```
/// use nurbspring_linalg::{cholesky_solve_dense, DenseMatrix};
/// let a = DenseMatrix::from_row_major(2, 2, vec![2.0, 1.0, 1.0, 2.0]);
/// let x = cholesky_solve_dense(&a, &[3.0, 3.0]).unwrap();
/// assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
/// ```
pub fn cholesky_solve_dense(a: &DenseMatrix, b: &[f64]) -> Result<Vec<f64>, LinalgError> {
    check_rhs("cholesky_solve_dense", a, b)?;
    let n = a.nrows();
    let mut x = b.to_vec();
    if n == 0 {
        return Ok(x);
    }
    let llt = dense_ref(a)
        .llt(Side::Lower)
        .map_err(|e| LinalgError::NotPositiveDefinite {
            detail: format!("dense Cholesky: {e:?}"),
        })?;
    llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut x, n, 1));
    Ok(x)
}

/// Solves `A x = b` by LU with partial (row) pivoting, `P A = L U` (faer). Errors with
/// [`LinalgError::Singular`] when a pivot `|U_ii|` is below `n·ε·max|U|`.
///
/// ```
/// use nurbspring_linalg::{solve_dense, DenseMatrix};
/// let a = DenseMatrix::from_row_major(2, 2, vec![0.0, 1.0, 1.0, 0.0]);
/// assert_eq!(solve_dense(&a, &[2.0, 3.0]).unwrap(), vec![3.0, 2.0]);
/// ```
pub fn solve_dense(a: &DenseMatrix, b: &[f64]) -> Result<Vec<f64>, LinalgError> {
    check_rhs("solve_dense", a, b)?;
    let n = a.nrows();
    let mut x = b.to_vec();
    if n == 0 {
        return Ok(x);
    }
    let lu = dense_ref(a).partial_piv_lu();
    let u = lu.U();
    let umax = (0..n)
        .flat_map(|j| (0..=j).map(move |i| (i, j)))
        .fold(0.0_f64, |m, (i, j)| m.max(u[(i, j)].abs()));
    let threshold = (n as f64) * f64::EPSILON * umax;
    for i in 0..n {
        if u[(i, i)].is_nan() || u[(i, i)].abs() <= threshold {
            return Err(LinalgError::Singular {
                detail: format!(
                    "LU pivot {i} is {:.3e} (threshold {threshold:.3e})",
                    u[(i, i)]
                ),
            });
        }
    }
    lu.solve_in_place(MatMut::from_column_major_slice_mut(&mut x, n, 1));
    Ok(x)
}
