//! The truncated modal basis of a large system (lowest modes by shift-invert Lanczos) against
//! the complete dense one on a system small enough for both: the same lowest modes and highest
//! frequency, a response that is exactly the lowest modes' plus the static correction of the
//! rest, the share left out equal to the tail of the dense modal amplitudes, and an
//! equilibrium that stays put.

use nurbspring_derive::{EnergyOrigin, ModalBasis, ScalarSystem};
use nurbspring_linalg::{SparseMatrix, SpdSolver};

/// Lanczos converges each pair to a residual of 1e-12 relative (linalg); measured here: the
/// eigenvalues to 7e-14 relative, the responses to 3e-13.
const LANCZOS: f64 = 1e-12;

/// The membrane of [`membrane`] with its border free (natural boundary): K singular, one
/// rigid mode (the translation).
fn free_membrane(nx: usize, ny: usize) -> (SparseMatrix, SparseMatrix) {
    let (k, m) = membrane(nx, ny);
    // Each diagonal entry becomes the sum of its row's couplings.
    let mut row_sum = vec![0.0; k.nrows()];
    for (i, j, v) in k.triplets() {
        if i != j {
            row_sum[i] -= v;
        }
    }
    let t: Vec<(usize, usize, f64)> = k
        .triplets()
        .map(|(i, j, v)| {
            if i == j {
                (i, j, row_sum[i])
            } else {
                (i, j, v)
            }
        })
        .collect();
    (
        SparseMatrix::from_triplets(k.nrows(), k.ncols(), &t).unwrap(),
        m,
    )
}

/// A membrane on an `nx × ny` grid fixed at its border: the 5-point Laplacian (unequal
/// spacings) as K, and a consistent-like mass with unequal diagonal and neighbour couplings
/// (diagonally dominant, so SPD) as M: simple eigenvalues, a non-diagonal M-inner product.
fn membrane(nx: usize, ny: usize) -> (SparseMatrix, SparseMatrix) {
    let n = nx * ny;
    let id = |i: usize, j: usize| i * ny + j;
    let (kx, ky) = (1.0, 1.7);
    let (mut k, mut m) = (Vec::new(), Vec::new());
    for i in 0..nx {
        for j in 0..ny {
            let a = id(i, j);
            k.push((a, a, 2.0 * kx + 2.0 * ky));
            m.push((a, a, 1.0 + 0.37 * ((i * 3 + j * 5) % 7) as f64 / 7.0));
            for (b, w) in [
                (i + 1 < nx).then(|| (id(i + 1, j), kx)),
                (j + 1 < ny).then(|| (id(i, j + 1), ky)),
            ]
            .into_iter()
            .flatten()
            {
                k.extend([(a, b, -w), (b, a, -w)]);
                m.extend([(a, b, 0.05), (b, a, 0.05)]);
            }
        }
    }
    (
        SparseMatrix::from_triplets(n, n, &k).unwrap(),
        SparseMatrix::from_triplets(n, n, &m).unwrap(),
    )
}

/// Initial state and load of every unknown: smooth and rough parts, all three coordinates.
fn excitation(n: usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let f = |a: usize, s: f64| ((a as f64 * s).sin() + 0.1 * ((a * a) % 11) as f64) * 0.3;
    (
        (0..n).map(|a| [f(a, 0.1), 0.0, -f(a, 0.05)]).collect(),
        (0..n).map(|a| [0.2, f(a, 0.7), 1.0]).collect(),
        (0..n).map(|a| [0.4, -0.5, f(a, 0.2) - 1.0]).collect(),
    )
}

fn scalar_column(x: &[[f64; 3]], c: usize) -> Vec<f64> {
    x.iter().map(|p| p[c]).collect()
}

/// `K⁻¹ f` per coordinate.
fn static_displacement(k: &SparseMatrix, f: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let solver = SpdSolver::new(k).unwrap();
    let cols: Vec<Vec<f64>> = (0..3).map(|c| solver.solve(&scalar_column(f, c))).collect();
    (0..f.len())
        .map(|a| [cols[0][a], cols[1][a], cols[2][a]])
        .collect()
}

/// `yᵀ M x` for the scalar vectors.
fn m_dot(m: &SparseMatrix, y: &[f64], x: &[f64]) -> f64 {
    let mut mx = vec![0.0; x.len()];
    m.mul_vec(x, &mut mx);
    y.iter().zip(&mx).map(|(a, b)| a * b).sum()
}

