//! The stiffness fit on problems whose answer is known.

use nurbspring_derive::{DeriveError, Omega, StiffnessFit};
use nurbspring_dnurbs::Geometry;
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{Class, Constants, LatticeOptions, ParameterGrid, SpringKind, SpringLattice};

/// The paper's surface (docs/math.md §7), slightly curved so that every class has out-of-plane terms.
fn surface(curved: bool) -> NurbsSurface {
    let (ku, kv) = paper_knots();
    let px = [0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.];
    let py = [0., 0.83, 2.5, 4.16, 5.];
    let mut pts = Vec::new();
    for (i, &x) in px.iter().enumerate() {
        for (j, &y) in py.iter().enumerate() {
            let z = if curved {
                2.0 + 0.1 * (i as f64) * (j as f64)
            } else {
                2.0
            };
            pts.push([x, y, z]);
        }
    }
    NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap()
}

fn paper_knots() -> (KnotVector, KnotVector) {
    (
        KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap(),
        KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap(),
    )
}

fn lattice(s: &NurbsSurface, bending: bool, k: [f64; 3], grid: ParameterGrid) -> SpringLattice {
    let options = LatticeOptions {
        grid,
        constants: Constants::from_pairs(
            [
                (SpringKind::Structural, k[0]),
                (SpringKind::Shear, k[1]),
                (SpringKind::Bend, k[2]),
            ]
            .into_iter()
            .filter(|&(kind, _)| bending || kind != SpringKind::Bend)
            .map(|(kind, k)| (Class::Spring(kind), k)),
        ),
        ..LatticeOptions::default()
    };
    SpringLattice::from_surface(s, &options, &[]).unwrap()
}

fn setup(lat: &SpringLattice, s: &NurbsSurface) -> (SparseMatrix, Vec<(Class, SparseMatrix)>) {
    let geometry = Geometry::Surface(s.clone());
    let omega = Omega::new(&geometry, lat.params.as_ref().unwrap(), false)
        .unwrap()
        .matrix()
        .clone();
    let x0 = lat.flat_positions();
    let unit = lat
        .classes()
        .into_iter()
        .map(|c| (c, lat.unit_stiffness(c, &x0)))
        .collect();
    (omega, unit)
}

fn synthetic_k_d(lat: &SpringLattice, omega: &SparseMatrix) -> SparseMatrix {
    let ks = lat.tangent_stiffness(&lat.flat_positions());
    omega
        .transpose()
        .matmul(&ks.matmul(omega).unwrap())
        .unwrap()
}

/// K_D := Ωᵀ K_S Ω with known k: the closed form recovers k to round-off, the residual
/// vanishes, and the trust region lands on the same answer.
#[test]
fn recovers_known_constants() {
    for (curved, bending, grid) in [
        (false, false, ParameterGrid::Knots),
        (true, false, ParameterGrid::Knots),
        (
            true,
            true,
            ParameterGrid::Uniform {
                nodes_u: 7,
                nodes_v: 6,
            },
        ),
    ] {
        let s = surface(curved);
        let truth = [2.5, 0.75, 0.3];
        let lat = lattice(&s, bending, truth, grid.clone());
        let (omega, unit) = setup(&lat, &s);
        let k_d = synthetic_k_d(&lat, &omega);
        let fit = StiffnessFit::new(&k_d, &omega, &unit, lat.springs.len(), None).unwrap();
        let k = fit.solve(false).unwrap();
        for (i, c) in fit.classes().iter().enumerate() {
            let expected = match c {
                Class::Spring(SpringKind::Structural) => truth[0],
                Class::Spring(SpringKind::Shear) => truth[1],
                Class::Spring(SpringKind::Bend) => truth[2],
                Class::Linear(..) | Class::Hinge(..) => unreachable!("a spring lattice"),
            };
            assert!(
                (k[i] - expected).abs() < 1e-11 * expected,
                "{c:?}: {} vs {expected} (curved {curved}, bending {bending})",
                k[i]
            );
        }
        assert!(fit.relative_residual(&k).unwrap() < 1e-13);
        let tr = fit.trust_region(&vec![1.0; k.len()], false, 200).unwrap();
        for i in 0..k.len() {
            assert!(
                (tr.k[i] - k[i]).abs() < 1e-9 * k[i].abs(),
                "{:?} vs {:?}",
                tr.k,
                k
            );
        }
        // Free-dof reading: a subset of the same matrices, same answer.
        let free: Vec<usize> = (0..k_d.nrows()).filter(|d| d % 7 != 0).collect();
        let fit_free =
            StiffnessFit::new(&k_d, &omega, &unit, lat.springs.len(), Some(&free)).unwrap();
        let k_free = fit_free.solve(false).unwrap();
        for i in 0..k.len() {
            assert!((k_free[i] - k[i]).abs() < 1e-10 * k[i].abs());
        }
    }
}

