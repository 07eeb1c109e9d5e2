//! Symmetric and generalized symmetric eigenproblems: dense (faer's self-adjoint EVD after a
//! Cholesky reduction) and sparse (Lanczos with full reorthogonalization, shift-invert).

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

use crate::bridge::{dense_ref, from_faer};
use crate::error::mismatch;
use crate::{DenseMatrix, LinalgError, LuSolver, SparseMatrix, SpdSolver};

mod lanczos;
#[cfg(test)]
use lanczos::*;
pub use lanczos::{generalized_eigen_sparse_lowest, largest_generalized_eigenvalue};

/// Eigenvalues in ascending order and the matching eigenvectors as the columns of `vectors`.
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetricEigen {
    /// Eigenvalues, ascending.
    pub values: Vec<f64>,
    /// Eigenvectors, column `i` for `values[i]` (`n × values.len()`).
    pub vectors: DenseMatrix,
}

fn check_dense_square(op: &'static str, a: &DenseMatrix) -> Result<(), LinalgError> {
    if a.nrows() != a.ncols() {
        return Err(mismatch(
            op,
            "a square matrix",
            format!("{}×{}", a.nrows(), a.ncols()),
        ));
    }
    if !a.data().iter().all(|v| v.is_finite()) {
        return Err(LinalgError::NonFinite { what: op });
    }
    Ok(())
}

/// Fixes the sign of each eigenvector so that its entry of largest magnitude is positive
/// (makes results reproducible).
fn normalize_signs(vectors: &mut DenseMatrix) {
    let (n, m) = (vectors.nrows(), vectors.ncols());
    for j in 0..m {
        let mut best = 0.0_f64;
        for i in 0..n {
            let v = vectors[(i, j)];
            if v.abs() > best.abs() * (1.0 + 1e-12) {
                best = v;
            }
        }
        if best < 0.0 {
            for i in 0..n {
                vectors[(i, j)] = -vectors[(i, j)];
            }
        }
    }
}

fn symmetric_part(a: &DenseMatrix) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

fn faer_evd(a: &Mat<f64>, what: &'static str) -> Result<(Vec<f64>, Mat<f64>), LinalgError> {
    // faer 0.24's divide and conquer loses accuracy on matrices of large norm (measured:
    // eigenvalue errors of 9e-7 ‖A‖ for n = 675 at ‖A‖ = 1e10, round-off at ‖A‖ = 1): the
    // matrix is scaled to unit max-norm first and the eigenvalues scaled back.
    let scale = max_abs(a);
    let scaled = if scale > 0.0 && scale.is_finite() {
        Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] / scale)
    } else {
        a.to_owned()
    };
    let unscale = if scale > 0.0 && scale.is_finite() {
        scale
    } else {
        1.0
    };
    let evd = scaled
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| LinalgError::Faer(format!("{what}: {e:?}")))?;
    let s = evd.S().column_vector();
    let values = (0..a.nrows()).map(|i| s[i] * unscale).collect();
    Ok((values, evd.U().to_owned()))
}

/// The largest absolute entry.
fn max_abs(a: &Mat<f64>) -> f64 {
    let mut m = 0.0_f64;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            m = m.max(a[(i, j)].abs());
        }
    }
    m
}

/// `A = Q Λ Qᵀ` for a dense symmetric A (faer's self-adjoint EVD: Householder
/// tridiagonalization and divide and conquer / QR). The symmetric part `(A + Aᵀ)/2` is used.
/// Eigenvalues ascending, eigenvectors orthonormal columns.
///
/// ```
/// use nurbspring_linalg::{symmetric_eigen, DenseMatrix};
/// let a = DenseMatrix::from_row_major(2, 2, vec![2.0, 1.0, 1.0, 2.0]);
/// let e = symmetric_eigen(&a).unwrap();
/// assert!((e.values[0] - 1.0).abs() < 1e-14 && (e.values[1] - 3.0).abs() < 1e-14);
/// ```
pub fn symmetric_eigen(a: &DenseMatrix) -> Result<SymmetricEigen, LinalgError> {
    check_dense_square("symmetric_eigen", a)?;
    let n = a.nrows();
    if n == 0 {
        return Ok(SymmetricEigen {
            values: Vec::new(),
            vectors: DenseMatrix::zeros(0, 0),
        });
    }
    let (values, u) = faer_evd(&symmetric_part(a), "symmetric_eigen")?;
    let mut vectors = from_faer(u.as_ref());
    normalize_signs(&mut vectors);
    Ok(SymmetricEigen { values, vectors })
}

