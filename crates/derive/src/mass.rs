//! The mass choice of the paper's Section III: the non-null eigenvalues of the D-NURBS mass
//! matrix M are the candidate node masses.

use nurbspring_linalg::{DenseMatrix, SparseMatrix, symmetric_eigen};
use nurbspring_sim::PointDofs;

use crate::error::{DeriveError, Input};

/// Largest matrix (rows) whose eigenvalues are computed densely.
pub const MAX_DENSE_EIGEN: usize = 4000;

/// The distinct non-null eigenvalues of the symmetric matrix `m`, ascending.
///
/// Eigenvalues with `|λ| ≤ 1e-12 · max|λ|` are null (they occur only when weights are
/// unknowns, docs/math.md §7); values within a relative `1e-9` of each other are one. A
/// constant-weight D-NURBS mass matrix is `M = S ⊗ I₃` (docs/math.md §1), whose eigenvalues are
/// those of S, each three times: then S alone is decomposed (27× less work).
pub fn mass_eigenvalues(m: &SparseMatrix) -> Result<Vec<f64>, DeriveError> {
    let factor = PointDofs::XYZ.scalar_factor(m);
    let decomposed = factor.as_ref().unwrap_or(m);
    if !within_dense_solve(decomposed) {
        // A scan needs them; with the mass fixed they are only listed (see `mass_step`).
        return Err(DeriveError::InvalidInput {
            input: Input::Mass,
            value: "\"eigenvalue-scan\"".to_string(),
            reason: format!(
                "the mass matrix's eigenproblem has {} rows, more than the {MAX_DENSE_EIGEN} of a dense eigenvalue scan",
                decomposed.nrows()
            ),
        });
    }
    let dense: DenseMatrix = decomposed.to_dense();
    let eig = symmetric_eigen(&dense)?;
    Ok(distinct_non_null(&eig.values, 1e-12, 1e-9))
}

/// Whether [`mass_eigenvalues`] of `m` is within the dense solve's size.
pub fn mass_eigenvalues_computable(m: &SparseMatrix) -> bool {
    within_dense_solve(PointDofs::XYZ.scalar_factor(m).as_ref().unwrap_or(m))
}

/// The size rule of the dense eigenvalue solve, on the matrix actually decomposed.
fn within_dense_solve(decomposed: &SparseMatrix) -> bool {
    decomposed.nrows() <= MAX_DENSE_EIGEN
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
    fn kronecker_mass_matrices_have_the_eigenvalues_of_the_whole_matrix() {
        // A tridiagonal SPD S (eigenvalues 2 − 2cos(kπ/7) + 1, distinct) and M = S ⊗ I₃: the
        // scan through S must give the distinct eigenvalues of the whole 18 × 18 matrix.
        let n = 6;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 3.0));
            if i + 1 < n {
                t.push((i, i + 1, -1.0));
                t.push((i + 1, i, -1.0));
            }
        }
        let m = SparseMatrix::from_triplets(n, n, &t)
            .unwrap()
            .kron_identity(3);
        let whole = symmetric_eigen(&m.to_dense()).unwrap();
        let expected = distinct_non_null(&whole.values, 1e-12, 1e-9);
        let got = mass_eigenvalues(&m).unwrap();
        assert_eq!(got.len(), n);
        for (k, (g, e)) in got.iter().zip(&expected).enumerate() {
            let exact = 3.0 - 2.0 * ((k + 1) as f64 * std::f64::consts::PI / 7.0).cos();
            assert!(
                (g - e).abs() < 1e-13 && (g - exact).abs() < 1e-13,
                "{g} {e} {exact}"
            );
        }
    }

    #[test]
    fn a_net_beyond_the_dense_solve_is_refused_and_says_so() {
        // S ⊗ I₃ with 4001 rows of S: too large; 4000 rows (12000 of M) is not.
        let diagonal = |n: usize| SparseMatrix::from_diagonal(&vec![1.0; n]).kron_identity(3);
        assert!(mass_eigenvalues_computable(&diagonal(4000)));
        assert!(!mass_eigenvalues_computable(&diagonal(4001)));
        match mass_eigenvalues(&diagonal(4001)) {
            Err(DeriveError::InvalidInput { input, reason, .. }) => {
                assert_eq!(input, Input::Mass);
                assert!(reason.contains("4001 rows"), "{reason}");
            }
            other => panic!("{other:?}"),
        }
        // Without the Kronecker form the whole matrix counts.
        let mut t: Vec<(usize, usize, f64)> = (0..4002).map(|i| (i, i, 1.0)).collect();
        t.push((0, 1, 0.5));
        t.push((1, 0, 0.5));
        assert!(!mass_eigenvalues_computable(
            &SparseMatrix::from_triplets(4002, 4002, &t).unwrap()
        ));
    }

    #[test]
    fn merges_repeated_and_drops_null() {
        let v = distinct_non_null(&[3.0, 1e-20, 1.0, 1.0 + 1e-12, 2.0, 3.0], 1e-12, 1e-9);
        assert_eq!(v, vec![1.0, 2.0, 3.0]);
        // Null is relative to the largest |λ| (here 4000): 1e-9 is null, 1e-8 is not.
        let v = distinct_non_null(&[4e3, 1e-9, -1e-8, 2e3], 1e-12, 1e-9);
        assert_eq!(v, vec![-1e-8, 2e3, 4e3]);
    }
}