/// A target that wants a negative constant: the k ≥ 0 solution holds it at zero, satisfies
/// the KKT conditions, and the projected trust region agrees.
#[test]
fn nonnegative_fit_satisfies_kkt() {
    let s = surface(true);
    let lat = lattice(&s, false, [1.0, 1.0, 0.0], ParameterGrid::Knots);
    let (omega, unit) = setup(&lat, &s);
    // K_S = 2 G_structural − 0.8 G_shear: no lattice can have it, the unconstrained fit finds it.
    let k_s = SparseMatrix::linear_combination(2.0, &unit[0].1, -0.8, &unit[1].1).unwrap();
    let k_d = omega
        .transpose()
        .matmul(&k_s.matmul(&omega).unwrap())
        .unwrap();
    let fit = StiffnessFit::new(&k_d, &omega, &unit, lat.springs.len(), None).unwrap();
    let free = fit.solve(false).unwrap();
    assert!(free.iter().any(|&x| x < 0.0), "{free:?}");
    let k = fit.solve(true).unwrap();
    assert!(k.iter().all(|&x| x >= 0.0));
    // KKT: gradient A k − b is zero on the positive entries and ≥ 0 on the zero ones.
    let ak = fit.gram().mul_vec(&k);
    let scale = fit.rhs().iter().map(|x| x.abs()).fold(0.0, f64::max);
    for i in 0..k.len() {
        let g = ak[i] - fit.rhs()[i];
        if k[i] > 0.0 {
            assert!(g.abs() < 1e-12 * scale, "stationarity {g}");
        } else {
            assert!(g > -1e-12 * scale, "dual feasibility {g}");
        }
    }
    let tr = fit.trust_region(&[1.0, 1.0], true, 500).unwrap();
    for i in 0..k.len() {
        assert!(
            (tr.k[i] - k[i]).abs() < 1e-8 * (1.0 + k[i].abs()),
            "{:?} vs {k:?}",
            tr.k
        );
    }
}

/// Classes that cannot be told apart give a singular fit naming them.
#[test]
fn dependent_classes_are_named() {
    let g =
        SparseMatrix::from_triplets(3, 3, &[(0, 0, 1.0), (1, 1, 2.0), (0, 1, 0.5), (1, 0, 0.5)])
            .unwrap();
    let mut g2 = g.clone();
    g2.scale(3.0);
    let k_d = SparseMatrix::identity(3);
    let omega = SparseMatrix::identity(3);
    let err = StiffnessFit::new(
        &k_d,
        &omega,
        &[
            (Class::Spring(SpringKind::Structural), g),
            (Class::Spring(SpringKind::Shear), g2),
        ],
        10,
        None,
    )
    .unwrap_err();
    match err {
        DeriveError::SingularFit { detail } => {
            assert!(
                detail.contains("structural") && detail.contains("shear"),
                "{detail}"
            );
        }
        other => panic!("unexpected {other}"),
    }
    let zero = SparseMatrix::zeros(3, 3);
    let err = StiffnessFit::new(
        &k_d,
        &omega,
        &[(Class::Spring(SpringKind::Bend), zero)],
        10,
        None,
    )
    .unwrap_err();
    assert!(err.to_string().contains("bend"), "{err}");
    // A class that contributes nothing beside one that does: named alone, without a
    // dependence judged on a Gram matrix that has a zero row.
    let g = SparseMatrix::identity(3);
    let err = StiffnessFit::new(
        &k_d,
        &omega,
        &[
            (Class::Spring(SpringKind::Structural), g),
            (Class::Spring(SpringKind::Bend), SparseMatrix::zeros(3, 3)),
        ],
        10,
        None,
    )
    .unwrap_err();
    match err {
        DeriveError::SingularFit { detail } => assert_eq!(
            detail,
            "bend elements contribute nothing on the selected dofs (Ωᵀ G Ω = 0)"
        ),
        other => panic!("unexpected {other}"),
    }
}