#[test]
fn the_lowest_modes_and_the_highest_frequency_are_the_dense_ones() {
    let (k, m) = membrane(23, 17);
    let all = ModalBasis::all(&k, &m).unwrap();
    let low = ModalBasis::lowest(&k, &m, 30).unwrap();
    assert!(all.is_complete() && !low.is_complete());
    assert_eq!((low.len(), low.unknowns()), (30, 391));
    for i in 0..30 {
        assert!(
            (low.lambda[i] - all.lambda[i]).abs() <= LANCZOS * all.lambda[i],
            "mode {i}: {} vs {}",
            low.lambda[i],
            all.lambda[i]
        );
        // Simple eigenvalues: the same vector up to sign.
        let overlap = m_dot(&m, &low.mode(i), &all.mode(i)).abs();
        assert!((overlap - 1.0).abs() < LANCZOS, "mode {i}: {overlap}");
    }
    let (top, top_all) = (low.omega_max().unwrap(), all.omega_max().unwrap());
    assert!(
        (top - top_all).abs() <= LANCZOS * top_all,
        "{top} vs {top_all}"
    );
    assert_eq!(top_all, *all.omega.last().unwrap());
    // Asking for every mode is the dense basis.
    assert!(ModalBasis::lowest(&k, &m, 391).unwrap().is_complete());
}

/// The truncated response at a watched point is `Σ_{i<r} w·φ_i η_i(t) + w·c` with `η_i` the
/// closed-form modal coordinates from the dense basis and `c = (I − Φ_rΦ_rᵀM) K⁻¹ f`; its
/// energies are those of that field.
#[test]
fn the_truncated_response_is_the_lowest_modes_plus_the_static_correction() {
    let (k, m) = membrane(19, 13);
    let n = k.nrows();
    let r = 25;
    let all = ModalBasis::all(&k, &m).unwrap();
    let low = ModalBasis::lowest(&k, &m, r).unwrap();
    let (u0, v0, f) = excitation(n);
    let origin = EnergyOrigin::of_load(&f, &u0);
    let system = ScalarSystem {
        free: (0..n).collect(),
        mass: m.clone(),
        stiffness: k.clone(),
        damping_ratio: 0.0,
        load: f.clone(),
        displacement: u0.clone(),
        velocity: v0.clone(),
        energy: origin.clone(),
    };
    let watch = vec![vec![(n / 2, 1.0)], vec![(7, 0.25), (n - 20, 0.75)]];
    let times = [0.0, 0.3, 1.7, 6.1, 25.0];
    let (points, energies) = low.response(&watch, &times, &u0, &v0, &f, Some(&origin));
    // The field by hand from the dense basis (its lowest r modes, signs taken from it).
    let us = static_displacement(&k, &f);
    let modes: Vec<Vec<f64>> = (0..r).map(|i| all.mode(i)).collect();
    let mut correction = us.clone();
    for phi in &modes {
        for c in 0..3 {
            let a = m_dot(&m, phi, &scalar_column(&us, c));
            for (x, p) in correction.iter_mut().zip(phi) {
                x[c] -= a * p;
            }
        }
    }
    for (s, &t) in times.iter().enumerate() {
        let mut u = correction.clone();
        let mut v = vec![[0.0; 3]; n];
        for (i, phi) in modes.iter().enumerate() {
            let (w, l) = (all.omega[i], all.lambda[i]);
            for c in 0..3 {
                let e0 = m_dot(&m, phi, &scalar_column(&u0, c));
                let e1 = m_dot(&m, phi, &scalar_column(&v0, c));
                let g: f64 = phi.iter().zip(&f).map(|(p, q)| p * q[c]).sum();
                let eta = (e0 - g / l) * (w * t).cos() + e1 / w * (w * t).sin() + g / l;
                let rate = -(e0 - g / l) * w * (w * t).sin() + e1 * (w * t).cos();
                for a in 0..n {
                    u[a][c] += eta * phi[a];
                    v[a][c] += rate * phi[a];
                }
            }
        }
        for (p, weights) in watch.iter().enumerate() {
            for c in 0..3 {
                let expected: f64 = weights.iter().map(|&(a, w)| w * u[a][c]).sum();
                assert!(
                    (points[p][s][c] - expected).abs() < LANCZOS,
                    "t = {t}, point {p}, coordinate {c}: {} vs {expected}",
                    points[p][s][c]
                );
            }
        }
        let expected = system.energies(&u, &v);
        let scale = expected[0] + expected[1].abs() + expected[2].abs();
        for (got, want) in energies[s].iter().zip(expected) {
            assert!(
                (got - want).abs() < LANCZOS * scale,
                "t = {t}: {:?} vs {expected:?}",
                energies[s]
            );
        }
    }
}

