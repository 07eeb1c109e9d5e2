//! Convergence against analytic solutions under h-refinement: a string's and a membrane's
//! eigenfrequencies (error O(h^{2p}) for degree p), and a clamped string's sag under gravity.

use std::f64::consts::PI;

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material, assemble_scalar,
    outer_ring_points,
};
use nurbspring_linalg::generalized_symmetric_eigen;

use crate::support::{self, tol};

/// Relative errors of ω_1 and ω_2 of a string (curve along x on [0, 1], α only, ends fixed):
/// `μ ẅ = α w_uu`, `ω_n = nπ √(α/μ)` (L = 1; every component obeys the same equation).
fn string_errors(p: usize, elements: usize) -> [f64; 2] {
    let (alpha, mu) = (2.0, 0.5);
    let model = DnurbsModel::new(
        Geometry::Curve(support::straight_curve(p, elements, 1.0)),
        Material {
            mu,
            alpha11: alpha,
            ..Material::default()
        },
        Loads::default(),
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions::default(),
    )
    .unwrap();
    let modes = model.modes(6).unwrap();
    // Each frequency appears three times (x, y, z).
    for n in 0..2 {
        let w = &modes.omega[3 * n..3 * n + 3];
        assert!((w[0] - w[2]).abs() <= 1e-9 * w[0], "{w:?}");
    }
    std::array::from_fn(|n| {
        let exact = (n + 1) as f64 * PI * (alpha / mu).sqrt();
        (modes.omega[3 * n] - exact) / exact
    })
}

#[test]
fn string_frequencies_converge_at_rate_2p() {
    // Grids fine enough to be in the asymptotic range (on 4-8-16 the cubic second mode still
    // converges at 6.6 and 6.3); errors stay far above round-off (1e-9 at 32 cubic elements).
    for (p, grids) in [(2, [8, 16, 32]), (3, [8, 16, 32])] {
        let errors: Vec<[f64; 2]> = grids.iter().map(|&n| string_errors(p, n)).collect();
        for mode in 0..2 {
            let e: Vec<f64> = errors.iter().map(|e| e[mode]).collect();
            // Galerkin eigenvalues approximate from above.
            assert!(
                e.iter().all(|&x| x > 0.0),
                "p = {p}, mode {}: {e:?}",
                mode + 1
            );
            let r = support::rate(e[1], e[2]);
            eprintln!(
                "string p = {p}, mode {}: relative errors {e:?}, rate {r:.3}",
                mode + 1
            );
            let expected = 2.0 * p as f64;
            assert!(
                (r - expected).abs() <= tol::RATE_SLACK,
                "p = {p}, mode {}: errors {e:?}, rate {r}",
                mode + 1
            );
        }
    }
}

/// Lowest distinct frequencies of a membrane `μ ẅ = α (w_xx + w_yy)` on the rectangle
/// `[0, a] × [0, b]` with fixed edges. D-NURBS derivatives are parametric, so the rectangle's
/// metric enters through `α11 = α/a²`, `α22 = α/b²` on the unit parameter square.
fn membrane_errors(p: usize, elements: usize) -> [f64; 3] {
    let (alpha, mu, a, b) = (1.5, 2.0, 1.5, 1.0);
    let patch = support::flat_patch(p, elements, elements, a, b);
    let (n_u, n_v) = (patch.n_u(), patch.n_v());
    let material = Material {
        mu,
        alpha11: alpha / (a * a),
        alpha22: alpha / (b * b),
        ..Material::default()
    };
    let s = assemble_scalar(
        &Geometry::Surface(patch),
        &material,
        &DnurbsOptions::default(),
    )
    .unwrap();
    let boundary = outer_ring_points(n_u, n_v, 1);
    let interior: Vec<usize> = (0..n_u * n_v).filter(|k| !boundary.contains(k)).collect();
    let eig = generalized_symmetric_eigen(
        &support::dense_sub(&s.stiffness, &interior),
        &support::dense_sub(&s.mass, &interior),
    )
    .unwrap();
    let c = PI * (alpha / mu).sqrt();
    let exact = [(1.0, 1.0), (2.0, 1.0), (1.0, 2.0)]
        .map(|(m, n): (f64, f64)| c * ((m / a).powi(2) + (n / b).powi(2)).sqrt());
    std::array::from_fn(|i| (eig.values[i].sqrt() - exact[i]) / exact[i])
}

#[test]
fn membrane_frequencies_converge_at_rate_2p() {
    let p = 2;
    let errors: Vec<[f64; 3]> = [4, 8, 16].iter().map(|&n| membrane_errors(p, n)).collect();
    for mode in 0..3 {
        let e: Vec<f64> = errors.iter().map(|e| e[mode]).collect();
        assert!(e.iter().all(|&x| x > 0.0), "mode {mode}: {e:?}");
        let r = support::rate(e[1], e[2]);
        eprintln!("membrane p = 2, mode {mode}: relative errors {e:?}, rate {r:.3}");
        assert!(
            (r - 4.0).abs() <= tol::RATE_SLACK,
            "mode {mode}: errors {e:?}, rate {r}"
        );
    }
}