/// Identifiability does not depend on the size of the classes' matrices: two independent
/// classes whose Gram entries are ~10⁻¹² (unit matrices scaled by 10⁻⁶) fit, and return the
/// constants of a target made from them.
#[test]
fn identifiability_is_judged_on_the_normalized_gram_matrix() {
    let a = SparseMatrix::from_triplets(3, 3, &[(0, 0, 1e-6), (1, 1, 2e-6)]).unwrap();
    let b = SparseMatrix::from_triplets(
        3,
        3,
        &[(1, 1, 1e-6), (2, 2, 1e-6), (1, 2, -5e-7), (2, 1, -5e-7)],
    )
    .unwrap();
    let k_d = SparseMatrix::linear_combination(3.0, &a, 0.5, &b).unwrap();
    let omega = SparseMatrix::identity(3);
    let fit = StiffnessFit::new(
        &k_d,
        &omega,
        &[
            (Class::Spring(SpringKind::Structural), a),
            (Class::Spring(SpringKind::Shear), b),
        ],
        10,
        None,
    )
    .unwrap();
    let k = fit.solve(false).unwrap();
    assert!(
        (k[0] - 3.0).abs() < 1e-10 && (k[1] - 0.5).abs() < 1e-10,
        "{k:?}"
    );
}

#[test]
fn too_few_springs_is_an_error() {
    let g = SparseMatrix::identity(3);
    let err = StiffnessFit::new(
        &g,
        &g,
        &[
            (Class::Spring(SpringKind::Structural), g.clone()),
            (Class::Spring(SpringKind::Shear), g.clone()),
        ],
        1,
        None,
    )
    .unwrap_err();
    assert!(matches!(
        err,
        DeriveError::TooFewElements {
            classes: 2,
            elements: 1
        }
    ));
}

#[test]
fn node_outside_domain_is_an_error() {
    let s = surface(false);
    let err = Omega::new(&Geometry::Surface(s), &[(0.5, 0.5), (1.5, 0.2)], false).unwrap_err();
    assert!(err.to_string().contains("1.5"), "{err}");
}

/// Ω p(0) = x(0) (eq. 11) on the lattice nodes.
#[test]
fn omega_maps_control_points_to_nodes() {
    let s = surface(true);
    let lat = lattice(&s, false, [1.0, 1.0, 0.0], ParameterGrid::Greville);
    let omega = Omega::new(
        &Geometry::Surface(s.clone()),
        lat.params.as_ref().unwrap(),
        false,
    )
    .unwrap()
    .matrix()
    .clone();
    let p: Vec<f64> = s.control_points().iter().flatten().copied().collect();
    let mut x = vec![0.0; omega.nrows()];
    omega.mul_vec(&p, &mut x);
    for (a, node) in lat.positions.iter().enumerate() {
        for c in 0..3 {
            assert!((x[3 * a + c] - node[c]).abs() < 1e-14 * (1.0 + node[c].abs()));
        }
    }
}

// ------------------------------------------------------------------ values recomputed outside the fit