/// The share left out is `√(Σ_{i≥r} a_i² / Σ_i a_i²)` of the dense basis's modal amplitudes
/// `a_i² = Σ_x (φ_iᵀM(u₀ − K⁻¹f))² + (φ_iᵀMv₀/ω_i)²`; zero for the complete basis.
#[test]
fn the_share_left_out_is_the_tail_of_the_dense_amplitudes() {
    let (k, m) = membrane(21, 15);
    let n = k.nrows();
    let all = ModalBasis::all(&k, &m).unwrap();
    let (u0, v0, f) = excitation(n);
    let us = static_displacement(&k, &f);
    let amplitude2: Vec<f64> = (0..n)
        .map(|i| {
            let phi = all.mode(i);
            (0..3)
                .map(|c| {
                    let w: Vec<f64> = u0.iter().zip(&us).map(|(a, b)| a[c] - b[c]).collect();
                    m_dot(&m, &phi, &w).powi(2)
                        + m_dot(&m, &phi, &scalar_column(&v0, c)).powi(2) / all.lambda[i]
                })
                .sum()
        })
        .collect();
    let total: f64 = amplitude2.iter().sum();
    assert_eq!(all.left_out(&u0, &v0, &f), Some(0.0));
    for r in [5, 40, 120] {
        let low = ModalBasis::lowest(&k, &m, r).unwrap();
        let expected = (amplitude2[r..].iter().sum::<f64>() / total).sqrt();
        let got = low.left_out(&u0, &v0, &f).unwrap();
        assert!(
            (got - expected).abs() < LANCZOS,
            "r = {r}: {got} vs {expected}"
        );
        assert!(
            expected > 1e-4,
            "r = {r}: the test needs a tail ({expected})"
        );
    }
}

/// From the static equilibrium `u₀ = K⁻¹f` at rest nothing moves, however few modes are kept:
/// the kept modes' part is at its own equilibrium and the static correction holds the rest.
#[test]
fn a_truncated_basis_keeps_the_static_equilibrium() {
    let (k, m) = membrane(17, 11);
    let n = k.nrows();
    let (_, _, f) = excitation(n);
    let us = static_displacement(&k, &f);
    let low = ModalBasis::lowest(&k, &m, 6).unwrap();
    let watch: Vec<Vec<(usize, f64)>> = [3, n / 3, n - 4].iter().map(|&a| vec![(a, 1.0)]).collect();
    let times = [0.0, 1.0, 10.0];
    let (points, _) = low.response(&watch, &times, &us, &vec![[0.0; 3]; n], &f, None);
    let scale = us.iter().flatten().fold(0.0_f64, |a, x| a.max(x.abs()));
    for (p, w) in watch.iter().enumerate() {
        for s in 0..times.len() {
            for c in 0..3 {
                assert!(
                    (points[p][s][c] - us[w[0].0][c]).abs() < LANCZOS * scale,
                    "point {p} at {}: {:?} vs {:?}",
                    times[s],
                    points[p][s],
                    us[w[0].0]
                );
            }
        }
    }
    assert!(low.left_out(&us, &vec![[0.0; 3]; n], &f).is_none());
}

/// A free membrane (K singular): the truncated basis finds the rigid mode (the shift lies below
/// zero) and gives it exactly zero frequency, as the dense basis does, with the same elastic
/// modes; a uniform translation under a uniform acceleration moves freely
/// (`u₀ + v₀t + ½gt²` at every point), and the share left out and the static correction (K⁻¹)
/// are not attempted.
#[test]
fn a_truncated_basis_of_a_free_membrane_keeps_its_rigid_mode() {
    let (k, m) = free_membrane(16, 13);
    let n = k.nrows();
    let all = ModalBasis::all(&k, &m).unwrap();
    let low = ModalBasis::lowest(&k, &m, 12).unwrap();
    assert_eq!((all.lambda[0], low.lambda[0]), (0.0, 0.0));
    assert_eq!(low.omega[0], 0.0);
    for i in 1..12 {
        assert!(low.lambda[i] > 0.0);
        assert!(
            (low.lambda[i] - all.lambda[i]).abs() <= LANCZOS * all.lambda[i],
            "mode {i}: {} vs {}",
            low.lambda[i],
            all.lambda[i]
        );
    }
    let (u0, v0, f) = excitation(n);
    assert!(low.left_out(&u0, &v0, &f).is_none());
    // A uniform translation under a uniform load: the rigid mode alone, x = x₀ + v t + ½ a t²
    // with a = f / (mass per unit translation) the same at every point.
    let u0 = vec![[0.1, -0.2, 0.3]; n];
    let v0 = vec![[0.5, 0.0, -1.0]; n];
    let mut ones = vec![0.0; n];
    m.mul_vec(&vec![1.0; n], &mut ones);
    // f = M·1 · g: a uniform acceleration g in every coordinate.
    let g = [0.0, -2.0, 0.7];
    let f: Vec<[f64; 3]> = ones
        .iter()
        .map(|&w| [w * g[0], w * g[1], w * g[2]])
        .collect();
    let watch = vec![vec![(0, 1.0)], vec![(n / 2, 1.0)]];
    let times = [0.0, 0.5, 1.0, 2.5];
    let (points, _) = low.response(&watch, &times, &u0, &v0, &f, None);
    for p in 0..watch.len() {
        for (s, &t) in times.iter().enumerate() {
            for c in 0..3 {
                let expected = u0[0][c] + v0[0][c] * t + 0.5 * g[c] * t * t;
                assert!(
                    (points[p][s][c] - expected).abs() < LANCZOS,
                    "point {p} at {t}: {:?}",
                    points[p][s]
                );
            }
        }
    }
}
