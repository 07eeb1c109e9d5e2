//! Least squares: Householder QR, Lawson–Hanson NNLS, affine solution spaces by SVD.

use crate::bridge::dense_ref;
use crate::dense::norm;
use crate::error::check_system;
use crate::{DenseMatrix, LinalgError};

/// `min ‖A x − b‖₂` for a full-column-rank `m × n` A (`m ≥ n`) by Householder QR
/// (`A = Q R`, `x = R⁻¹ Qᵀ b`; Golub & Van Loan §5.3.3; faer's blocked Householder QR).
/// Errors with [`LinalgError::Singular`] naming the rank-deficient column when
/// `|R_jj| ≤ max(m, n)·ε·max_i |R_ii|`, or when `m < n`.
///
/// ```
/// use nurbspring_linalg::{least_squares, DenseMatrix};
/// // Fit y = c0 + c1 t through (0, 1), (1, 3), (2, 5): exact line 1 + 2t.
/// let a = DenseMatrix::from_row_major(3, 2, vec![1.0, 0.0, 1.0, 1.0, 1.0, 2.0]);
/// let x = least_squares(&a, &[1.0, 3.0, 5.0]).unwrap();
/// assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 2.0).abs() < 1e-14);
/// ```
pub fn least_squares(a: &DenseMatrix, b: &[f64]) -> Result<Vec<f64>, LinalgError> {
    check_system("least_squares", a, b)?;
    let (m, n) = (a.nrows(), a.ncols());
    if n == 0 {
        return Ok(Vec::new());
    }
    if m < n {
        return Err(LinalgError::Singular {
            detail: format!("least squares with {m} equations for {n} unknowns is rank deficient"),
        });
    }
    let qr = dense_ref(a).qr();
    let r = qr.thin_R();
    let rmax = (0..n).fold(0.0_f64, |acc, i| acc.max(r[(i, i)].abs()));
    let threshold = (m.max(n) as f64) * f64::EPSILON * rmax;
    for j in 0..n {
        if r[(j, j)].is_nan() || r[(j, j)].abs() <= threshold {
            return Err(LinalgError::Singular {
                detail: format!(
                    "least squares matrix ({m}×{n}) is rank deficient at column {j}: |R_jj| = {:.3e} ≤ {threshold:.3e}",
                    r[(j, j)].abs()
                ),
            });
        }
    }
    let q = qr.compute_thin_Q();
    let mut x: Vec<f64> = (0..n)
        .map(|j| (0..m).map(|i| q[(i, j)] * b[i]).sum())
        .collect();
    for i in (0..n).rev() {
        let mut s = x[i];
        for j in i + 1..n {
            s -= r[(i, j)] * x[j];
        }
        x[i] = s / r[(i, i)];
    }
    Ok(x)
}