/// Dense copy as row-major `Vec<Vec<f64>>`, for sums done here rather than by the fit.
fn dense(a: &SparseMatrix) -> Vec<Vec<f64>> {
    let d = a.to_dense();
    (0..d.nrows()).map(|i| d.row(i).to_vec()).collect()
}

fn frobenius(a: &[Vec<f64>]) -> f64 {
    a.iter().flatten().map(|x| x * x).sum::<f64>().sqrt()
}

fn minus(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(r, s)| r.iter().zip(s).map(|(x, y)| x - y).collect())
        .collect()
}

/// Spectral norm of a symmetric matrix by power iteration on `A²` (independent of the
/// eigensolver the fit uses): the Rayleigh quotient of `A²` converges as `(λ₂/λ₁)⁴` per
/// iteration; 4000 iterations.
fn spectral_norm_by_power_iteration(a: &[Vec<f64>]) -> f64 {
    let n = a.len();
    let mut x: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * ((i * 7) % 11) as f64).collect();
    let mul = |x: &[f64]| -> Vec<f64> {
        a.iter()
            .map(|r| r.iter().zip(x).map(|(p, q)| p * q).sum())
            .collect()
    };
    let mut lambda2 = 0.0;
    for _ in 0..4000 {
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        x.iter_mut().for_each(|v| *v /= norm);
        let y = mul(&mul(&x));
        // Rayleigh quotient of A² at the unit vector x.
        lambda2 = x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>();
        x = y;
    }
    lambda2.sqrt()
}

/// Ωᵀ K_S(k) Ω built the slow way: set the constants on the lattice, take its tangent stiffness.
fn pulled_back(
    lat: &SpringLattice,
    omega: &SparseMatrix,
    classes: &[Class],
    k: &[f64],
) -> SparseMatrix {
    let mut lat = lat.clone();
    lat.set_constants(&Constants::from_values(classes, k));
    synthetic_k_d(&lat, omega)
}

/// `model_matrix(k)` is `Ωᵀ K_S(k) Ω` of the lattice carrying k; the Frobenius fit of a
/// target that is not in the span is stationary (`⟨H_c, model(k) − K_D⟩_F = 0`, the normal
/// equations), and its `relative_residual` is the residual recomputed here.
#[test]
fn model_matrix_and_the_frobenius_residual_recomputed_from_the_constants() {
    let s = surface(true);
    let lat = lattice(&s, true, [2.5, 0.75, 0.3], ParameterGrid::Knots);
    let (omega, unit) = setup(&lat, &s);
    let n = omega.ncols();
    // A target outside the span: the lattice's own stiffness plus a diagonal.
    let diag =
        SparseMatrix::from_diagonal(&(0..n).map(|i| 0.5 + 0.01 * i as f64).collect::<Vec<_>>());
    let k_d =
        SparseMatrix::linear_combination(1.0, &synthetic_k_d(&lat, &omega), 1.0, &diag).unwrap();
    let fit = StiffnessFit::new(&k_d, &omega, &unit, lat.springs.len(), None).unwrap();
    let classes = fit.classes().to_vec();

    let probe = [1.3, 0.2, 0.05];
    let by_lattice = dense(&pulled_back(&lat, &omega, &classes, &probe));
    let by_fit = dense(&fit.model_matrix(&probe).unwrap());
    assert!(frobenius(&minus(&by_fit, &by_lattice)) < 1e-13 * frobenius(&by_lattice));

    let k = fit.solve(false).unwrap();
    let model = dense(&pulled_back(&lat, &omega, &classes, &k));
    let target = dense(&k_d);
    let r = minus(&model, &target);
    let residual = frobenius(&r) / frobenius(&target);
    assert!(
        residual > 1e-3,
        "the target is outside the span: {residual}"
    );
    assert!(
        (fit.relative_residual(&k).unwrap() - residual).abs() < 1e-12 * residual,
        "{} vs {residual}",
        fit.relative_residual(&k).unwrap()
    );
    for (c, (_, g)) in unit.iter().enumerate() {
        let h = dense(
            &omega
                .transpose()
                .matmul(&g.matmul(&omega).unwrap())
                .unwrap(),
        );
        let inner: f64 = h
            .iter()
            .flatten()
            .zip(r.iter().flatten())
            .map(|(a, b)| a * b)
            .sum();
        assert!(
            inner.abs() < 1e-10 * frobenius(&h) * frobenius(&r),
            "normal equation {c}: {inner:e}"
        );
    }
}

