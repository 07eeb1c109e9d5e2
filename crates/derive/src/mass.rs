//! The mass choice of the paper's Section III: the non-null eigenvalues of the D-NURBS mass
//! matrix M are the candidate node masses.

use nurbspring_linalg::{DenseMatrix, SparseMatrix, symmetric_eigen};

use crate::DeriveError;

/// Largest matrix (rows) whose eigenvalues are computed densely.
pub const MAX_DENSE_EIGEN: usize = 4000;

/// The distinct non-null eigenvalues of the symmetric matrix `m`, ascending.
///
/// Eigenvalues with `|λ| ≤ 1e-12 · max|λ|` are null (they occur only when weights are
/// unknowns, docs/math.md §7); values within a relative `1e-9` of each other are one (M = S ⊗ I₃
/// repeats every eigenvalue of S three times).
pub fn mass_eigenvalues(m: &SparseMatrix) -> Result<Vec<f64>, DeriveError> {
    if m.nrows() > MAX_DENSE_EIGEN {
        return Err(DeriveError::InvalidOption {
            name: "fit.mass",
            value: "\"eigenvalue-scan\"".to_string(),
            reason: format!(
                "the mass matrix has {} rows, more than the {MAX_DENSE_EIGEN} of a dense eigenvalue scan",
                m.nrows()
            ),
        });
    }
    let dense: DenseMatrix = m.to_dense();
    let eig = symmetric_eigen(&dense)?;
    Ok(distinct_non_null(&eig.values, 1e-12, 1e-9))
}

/// Drops null values (`|λ| ≤ null_tol · max|λ|`) and merges values within a relative
/// `merge_tol`; returns them ascending.
pub fn distinct_non_null(values: &[f64], null_tol: f64, merge_tol: f64) -> Vec<f64> {
    let scale = values.iter().map(|x| x.abs()).fold(0.0, f64::max);
    let mut v: Vec<f64> = values
        .iter()
        .copied()
        .filter(|x| x.abs() > null_tol * scale)
        .collect();
    v.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::with_capacity(v.len());
    for x in v {
        match out.last() {
            Some(&last) if (x - last).abs() <= merge_tol * x.abs().max(last.abs()) => {}
            _ => out.push(x),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_repeated_and_drops_null() {
        let v = distinct_non_null(&[3.0, 1e-20, 1.0, 1.0 + 1e-12, 2.0, 3.0], 1e-12, 1e-9);
        assert_eq!(v, vec![1.0, 2.0, 3.0]);
    }
}