/// Steady state (paper eq. (8)) of a string clamped at both ends under gravity:
/// `−α w'' = μ g` gives `w(x) = μ g x (L − x) / (2α)`, a parabola in the spline space for p ≥ 2,
/// so Galerkin reproduces it exactly.
#[test]
fn clamped_string_sags_into_the_parabola() {
    let (alpha, mu, g) = (2.0, 3.0, -9.81);
    for (p, elements) in [(2, 5), (3, 3), (4, 7)] {
        let model = DnurbsModel::new(
            Geometry::Curve(support::straight_curve(p, elements, 1.0)),
            Material {
                mu,
                alpha11: alpha,
                ..Material::default()
            },
            Loads {
                gravity: [0.0, 0.0, g],
                ..Loads::default()
            },
            &Constraints {
                fixed_rings: 1,
                ..Constraints::default()
            },
            DnurbsOptions::default(),
        )
        .unwrap();
        let p_ss = model.steady_state().unwrap();
        for i in 0..=20 {
            let x = i as f64 / 20.0;
            let c = model.point(x, 0.0, &p_ss).unwrap();
            let w = mu * g * x * (1.0 - x) / (2.0 * alpha);
            assert!(
                (c[0] - x).abs() <= tol::STEADY_STATE,
                "p = {p}: x({x}) = {}",
                c[0]
            );
            assert!(c[1].abs() <= tol::STEADY_STATE);
            assert!(
                (c[2] - w).abs() <= tol::STEADY_STATE,
                "p = {p}: z({x}) = {}, parabola {w}",
                c[2]
            );
        }
    }
}

/// A clamped membrane's sag is not polynomial; its centre deflection converges to the series
/// solution `w(½, ½) = (16 μ g / (α π⁴)) Σ_{m,n odd} (−1)^{(m+n)/2−1} / (m n (m² + n²))` on the
/// unit square.
#[test]
fn clamped_membrane_centre_deflection_converges() {
    let (alpha, mu, g) = (1.0, 1.0, -1.0);
    let mut series = 0.0;
    for m in (1..400).step_by(2) {
        for n in (1..400).step_by(2) {
            let sign = if ((m + n) / 2 - 1) % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            series += sign / ((m * n) as f64 * ((m * m + n * n) as f64));
        }
    }
    let exact = 16.0 * mu * g / (alpha * PI.powi(4)) * series;
    let errors: Vec<f64> = [4, 8, 16]
        .iter()
        .map(|&n| {
            let model = DnurbsModel::new(
                Geometry::Surface(support::flat_patch(2, n, n, 1.0, 1.0)),
                Material {
                    mu,
                    alpha11: alpha,
                    alpha22: alpha,
                    ..Material::default()
                },
                Loads {
                    gravity: [0.0, 0.0, g],
                    ..Loads::default()
                },
                &Constraints {
                    fixed_rings: 1,
                    ..Constraints::default()
                },
                DnurbsOptions::default(),
            )
            .unwrap();
            let p = model.steady_state().unwrap();
            (model.point(0.5, 0.5, &p).unwrap()[2] - exact).abs() / exact.abs()
        })
        .collect();
    eprintln!("membrane sag at the centre: relative errors {errors:?}");
    // Point values of quadratic splines converge at O(h^{p+1}) = O(h³) or better (O(h⁴) is
    // observed at the symmetric centre).
    assert!(
        support::rate(errors[1], errors[2]) >= 3.0 - tol::RATE_SLACK,
        "{errors:?}"
    );
    assert!(errors[2] < tol::MEMBRANE_SAG, "{errors:?}");
}

/// Above `DENSE_MODES_LIMIT` free dofs the modes come from sparse shift-invert Lanczos, which
/// must find every copy of the threefold frequencies of `S ⊗ I_3`.
#[test]
fn sparse_modes_above_the_dense_limit() {
    let (alpha, mu) = (2.0, 0.5);
    let elements = 700;
    let model = DnurbsModel::new(
        Geometry::Curve(support::straight_curve(2, elements, 1.0)),
        Material {
            mu,
            alpha11: alpha,
            ..Material::default()
        },
        Loads::default(),
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions::default(),
    )
    .unwrap();
    assert!(model.n_free() > nurbspring_dnurbs::DENSE_MODES_LIMIT);
    let modes = model.modes(6).unwrap();
    assert_eq!(modes.omega.len(), 6);
    for (i, w) in modes.omega.iter().enumerate() {
        let exact = (i / 3 + 1) as f64 * PI * (alpha / mu).sqrt();
        assert!(
            (w - exact).abs() <= tol::SPARSE_EIGEN * exact,
            "ω_{i} = {w}, exact {exact}"
        );
    }
}

/// A free-free string above the dense limit: the three rigid translations (ω = 0) make K
/// singular, which the negative shift of the sparse solver must absorb; then the free-free
/// string's `ω_1 = π √(α/μ)` (Neumann ends, `cos(π u)`) three times.
#[test]
fn sparse_modes_of_a_free_floating_string() {
    let (alpha, mu) = (2.0, 0.5);
    let model = DnurbsModel::new(
        Geometry::Curve(support::straight_curve(2, 700, 1.0)),
        Material {
            mu,
            alpha11: alpha,
            ..Material::default()
        },
        Loads::default(),
        &Constraints::default(),
        DnurbsOptions::default(),
    )
    .unwrap();
    assert!(model.n_free() > nurbspring_dnurbs::DENSE_MODES_LIMIT);
    let modes = model.modes(6).unwrap();
    assert_eq!(modes.omega.len(), 6);
    let omega_1 = PI * (alpha / mu).sqrt();
    for (i, w) in modes.omega.iter().enumerate() {
        if i < 3 {
            // ω² of a rigid translation is 0 up to the solver's tolerance relative to ω_1².
            assert!(
                w * w <= tol::SPARSE_EIGEN * omega_1 * omega_1,
                "ω_{i} = {w}"
            );
        } else {
            assert!(
                (w - omega_1).abs() <= tol::SPARSE_EIGEN * omega_1,
                "ω_{i} = {w}, exact {omega_1}"
            );
        }
    }
}