/// `relative_spectral_residual` against residuals known in closed form (`K_D = 2 Ωᵀ K_S Ω`:
/// 1/2 at the lattice's constants, 1 at zero) and against power iteration; `solve_spectral`
/// returns a point whose residual it reports, no worse than the Frobenius solution's, and the
/// exact constants when the target is in the span.
#[test]
fn spectral_residual_and_fit_against_closed_forms_and_power_iteration() {
    let s = surface(true);
    let truth = [2.5, 0.75, 0.3];
    let lat = lattice(&s, true, truth, ParameterGrid::Knots);
    let (omega, unit) = setup(&lat, &s);
    let exact = synthetic_k_d(&lat, &omega);
    let twice = SparseMatrix::linear_combination(2.0, &exact, 0.0, &exact).unwrap();
    let fit = StiffnessFit::new(&twice, &omega, &unit, lat.springs.len(), None).unwrap();
    let classes = fit.classes().to_vec();
    let t: Vec<f64> = classes
        .iter()
        .map(|c| match c {
            Class::Spring(SpringKind::Structural) => truth[0],
            Class::Spring(SpringKind::Shear) => truth[1],
            Class::Spring(SpringKind::Bend) => truth[2],
            Class::Linear(..) | Class::Hinge(..) => unreachable!(),
        })
        .collect();
    assert!((fit.relative_spectral_residual(&t).unwrap() - 0.5).abs() < 1e-12);
    assert!((fit.relative_spectral_residual(&vec![0.0; t.len()]).unwrap() - 1.0).abs() < 1e-12);
    let probe = [1.0, 2.0, 0.1];
    let d = minus(
        &dense(&pulled_back(&lat, &omega, &classes, &probe)),
        &dense(&twice),
    );
    let want =
        spectral_norm_by_power_iteration(&d) / spectral_norm_by_power_iteration(&dense(&twice));
    let got = fit.relative_spectral_residual(&probe).unwrap();
    assert!(
        (got - want).abs() < 1e-8 * want,
        "{got} vs power iteration {want}"
    );

    // In the span: the exact constants, residual ~ 0.
    let (k, r) = fit.solve_spectral().unwrap();
    for i in 0..k.len() {
        assert!(
            (k[i] - 2.0 * t[i]).abs() < 1e-9 * t[i],
            "{k:?} vs 2 × {t:?}"
        );
    }
    assert!(r < 1e-12, "{r:e}");

    // Outside the span: the reported residual is the residual at the returned k, and no worse
    // than the Frobenius fit's.
    let n = omega.ncols();
    let diag =
        SparseMatrix::from_diagonal(&(0..n).map(|i| 0.5 + 0.01 * i as f64).collect::<Vec<_>>());
    let k_d = SparseMatrix::linear_combination(1.0, &exact, 1.0, &diag).unwrap();
    let fit = StiffnessFit::new(&k_d, &omega, &unit, lat.springs.len(), None).unwrap();
    let (k, r) = fit.solve_spectral().unwrap();
    let d = minus(
        &dense(&pulled_back(&lat, &omega, &classes, &k)),
        &dense(&k_d),
    );
    let want =
        spectral_norm_by_power_iteration(&d) / spectral_norm_by_power_iteration(&dense(&k_d));
    assert!((r - want).abs() < 1e-8 * want, "{r} vs {want}");
    let frob = fit.solve(false).unwrap();
    assert!(r <= fit.relative_spectral_residual(&frob).unwrap() * (1.0 + 1e-12));
}

