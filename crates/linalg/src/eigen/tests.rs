//! Unit tests of `eigen`.

use super::*;

#[test]
fn tridiagonal_ql_matches_laplacian_spectrum() {
    let n = 40;
    let (mut vals, z) = tridiagonal_eigen(&vec![2.0; n], &vec![-1.0; n - 1], &[n - 1]).unwrap();
    // last components of normalized eigenvectors square-sum to 1
    let s: f64 = z[0].iter().map(|v| v * v).sum();
    assert!((s - 1.0).abs() < 1e-12);
    vals.sort_by(f64::total_cmp);
    for (j, v) in vals.iter().enumerate() {
        let exact = 2.0 - 2.0 * (((j + 1) as f64) * std::f64::consts::PI / (n + 1) as f64).cos();
        assert!((v - exact).abs() < 1e-13, "{j}: {v} vs {exact}");
    }
}

/// Random symmetric tridiagonals (unequal diagonals, so the shifts and the Gershgorin
/// interval matter; some zero couplings, so the matrix splits): the QL iteration's
/// eigenvalues and eigenvector rows and the bisection's k-th eigenvalue against faer's
/// dense decomposition of the same matrix, to the round-off of the spectrum's scale
/// (measured 1.4e-15 of it on the eigenvalues and 3.3e-15 on the eigenvector rows, whose
/// eigenvalue gaps are at least 8.6e-4 of the scale; checked at 1e-14 and 1e-12).
#[test]
fn tridiagonal_ql_and_bisection_match_the_dense_decomposition() {
    let mut rng = SplitMix64(7);
    for (case, n) in [1usize, 2, 3, 5, 8, 17, 40, 41].into_iter().enumerate() {
        let d: Vec<f64> = (0..n).map(|_| 3.0 * rng.next_f64()).collect();
        let e: Vec<f64> = (0..n.saturating_sub(1))
            .map(|i| {
                if (i + case) % 7 == 3 {
                    0.0
                } else {
                    2.0 * rng.next_f64()
                }
            })
            .collect();
        let t = DenseMatrix::from_fn(n, n, |i, j| match (i, j) {
            _ if i == j => d[i],
            _ if j == i + 1 => e[i],
            _ if i == j + 1 => e[j],
            _ => 0.0,
        });
        let dense = symmetric_eigen(&t).unwrap();
        let scale = dense.values.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let rows: Vec<usize> = [0, n / 2, n - 1].into_iter().collect();
        let (vals, z) = tridiagonal_eigen(&d, &e, &rows).unwrap();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        let sorted: Vec<f64> = order.iter().map(|&i| vals[i]).collect();
        for k in 0..n {
            let exact = dense.values[k];
            assert!(
                (sorted[k] - exact).abs() < 1e-14 * scale,
                "n {n}, λ_{k}: QL {}, dense {exact}",
                sorted[k]
            );
            let b = tridiagonal_eigenvalue(&d, &e, k);
            assert!(
                (b - exact).abs() < 1e-14 * scale,
                "n {n}, λ_{k}: bisection {b}, dense {exact}"
            );
            // Eigenvector rows, where the eigenvalue is simple (up to sign).
            let gap = (0..n)
                .filter(|&j| j != k)
                .map(|j| (dense.values[j] - exact).abs())
                .fold(f64::INFINITY, f64::min);
            if gap > 1e-6 * scale {
                for (r, &row) in rows.iter().enumerate() {
                    let (ql, dn) = (z[r][order[k]].abs(), dense.vectors[(row, k)].abs());
                    assert!(
                        (ql - dn).abs() < 1e-12,
                        "n {n}, φ_{k}[{row}]: QL {ql}, dense {dn}"
                    );
                }
            }
        }
    }
}

#[test]
fn largest_eigenvalue_with_huge_masses_is_an_error_or_a_number_never_a_panic() {
    // A spring chain with masses of 1e308: M⁻¹K underflows to (nearly) zero.
    let n = 5;
    let k = SparseMatrix::from_dense(
        &DenseMatrix::from_fn(n, n, |i, j| match i.abs_diff(j) {
            0 => 2.0,
            1 => -1.0,
            _ => 0.0,
        }),
        0.0,
    );
    for mass in [1e300, 1e308, f64::MAX] {
        let m = SparseMatrix::from_diagonal(&vec![mass; n]);
        match largest_generalized_eigenvalue(&k, &m, 1e-12) {
            Ok(l) => assert!(l.is_finite() && l >= 0.0 && l <= 4.0 / mass * 1.0001, "{l}"),
            Err(e) => assert!(e.to_string().contains("underflow"), "{e}"),
        }
    }
}
