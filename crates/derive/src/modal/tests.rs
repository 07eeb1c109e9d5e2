//! Unit tests of `modal`.

use super::*;

/// `k · tridiag(−1, 2, −1)` of a chain of `n` nodes between two fixed ends.
pub(crate) fn chain(n: usize, k: f64) -> SparseMatrix {
    let mut t = Vec::new();
    for i in 0..n {
        t.push((i, i, 2.0 * k));
        if i + 1 < n {
            t.push((i, i + 1, -k));
            t.push((i + 1, i, -k));
        }
    }
    SparseMatrix::from_triplets(n, n, &t).unwrap()
}

/// Without stiffness the lowest frequency is 0 (no shift of 0 is tried on a zero matrix).
#[test]
fn no_stiffness_has_a_zero_lowest_frequency() {
    let l = SparseMatrix::from_triplets(3, 3, &[(0, 0, 0.0), (1, 1, 0.0), (2, 2, 0.0)]).unwrap();
    assert_eq!(lowest_frequency(&l, &[1.0, 2.0, 3.0]).unwrap(), 0.0);
}

/// The fixed-fixed chain's lowest frequency `2 √(k/m) sin(π / (2(n + 1)))` at stiffness
/// scales from 1e-10 to 1e10: the shift of the shift-invert solve must follow the scale of
/// `L` (a fixed shift of −1 cannot resolve eigenvalues of 1e-10 against 1). The chain is
/// long enough that the Krylov space does not cover it.
#[test]
fn the_lowest_frequency_of_a_chain_at_every_scale() {
    let n = 300;
    for k in [1e-10, 1.0, 1e10] {
        for m in [1e-3, 1.0] {
            let w = lowest_frequency(&chain(n, k), &vec![m; n]).unwrap();
            let exact =
                2.0 * (k / m).sqrt() * (std::f64::consts::PI / (2.0 * (n + 1) as f64)).sin();
            assert!(
                (w - exact).abs() < 1e-12 * exact,
                "k {k}, m {m}: {w} vs {exact}"
            );
        }
    }
}

/// The reduced solve (masses eliminated by Woodbury and a Schur complement, the factors by
/// non-negative least squares) against the optimality conditions of the dense problem
/// (H assembled from its blocks): the gradient `Hz − g` vanishes on every positive factor
/// and every mass above the floor, is ≥ 0 on a factor at 0; a mass pulled below the floor
/// is held at it.
#[test]
fn the_reduced_solve_against_a_dense_one() {
    let mut seed = 11u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let (c, n, rows) = (3, 5, 2);
    let a = DenseMatrix::from_fn(7, c + n, |_, _| rnd());
    let gram = a.transpose().matmul(&a);
    let hkk = DenseMatrix::from_fn(c, c, |i, j| gram[(i, j)] + if i == j { 0.5 } else { 0.0 });
    let hkm = DenseMatrix::from_fn(c, n, |i, j| 0.3 * gram[(i, c + j)]);
    let d: Vec<f64> = (0..n).map(|_| 2.0 + rnd()).collect();
    let s = DenseMatrix::from_fn(rows, n, |_, _| rnd());
    let dense = |gm: &[f64], gk: &[f64]| {
        let t = c + n;
        let h = DenseMatrix::from_fn(t, t, |i, j| match (i < c, j < c) {
            (true, true) => hkk[(i, j)],
            (true, false) => hkm[(i, j - c)],
            (false, true) => hkm[(j, i - c)],
            (false, false) => {
                let (p, q) = (i - c, j - c);
                (0..rows).map(|r| s[(r, p)] * s[(r, q)]).sum::<f64>()
                    + if p == q { d[p] } else { 0.0 }
            }
        });
        let g: Vec<f64> = gk.iter().chain(gm).copied().collect();
        (h, g)
    };
    for trial in 0..20 {
        let gk: Vec<f64> = (0..c).map(|_| rnd()).collect();
        let gm: Vec<f64> = (0..n).map(|_| 3.0 + rnd()).collect();
        let (h, g) = dense(&gm, &gk);
        let (y, x) = solve_with_floor(&hkk, &hkm, &d, &s, &gk, &gm).unwrap();
        let z: Vec<f64> = y.iter().chain(&x).copied().collect();
        let hz = h.mul_vec(&z);
        let floored: Vec<bool> = (0..n).map(|p| x[p] == MASS_FLOOR).collect();
        for j in 0..c + n {
            let grad = hz[j] - g[j];
            if j < c && y[j] == 0.0 {
                assert!(
                    grad >= -1e-10,
                    "{trial}: factor {j} at 0 with gradient {grad}"
                );
            } else if j >= c && floored[j - c] {
                assert!(x[j - c] == MASS_FLOOR);
            } else {
                assert!(grad.abs() < 1e-10, "{trial}: unknown {j} gradient {grad}");
            }
        }
        assert!(y.iter().all(|&v| v >= 0.0) && x.iter().all(|&v| v >= MASS_FLOOR));
    }
    // A right-hand side that pulls mass 0 below the floor.
    let gk = vec![0.1; c];
    let mut gm = vec![3.0; n];
    gm[0] = -50.0;
    let (_, x) = solve_with_floor(&hkk, &hkm, &d, &s, &gk, &gm).unwrap();
    assert_eq!(x[0], MASS_FLOOR);
}