/// The reported spectrum of a spring lattice at rest maps round-off eigenvalues to exactly
/// zero: a flat lattice of structural and shear springs, free, in a plane tilted off every
/// axis (so that its zero modes are not exact in floating point) and stiff (so that the
/// round-off is far from 1 in absolute terms), has one zero per node (its out-of-plane
/// displacement) and three in-plane rigid motions; every other frequency is well above them.
#[test]
fn the_spectrum_of_a_free_flat_lattice_has_its_zero_modes() {
    let flat = surface(false);
    let (a, b) = (0.3f64, 0.4f64);
    let rotate = |p: [f64; 3]| {
        // About x by a, then about y by b.
        let (y, z) = (
            a.cos() * p[1] - a.sin() * p[2],
            a.sin() * p[1] + a.cos() * p[2],
        );
        let (x, z) = (b.cos() * p[0] + b.sin() * z, -b.sin() * p[0] + b.cos() * z);
        [x, y, z]
    };
    let (ku, kv) = paper_knots();
    let tilted = NurbsSurface::try_new(
        ku,
        kv,
        flat.control_points().iter().map(|&p| rotate(p)).collect(),
        flat.weights().to_vec(),
    )
    .unwrap();
    let lat = lattice(&tilted, false, [3e3, 1e3, 0.0], ParameterGrid::Knots);
    assert!(lat.fixed.iter().all(|f| !f));
    let omega = nurbspring_derive::msm_spectrum(&lat).unwrap();
    assert_eq!(omega.len(), 3 * lat.n_nodes());
    let zeros = omega.iter().filter(|&&w| w == 0.0).count();
    assert_eq!(zeros, lat.n_nodes() + 3, "{omega:?}");
    let top = omega.last().unwrap();
    let lowest_nonzero = omega.iter().find(|&&w| w > 0.0).unwrap();
    assert!(*lowest_nonzero > 1e-3 * top, "{lowest_nonzero} vs {top}");
}

/// Random symmetric 6 × 6 "unit matrices" for four classes (Ω the identity) and a target
/// `K_D = Σ t_c G_c + E` with some `t_c < 0` and a perturbation E, so that the `k ≥ 0` optimum
/// has an active set to find. A linear congruential generator keeps the cases fixed.
fn random_fits() -> Vec<StiffnessFit> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let classes = Class::linear(&nurbspring_msm::LinearKind::ALL);
    let n = 6;
    let mut out = Vec::new();
    for _ in 0..40 {
        let mut symmetric = || {
            let mut t = Vec::new();
            for i in 0..n {
                for j in i..n {
                    let v = next();
                    t.push((i, j, v));
                    if i != j {
                        t.push((j, i, v));
                    }
                }
            }
            SparseMatrix::from_triplets(n, n, &t).unwrap()
        };
        let unit: Vec<(Class, SparseMatrix)> =
            classes[..4].iter().map(|&c| (c, symmetric())).collect();
        let mut k_d = symmetric();
        k_d.scale(0.3);
        for (_, g) in &unit {
            // Constants in the hundreds: the radius (1 from the origin) must grow to reach them.
            k_d = SparseMatrix::linear_combination(1.0, &k_d, 300.0 * next(), g).unwrap();
        }
        out.push(StiffnessFit::new(&k_d, &SparseMatrix::identity(n), &unit, 100, None).unwrap());
    }
    out
}