/// The eigenvalues of a dense symmetric A, ascending (the symmetric part `(A + Aᵀ)/2` is used),
/// without the eigenvectors: the same values as [`symmetric_eigen`] at a fraction of the cost.
///
/// ```
/// use nurbspring_linalg::{symmetric_eigenvalues, DenseMatrix};
/// let a = DenseMatrix::from_row_major(2, 2, vec![2.0, 1.0, 1.0, 2.0]);
/// let v = symmetric_eigenvalues(&a).unwrap();
/// assert!((v[0] - 1.0).abs() < 1e-14 && (v[1] - 3.0).abs() < 1e-14);
/// ```
pub fn symmetric_eigenvalues(a: &DenseMatrix) -> Result<Vec<f64>, LinalgError> {
    check_dense_square("symmetric_eigenvalues", a)?;
    if a.nrows() == 0 {
        return Ok(Vec::new());
    }
    // Scaled to unit max-norm as in `faer_evd`.
    let sym = symmetric_part(a);
    let scale = max_abs(&sym);
    let unscale = if scale > 0.0 && scale.is_finite() {
        scale
    } else {
        1.0
    };
    let mut values = Mat::from_fn(sym.nrows(), sym.ncols(), |i, j| sym[(i, j)] / unscale)
        .self_adjoint_eigenvalues(Side::Lower)
        .map_err(|e| LinalgError::Faer(format!("symmetric_eigenvalues: {e:?}")))?;
    for v in &mut values {
        *v *= unscale;
    }
    values.sort_by(f64::total_cmp);
    Ok(values)
}

/// The smallest and the largest eigenvalue of a dense symmetric matrix (its symmetric part):
/// faer's Householder tridiagonalization, then bisection on Sturm counts of the tridiagonal
/// matrix for the two ends of the spectrum alone (Golub & Van Loan §8.4.1), to the round-off
/// of the tridiagonal's entries. `‖A‖₂ = max(|λ_min|, |λ_max|)` costs the reduction and two
/// bisections instead of a whole spectrum.
/// ```
/// use nurbspring_linalg::{symmetric_extreme_eigenvalues, DenseMatrix};
/// let a = DenseMatrix::from_row_major(3, 3, vec![2.0, 1.0, 0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0]);
/// let (lo, hi) = symmetric_extreme_eigenvalues(&a).unwrap();
/// let r2 = 2f64.sqrt();
/// assert!((lo - (2.0 - r2)).abs() < 1e-14 && (hi - (2.0 + r2)).abs() < 1e-14);
/// ```
pub fn symmetric_extreme_eigenvalues(a: &DenseMatrix) -> Result<(f64, f64), LinalgError> {
    check_dense_square("symmetric_extreme_eigenvalues", a)?;
    let n = a.nrows();
    if n == 0 {
        return Err(mismatch(
            "symmetric_extreme_eigenvalues",
            "a non-empty matrix",
            "0×0".to_string(),
        ));
    }
    let (d, e) = tridiagonal_of(&symmetric_part(a));
    Ok((
        tridiagonal_eigenvalue(&d, &e, 0),
        tridiagonal_eigenvalue(&d, &e, n - 1),
    ))
}

/// The diagonal and off-diagonal of the tridiagonal matrix orthogonally similar to the
/// symmetric `a` (faer's blocked Householder reduction, one thread).
fn tridiagonal_of(a: &Mat<f64>) -> (Vec<f64>, Vec<f64>) {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::tridiag;
    let n = a.nrows();
    if n == 1 {
        return (vec![a[(0, 0)]], Vec::new());
    }
    let mut trid = a.to_owned();
    let bs = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(n, n);
    let mut householder = Mat::<f64>::zeros(bs, n - 1);
    let mut buffer = MemBuffer::new(tridiag::tridiag_in_place_scratch::<f64>(
        n,
        Par::Seq,
        Default::default(),
    ));
    tridiag::tridiag_in_place(
        trid.as_mut(),
        householder.as_mut(),
        Par::Seq,
        MemStack::new(&mut buffer),
        Default::default(),
    );
    let d = (0..n).map(|i| trid[(i, i)]).collect();
    let e = (0..n - 1).map(|i| trid[(i + 1, i)]).collect();
    (d, e)
}