/// Bands by hand on 10 lines: the first three from each edge by their distance, the
/// rest inside; an element is banded by its line nearest an edge, the low edge first.
#[test]
fn bands_of_elements() {
    assert_eq!(Band::of(0, 1, 10), Band::Low(0));
    assert_eq!(Band::of(2, 4, 10), Band::Low(2));
    assert_eq!(Band::of(3, 5, 10), Band::Inside);
    assert_eq!(Band::of(5, 7, 10), Band::High(2));
    assert_eq!(Band::of(8, 9, 10), Band::High(0));
    // On a short lattice the low edge wins.
    assert_eq!(Band::of(2, 3, 4), Band::Low(2));
    let g = FitGroup {
        kind: LinearKind::BendU,
        u: Band::Low(1),
        v: Band::High(0),
    };
    assert_eq!(g.name(), "bend_u[u1,v-0]");
}

/// Half-waves of separable shapes `sin(a π i/(N+1)) sin(b π j/(N+1))` on a 9 × 7 grid whose
/// outer ring is fixed; and the selection: `K = max(⌈(N+1)/2⌉, min(N, 3))` per direction,
/// the count capped at `K_u K_v`, a repeated frequency taken whole or not at all.
#[test]
fn half_waves_and_resolved_modes() {
    let (n_u, n_v) = (9, 7);
    let free: Vec<usize> = (0..n_u * n_v)
        .filter(|a| {
            let (i, j) = (a / n_v, a % n_v);
            i > 0 && j > 0 && i + 1 < n_u && j + 1 < n_v
        })
        .collect();
    let shape = |a: usize, b: usize| -> Vec<f64> {
        free.iter()
            .map(|&x| {
                let (i, j) = ((x / n_v) as f64, (x % n_v) as f64);
                (a as f64 * std::f64::consts::PI * i / (n_u - 1) as f64).sin()
                    * (b as f64 * std::f64::consts::PI * j / (n_v - 1) as f64).sin()
            })
            .collect()
    };
    let mut position = vec![usize::MAX; n_u * n_v];
    for (p, &a) in free.iter().enumerate() {
        position[a] = p;
    }
    for (a, b) in [(1, 1), (3, 2), (5, 4), (7, 1)] {
        assert_eq!(
            half_waves((n_u, n_v), &position, &shape(a, b)),
            [a, b],
            "{a}, {b}"
        );
    }
    // 7 free lines along u: K_u = 4; 5 along v: K_v = 3; at most 12 modes. Frequencies
    // `√(a² + 1.7 b²)`, none repeated.
    let mut modes = Vec::new();
    for a in 1..=7 {
        for b in 1..=5 {
            modes.push((((a * a) as f64 + 1.7 * (b * b) as f64).sqrt(), a, b));
        }
    }
    modes.sort_by(|x, y| x.0.total_cmp(&y.0));
    let sampled: Vec<SampledMode> = modes
        .iter()
        .map(|&(w, a, b)| SampledMode {
            omega: w,
            shape: shape(a, b),
        })
        .collect();
    let (picked, k) = resolved_modes((n_u, n_v), &free, &sampled);
    assert_eq!(k, [4, 3]);
    let labels: Vec<(usize, usize)> = picked.iter().map(|&i| (modes[i].1, modes[i].2)).collect();
    assert!(labels.iter().all(|&(a, b)| a <= 4 && b <= 3), "{labels:?}");
    // (1,1) … (4,3): 12 modes.
    assert_eq!(labels.len(), 12, "{labels:?}");
    for w in picked.windows(2) {
        assert!(w[0] < w[1]);
    }
    // A repeated frequency with a member beyond K is left out whole: (1,2) paired with a
    // copy of (5,1) at its frequency.
    let mut paired = sampled.clone();
    let at = modes.iter().position(|m| (m.1, m.2) == (1, 2)).unwrap();
    paired.insert(
        at + 1,
        SampledMode {
            omega: paired[at].omega,
            shape: shape(5, 1),
        },
    );
    let (picked, _) = resolved_modes((n_u, n_v), &free, &paired);
    assert!(
        !picked.contains(&at) && !picked.contains(&(at + 1)),
        "{picked:?}"
    );
}