/// The `k ≥ 0` optimum against the KKT conditions of `½ kᵀA k − bᵀk` (A the Gram matrix):
/// `k ≥ 0`, the gradient zero where `k > 0` and non-negative where `k = 0`.
fn assert_kkt(fit: &StiffnessFit, k: &[f64], tol: f64, what: &str) {
    let ak = fit.gram().mul_vec(k);
    let scale = fit.rhs().iter().map(|x| x.abs()).fold(0.0, f64::max);
    for i in 0..k.len() {
        let g = ak[i] - fit.rhs()[i];
        assert!(k[i] >= 0.0, "{what}: {k:?}");
        if k[i] > 0.0 {
            assert!(g.abs() < tol * scale, "{what}: stationarity {g} at {k:?}");
        } else {
            assert!(g > -tol * scale, "{what}: dual feasibility {g} at {k:?}");
        }
    }
}

/// On random problems with active bounds: the closed-form `k ≥ 0` solution satisfies the KKT
/// conditions; the projected trust region reaches it from the origin (every constant at the
/// bound, the gradient pushing inward) and from far away (100 in every class; the radius must
/// grow), each within 60 iterations; the unconstrained trust region reaches the unconstrained
/// solution from 10⁴ within 40.
#[test]
fn nonnegative_fits_and_trust_regions_on_random_problems() {
    let mut active = 0;
    for (case, fit) in random_fits().iter().enumerate() {
        let k = fit.solve(true).unwrap();
        assert_kkt(fit, &k, 1e-10, &format!("case {case}, closed form"));
        active += k.iter().filter(|&&x| x == 0.0).count();
        // Round-off of the constants' size (measured: below 10⁻¹⁵), with a margin; from 10⁴
        // the stop (the gradient below 10⁻¹³ of the start's) is 10⁻¹³ of a start 10³ times
        // farther than the constants.
        let close = |a: &[f64], b: &[f64], rel: f64| {
            let scale = b.iter().map(|x| x.abs()).fold(1.0, f64::max);
            a.iter().zip(b).all(|(x, y)| (x - y).abs() < rel * scale)
        };
        for start in [vec![0.0; 4], vec![100.0; 4]] {
            let tr = fit.trust_region(&start, true, 60).unwrap();
            assert!(
                close(&tr.k, &k, 1e-13),
                "case {case} from {start:?}: {:?} vs {k:?} after {}",
                tr.k,
                tr.iterations
            );
        }
        let free = fit.solve(false).unwrap();
        let tr = fit.trust_region(&[1e4; 4], false, 40).unwrap();
        assert!(
            close(&tr.k, &free, 1e-10),
            "case {case}: {:?} vs {free:?}",
            tr.k
        );
    }
    // The cases do exercise the bounds.
    assert!(active >= 20, "{active}");
}

/// Two classes whose unit matrices are nearly parallel (normalized Gram off-diagonal 0.99),
/// started where the first constant is optimal given the second, which sits at 0.01 and is
/// pulled below zero: the full step (inside the start radius) goes far along the valley, and
/// its projection on `k ≥ 0` climbs the objective (predicted decrease < 0). The radius must
/// shrink to a quarter of that step each time; the iteration then reaches the `k ≥ 0`
/// optimum `(a + 0.99 b, 0)` of `K_D = a G₁ + b G₂` within eight iterations.
#[test]
fn the_projected_trust_region_shrinks_when_the_projection_climbs() {
    let c2 = (1.0f64 - 0.99 * 0.99).sqrt();
    let g1 = SparseMatrix::from_triplets(2, 2, &[(0, 0, 1.0)]).unwrap();
    let g2 = SparseMatrix::from_triplets(2, 2, &[(0, 0, 0.99), (1, 1, c2)]).unwrap();
    let (a, b) = (300.0, -100.0);
    let k_d = SparseMatrix::linear_combination(a, &g1, b, &g2).unwrap();
    let classes = Class::linear(&nurbspring_msm::LinearKind::ALL);
    let unit = [(classes[0], g1), (classes[1], g2)];
    let fit = StiffnessFit::new(&k_d, &SparseMatrix::identity(2), &unit, 10, None).unwrap();
    let eps = 0.01;
    let start = [a - 0.99 * (eps - b), eps];
    // The first constant is optimal given the second; the second is pushed outward.
    let g = fit.gram().mul_vec(&start);
    assert!((g[0] - fit.rhs()[0]).abs() < 1e-9 * fit.rhs()[0].abs());
    assert!(g[1] - fit.rhs()[1] > 0.0);
    let tr = fit.trust_region(&start, true, 100).unwrap();
    // Rejected steps shrink the radius to a quarter of the step each time: from the first
    // step's 99 to the 0.6 that the projection tolerates takes four, then two steps settle.
    assert!(tr.iterations <= 8, "{} iterations", tr.iterations);
    let expected = [a + 0.99 * b, 0.0];
    assert!(
        (tr.k[0] - expected[0]).abs() < 1e-13 * expected[0] && tr.k[1] == 0.0,
        "{:?} after {} iterations",
        tr.k,
        tr.iterations
    );
    assert_kkt(&fit, &tr.k, 1e-10, "valley");
}

