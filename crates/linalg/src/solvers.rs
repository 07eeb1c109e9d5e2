//! Direct solvers: sparse Cholesky and LU (faer), dense Cholesky and partial-pivoting LU.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::linalg::{LuError, SupernodalThreshold};
use faer::{Conj, MatMut, Par, Side};

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

fn llt_error(e: faer::linalg::cholesky::llt::factor::LltError) -> LinalgError {
    match e {
        faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
            LinalgError::NotPositiveDefinite {
                detail: format!(
                    "non-positive pivot at elimination step {index} of the sparse Cholesky factorization"
                ),
            }
        }
    }
}

/// Sparse symmetric positive-definite solver: `A = L Lᵀ` by faer's sparse Cholesky (AMD
/// ordering, supernodal or simplicial). The symbolic analysis is done once in [`SpdSolver::new`];
/// [`SpdSolver::refactor`] redoes only the numeric factorization for a matrix with the same
/// pattern (a different pattern triggers a new symbolic analysis), into factor storage
/// allocated once (faer's scratch workspace is allocated per call). Small systems factor and
/// solve on the calling thread; large ones use rayon's pool. Only the lower
/// triangle of A is read, so A must be symmetric.
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
    symbolic: Option<Arc<SymbolicCholesky<usize>>>,
    /// The numeric factor (`symbolic.len_val()` values).
    factor: Vec<f64>,
    /// Where the next numeric factorization is written, swapped with `factor` on success so
    /// that a failed refactorization leaves the previous factor in place.
    spare: Vec<f64>,
}

/// Systems with fewer unknowns than this factor and solve on one thread: below it, handing
/// work to the pool costs more than it saves.
const PARALLEL_MIN_DIM: usize = 20_000;

/// From this many unknowns on, the supernodal factorization is used whatever faer's flop
/// estimate says: on lattice and D-NURBS Newton matrices (3 × 3 blocks per node) it factors
/// and solves about 1.6× faster than the simplicial one from a few thousand unknowns on
/// (measured on a 33 × 33 lattice, 3,267 unknowns), and is no faster below.
const SUPERNODAL_MIN_DIM: usize = 2_000;

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
            factor: Vec::new(),
            spare: Vec::new(),
        };
        s.refactor(a)?;
        Ok(s)
    }

    fn par(n: usize) -> Par {
        if n < PARALLEL_MIN_DIM {
            Par::Seq
        } else {
            faer::get_global_parallelism()
        }
    }

    fn analyze(a: &SparseMatrix) -> Result<Option<Arc<SymbolicCholesky<usize>>>, LinalgError> {
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
        let symbolic = factorize_symbolic_cholesky(
            sym,
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: if a.nrows() >= SUPERNODAL_MIN_DIM {
                    SupernodalThreshold::FORCE_SUPERNODAL
                } else {
                    SupernodalThreshold::AUTO
                },
                ..Default::default()
            },
        )
        .map_err(|e| LinalgError::Faer(format!("symbolic Cholesky: {e:?}")))?;
        Ok(Some(Arc::new(symbolic)))
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
        let same_pattern = self.symbolic.is_some()
            && a.nrows() == self.n
            && a.col_ptr() == self.col_ptr.as_slice()
            && a.row_idx() == self.row_idx.as_slice();
        let symbolic = if same_pattern {
            self.symbolic.clone()
        } else {
            Self::analyze(a)?
        };
        let Some(sym) = &symbolic else {
            // The empty system: nothing to factor.
            self.n = 0;
            self.symbolic = None;
            self.factor.clear();
            return Ok(());
        };
        let par = Self::par(a.nrows());
        self.spare.resize(sym.len_val(), 0.0);
        let mut buffer =
            MemBuffer::try_new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
                .map_err(|_| LinalgError::Faer("out of memory for the Cholesky workspace".into()))?;
        sym.factorize_numeric_llt::<f64>(
            &mut self.spare,
            sparse_ref(a),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .map_err(llt_error)?;
        std::mem::swap(&mut self.factor, &mut self.spare);
        if !same_pattern {
            self.n = a.nrows();
            self.col_ptr = a.col_ptr().to_vec();
            self.row_idx = a.row_idx().to_vec();
        }
        self.symbolic = symbolic;
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
        let Some(sym) = &self.symbolic else {
            return;
        };
        let par = Self::par(self.n);
        let mut buffer = MemBuffer::new(sym.solve_in_place_scratch::<f64>(1, par));
        LltRef::new(sym, &self.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, self.n, 1),
            par,
            MemStack::new(&mut buffer),
        );
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

/// Solves `A X = B` for a dense symmetric positive-definite A and every column of B at once,
/// by one Cholesky factorization `A = L Lᵀ` (faer, lower triangle read). Errors with
/// [`LinalgError::NotPositiveDefinite`], or [`LinalgError::DimensionMismatch`] when B's rows
/// are not A's.
///
/// ```
/// use nurbspring_linalg::{cholesky_solve_dense_columns, DenseMatrix};
/// let a = DenseMatrix::from_row_major(2, 2, vec![2.0, 1.0, 1.0, 2.0]);
/// let b = DenseMatrix::from_row_major(2, 2, vec![3.0, 1.0, 3.0, -1.0]);
/// let x = cholesky_solve_dense_columns(&a, &b).unwrap();
/// // Columns (1, 1) and (1, −1).
/// for (got, want) in x.data().iter().zip([1.0, 1.0, 1.0, -1.0]) {
///     assert!((got - want).abs() < 1e-15);
/// }
/// ```
pub fn cholesky_solve_dense_columns(
    a: &DenseMatrix,
    b: &DenseMatrix,
) -> Result<DenseMatrix, LinalgError> {
    let n = a.nrows();
    if a.ncols() != n || b.nrows() != n {
        return Err(LinalgError::DimensionMismatch {
            op: "cholesky_solve_dense_columns",
            expected: format!("A square and B with its {} rows", a.nrows()),
            found: format!(
                "A {}×{}, B {}×{}",
                a.nrows(),
                a.ncols(),
                b.nrows(),
                b.ncols()
            ),
        });
    }
    let k = b.ncols();
    if n == 0 || k == 0 {
        return Ok(b.clone());
    }
    let llt = dense_ref(a)
        .llt(Side::Lower)
        .map_err(|e| LinalgError::NotPositiveDefinite {
            detail: format!("dense Cholesky: {e:?}"),
        })?;
    // B's transpose in row-major order is B in column-major order.
    let mut x = b.transpose().data().to_vec();
    llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut x, n, k));
    Ok(DenseMatrix::from_row_major(k, n, x).transpose())
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