/// Lawson–Hanson active-set NNLS (*Solving Least Squares Problems*, 1974, ch. 23):
/// `min ‖A x − b‖₂` subject to `x ≥ 0`. At the solution the KKT conditions hold: `x ≥ 0`,
/// `w = Aᵀ(b − A x) ≤ 0` where `x = 0`, and `w = 0` where `x > 0`. Each inner problem is solved by
/// [`least_squares`] on the passive columns.
///
/// ```
/// use nurbspring_linalg::{nonnegative_least_squares, DenseMatrix};
/// // Unconstrained solution would be (2, −1); the bound makes x₁ = 0.
/// let a = DenseMatrix::identity(2);
/// let x = nonnegative_least_squares(&a, &[2.0, -1.0]).unwrap();
/// assert_eq!(x, vec![2.0, 0.0]);
/// ```
pub fn nonnegative_least_squares(a: &DenseMatrix, b: &[f64]) -> Result<Vec<f64>, LinalgError> {
    check_system("nonnegative_least_squares", a, b)?;
    let (m, n) = (a.nrows(), a.ncols());
    let mut x = vec![0.0; n];
    if n == 0 {
        return Ok(x);
    }
    let norm1 = (0..n)
        .map(|j| (0..m).map(|i| a[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let tol = 10.0 * f64::EPSILON * norm1 * (m.max(n) as f64);
    let mut passive = vec![false; n];
    let gradient = |x: &[f64]| -> Vec<f64> {
        let mut r = b.to_vec();
        for i in 0..m {
            r[i] -= a.row(i).iter().zip(x).map(|(p, q)| p * q).sum::<f64>();
        }
        (0..n)
            .map(|j| (0..m).map(|i| a[(i, j)] * r[i]).sum())
            .collect()
    };
    let solve_passive = |passive: &[bool]| -> Result<Vec<f64>, LinalgError> {
        let cols: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
        let sub = DenseMatrix::from_fn(m, cols.len(), |i, k| a[(i, cols[k])]);
        let zp = least_squares(&sub, b)?;
        let mut z = vec![0.0; n];
        for (k, &j) in cols.iter().enumerate() {
            z[j] = zp[k];
        }
        Ok(z)
    };
    let max_outer = 3 * n + 10;
    let mut w = gradient(&x);
    for outer in 0.. {
        if outer >= max_outer {
            return Err(LinalgError::NoConvergence {
                what: "Lawson–Hanson NNLS",
                iterations: outer,
            });
        }
        let candidate = (0..n)
            .filter(|&j| !passive[j] && w[j] > tol)
            .max_by(|&p, &q| w[p].total_cmp(&w[q]));
        let Some(t) = candidate else { break };
        passive[t] = true;
        let mut inner = 0;
        loop {
            inner += 1;
            if inner > 3 * n + 10 {
                return Err(LinalgError::NoConvergence {
                    what: "Lawson–Hanson NNLS inner loop",
                    iterations: inner,
                });
            }
            let z = solve_passive(&passive)?;
            if (0..n).filter(|&j| passive[j]).all(|j| z[j] > 0.0) {
                x = z;
                break;
            }
            // Step from x towards z until the first passive variable hits zero.
            let mut alpha = f64::INFINITY;
            for j in 0..n {
                if passive[j] && z[j] <= 0.0 {
                    alpha = alpha.min(x[j] / (x[j] - z[j]));
                }
            }
            for j in 0..n {
                x[j] += alpha * (z[j] - x[j]);
            }
            for j in 0..n {
                if passive[j] && x[j] <= tol {
                    passive[j] = false;
                    x[j] = 0.0;
                }
            }
        }
        w = gradient(&x);
    }
    Ok(x)
}

/// All solutions of the underdetermined linear system `A x = b` as `x = g + N y`: `N`
/// (columns, orthonormal) spans the null space of A and `g` is the minimum-norm particular
/// solution, both from the full SVD `A = U Σ Vᵀ` (singular values `≤ tol·σ_max` count as zero;
/// `tol ≤ 0` means `max(rows, cols)·ε`). Used for linear constraints `p = G q + g` (docs/math.md §4).
/// Errors with [`LinalgError::Singular`] when the system is inconsistent: when the least
/// residual exceeds the round-off of the larger of `‖b‖`, `σ_max ‖g‖` and `σ_max · x_scale`
/// (`x_scale`: the size of the quantities `b` was computed from, e.g. coordinates moved to the
/// right-hand side, whose round-off can leave redundant rows slightly apart; 0 when none).
///
/// ```
/// use nurbspring_linalg::{affine_solution_space, DenseMatrix};
/// // x0 + x1 = 2 in R²: null space along (1, −1)/√2, minimum-norm solution (1, 1).
/// let a = DenseMatrix::from_row_major(1, 2, vec![1.0, 1.0]);
/// let (null, g) = affine_solution_space(&a, &[2.0], 0.0, 0.0).unwrap();
/// assert_eq!(null.ncols(), 1);
/// assert!((g[0] - 1.0).abs() < 1e-14 && (g[1] - 1.0).abs() < 1e-14);
/// assert!((null[(0, 0)] + null[(1, 0)]).abs() < 1e-14);
/// ```
pub fn affine_solution_space(
    a: &DenseMatrix,
    b: &[f64],
    tol: f64,
    x_scale: f64,
) -> Result<(DenseMatrix, Vec<f64>), LinalgError> {
    check_system("affine_solution_space", a, b)?;
    let (r, n) = (a.nrows(), a.ncols());
    if r == 0 || n == 0 {
        return Ok((DenseMatrix::identity(n), vec![0.0; n]));
    }
    let svd = dense_ref(a)
        .svd()
        .map_err(|e| LinalgError::Faer(format!("SVD in affine_solution_space: {e:?}")))?;
    let (u, v) = (svd.U(), svd.V());
    let s = svd.S().column_vector();
    let k = r.min(n);
    let smax = (0..k).fold(0.0_f64, |acc, i| acc.max(s[i]));
    let rel = if tol > 0.0 {
        tol
    } else {
        (r.max(n) as f64) * f64::EPSILON
    };
    let rank = (0..k).filter(|&i| s[i] > rel * smax).count();
    // g = V Σ⁺ Uᵀ b over the non-zero singular values (sorted descending by faer).
    let mut g = vec![0.0; n];
    for i in 0..rank {
        let c: f64 = (0..r).map(|row| u[(row, i)] * b[row]).sum::<f64>() / s[i];
        for j in 0..n {
            g[j] += c * v[(j, i)];
        }
    }
    let null = DenseMatrix::from_fn(n, n - rank, |i, j| v[(i, rank + j)]);
    let residual: Vec<f64> = a.mul_vec(&g).iter().zip(b).map(|(p, q)| p - q).collect();
    let scale = norm(b)
        .max(smax * norm(&g))
        .max(smax * x_scale)
        .max(f64::MIN_POSITIVE);
    if norm(&residual) > 1e3 * rel * scale {
        return Err(LinalgError::Singular {
            detail: format!(
                "the constraints A x = b are inconsistent: least residual {:.3e} (rank {rank} of {r} rows)",
                norm(&residual)
            ),
        });
    }
    Ok((null, g))
}