/// Scaling the whole problem (`K_D` and every unit matrix by s) leaves the constants: the
/// `k ≥ 0` trust region from the bound reaches the same optimum at s = 10⁻⁶ and 10⁶ (its ratio
/// of actual to predicted decrease does not depend on the scale).
#[test]
fn the_trust_region_does_not_depend_on_the_problems_scale() {
    let classes = Class::linear(&nurbspring_msm::LinearKind::ALL);
    for (case, fit) in random_fits().iter().enumerate().take(10) {
        let k = fit.solve(true).unwrap();
        for scale in [1e-6, 1e6] {
            let unit: Vec<(Class, SparseMatrix)> = (0..4)
                .map(|c| {
                    let mut h = fit.h(c).clone();
                    h.scale(scale);
                    (classes[c], h)
                })
                .collect();
            // K_D: the target's part in the span of the classes, Σ k*_c H_c with k* the
            // unconstrained solution (the part outside the span moves no optimum); Ω is the
            // identity, so H_c = G_c.
            let free = fit.solve(false).unwrap();
            let mut k_d = SparseMatrix::zeros(6, 6);
            for (c, (_, h)) in unit.iter().enumerate() {
                k_d = SparseMatrix::linear_combination(1.0, &k_d, free[c], h).unwrap();
            }
            let scaled =
                StiffnessFit::new(&k_d, &SparseMatrix::identity(6), &unit, 100, None).unwrap();
            let tr = scaled.trust_region(&[0.0; 4], true, 60).unwrap();
            let size = k.iter().map(|x| x.abs()).fold(1.0, f64::max);
            for c in 0..4 {
                assert!(
                    (tr.k[c] - k[c]).abs() < 1e-13 * size,
                    "case {case}, scale {scale}: {:?} vs {k:?}",
                    tr.k
                );
            }
        }
    }
}

/// The spectral-norm fit improves on the Frobenius solution it starts from when the two
/// norms disagree (random problems whose target is not in the span of the classes): a lower
/// spectral residual, and no step of 10⁻³ of the largest constant along a class lowers it
/// further by more than a part in 10⁴ (a minimum of a convex function, up to Nelder–Mead's
/// accuracy on a non-smooth one).
#[test]
fn the_spectral_fit_improves_on_the_frobenius_start() {
    for (case, fit) in random_fits().iter().enumerate().take(5) {
        let start = fit.solve(false).unwrap();
        let r0 = fit.relative_spectral_residual(&start).unwrap();
        let (k, r) = fit.solve_spectral().unwrap();
        assert_eq!(r, fit.relative_spectral_residual(&k).unwrap());
        assert!(r < r0 * (1.0 - 1e-4), "case {case}: {r} vs {r0}");
        let step = 1e-3 * k.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for c in 0..k.len() {
            for sign in [-1.0, 1.0] {
                let mut probe = k.clone();
                probe[c] += sign * step;
                let rp = fit.relative_spectral_residual(&probe).unwrap();
                assert!(rp > r * (1.0 - 1e-4), "case {case}, class {c}: {rp} < {r}");
            }
        }
    }
}