/// The `k`-th smallest eigenvalue (from 0) of the symmetric tridiagonal matrix with diagonal
/// `d` and off-diagonal `e`, by bisection on the Sturm count (the number of negative pivots of
/// `T − x I = L D Lᵀ`, which is the number of eigenvalues below x), inside Gershgorin's
/// interval, to the interval's round-off.
fn tridiagonal_eigenvalue(d: &[f64], e: &[f64], k: usize) -> f64 {
    let n = d.len();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..n {
        let r = if i > 0 { e[i - 1].abs() } else { 0.0 } + if i + 1 < n { e[i].abs() } else { 0.0 };
        lo = lo.min(d[i] - r);
        hi = hi.max(d[i] + r);
    }
    let scale = lo.abs().max(hi.abs());
    // A pivot that vanishes is replaced by a tiny one of the same sign convention (LAPACK's
    // dstebz): the count stays correct to the round-off of the entries.
    let tiny = f64::MIN_POSITIVE.max(f64::EPSILON * scale * f64::EPSILON);
    let below = |x: f64| -> usize {
        let mut count = 0;
        let mut q = d[0] - x;
        for i in 0..n {
            if i > 0 {
                q = d[i] - x - e[i - 1] * e[i - 1] / q;
            }
            if q.abs() < tiny {
                q = -tiny;
            }
            if q < 0.0 {
                count += 1;
            }
        }
        count
    };
    // Widen by round-off so that the interval certainly holds the spectrum.
    let pad = 2.0 * f64::EPSILON * scale * n as f64 + f64::MIN_POSITIVE;
    lo -= pad;
    hi += pad;
    while hi - lo > 2.0 * f64::EPSILON * lo.abs().max(hi.abs()) + f64::MIN_POSITIVE {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) > k {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `K φ = λ M φ` with K symmetric and M symmetric positive definite, by Cholesky reduction:
/// `M = L Lᵀ`, `C = L⁻¹ K L⁻ᵀ = Y Λ Yᵀ`, `φ = L⁻ᵀ Y` (Golub & Van Loan §8.7.2). Eigenvalues
/// ascending; eigenvectors M-orthonormal (`ΦᵀMΦ = I`). A diagonal M (a lumped mass) has
/// `L = diag(√m_i)`: C and Φ are then scaled entry by entry, the eigen-decomposition of C
/// being the only `O(n³)` work (the general reduction adds a Cholesky factorization and three
/// triangular solves, about as much again).
///
/// ```
/// use nurbspring_linalg::{generalized_symmetric_eigen, DenseMatrix};
/// let k = DenseMatrix::from_row_major(2, 2, vec![2.0, -1.0, -1.0, 2.0]);
/// let m = DenseMatrix::from_row_major(2, 2, vec![2.0, 0.0, 0.0, 2.0]);
/// let e = generalized_symmetric_eigen(&k, &m).unwrap();
/// assert!((e.values[0] - 0.5).abs() < 1e-14 && (e.values[1] - 1.5).abs() < 1e-14);
/// ```
pub fn generalized_symmetric_eigen(
    k: &DenseMatrix,
    m: &DenseMatrix,
) -> Result<SymmetricEigen, LinalgError> {
    check_dense_square("generalized_symmetric_eigen (K)", k)?;
    check_dense_square("generalized_symmetric_eigen (M)", m)?;
    if k.nrows() != m.nrows() {
        return Err(mismatch(
            "generalized_symmetric_eigen",
            format!("M of size {}", k.nrows()),
            format!("{}", m.nrows()),
        ));
    }
    let n = k.nrows();
    if n == 0 {
        return Ok(SymmetricEigen {
            values: Vec::new(),
            vectors: DenseMatrix::zeros(0, 0),
        });
    }
    if let Some(d) = diagonal(m) {
        return diagonal_reduction(k, &d);
    }
    let llt = dense_ref(m)
        .llt(Side::Lower)
        .map_err(|e| LinalgError::NotPositiveDefinite {
            detail: format!("Cholesky of the mass matrix M: {e:?}"),
        })?;
    let l = llt.L();
    let mut c = symmetric_part(k);
    l.solve_lower_triangular_in_place(c.as_mut()); // L⁻¹ K
    let mut c2 = c.transpose().to_owned(); // K L⁻ᵀ
    l.solve_lower_triangular_in_place(c2.as_mut()); // L⁻¹ K L⁻ᵀ
    let sym = Mat::from_fn(n, n, |i, j| 0.5 * (c2[(i, j)] + c2[(j, i)]));
    let (values, mut y) = faer_evd(&sym, "generalized_symmetric_eigen")?;
    l.transpose().solve_upper_triangular_in_place(y.as_mut()); // φ = L⁻ᵀ Y
    let mut vectors = from_faer(y.as_ref());
    normalize_signs(&mut vectors);
    Ok(SymmetricEigen { values, vectors })
}

/// The diagonal of `m` when every entry off it is zero.
fn diagonal(m: &DenseMatrix) -> Option<Vec<f64>> {
    let n = m.nrows();
    for j in 0..n {
        for i in 0..n {
            if i != j && m[(i, j)] != 0.0 {
                return None;
            }
        }
    }
    Some((0..n).map(|i| m[(i, i)]).collect())
}

/// [`generalized_symmetric_eigen`] for `M = diag(d)`: `L = diag(√d)`, the same reduction
/// written entry by entry.
fn diagonal_reduction(k: &DenseMatrix, d: &[f64]) -> Result<SymmetricEigen, LinalgError> {
    // The entries are finite (checked by the caller).
    if let Some(i) = d.iter().position(|&x| x <= 0.0) {
        return Err(LinalgError::NotPositiveDefinite {
            detail: format!(
                "Cholesky of the mass matrix M: diagonal entry {i} is {}, not positive",
                d[i]
            ),
        });
    }
    let n = d.len();
    let l: Vec<f64> = d.iter().map(|x| x.sqrt()).collect();
    let sym = Mat::from_fn(n, n, |i, j| {
        let kij = 0.5 * (k[(i, j)] + k[(j, i)]);
        kij / l[i] / l[j]
    });
    let (values, y) = faer_evd(&sym, "generalized_symmetric_eigen")?;
    let mut vectors = DenseMatrix::from_fn(n, n, |i, j| y[(i, j)] / l[i]);
    normalize_signs(&mut vectors);
    Ok(SymmetricEigen { values, vectors })
}

// ---------------------------------------------------------------------------------------------
// Lanczos machinery.

#[cfg(test)]
mod tests;
