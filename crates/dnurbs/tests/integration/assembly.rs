//! Assembled matrices: symmetry, definiteness, partition of unity, rigid translations,
//! refinement invariance, weights-as-dofs blocks, loads, determinism.

use nurbspring_dnurbs::{
    DnurbsOptions, Geometry, Integration, Loads, Material, PointLoad, assemble, assemble_scalar,
};
use nurbspring_linalg::{SparseMatrix, SpdSolver, symmetric_eigen};

use crate::support::{self, tol};

/// Every term of the energy that applies to `geometry` (a curve has no v terms).
fn terms_for(geometry: &Geometry) -> Material {
    if geometry.is_curve() {
        Material {
            alpha22: 0.0,
            beta12: 0.0,
            beta22: 0.0,
            ..all_terms()
        }
    } else {
        all_terms()
    }
}

fn all_terms() -> Material {
    Material {
        mu: 1.7,
        gamma: 0.3,
        alpha11: 0.9,
        alpha22: 1.3,
        beta11: 0.02,
        beta12: 0.05,
        beta22: 0.04,
    }
}

#[test]
fn paper_mass_is_spd_and_sums_to_75() {
    let g = Geometry::Surface(support::paper_surface());
    let m = assemble(
        &g,
        &support::paper_material(),
        &Loads::default(),
        &DnurbsOptions::default(),
    )
    .unwrap();
    assert_eq!(m.mass.nrows(), 105);
    assert!(
        m.mass.symmetry_error() <= tol::SYMMETRY,
        "{}",
        m.mass.symmetry_error()
    );
    SpdSolver::new(&m.mass).expect("M must be positive definite");
    // Σ_ij M_ij = 3 μ · (parameter area) = 3 · 25 · 1 (docs/math.md §7).
    assert!(
        (m.mass.sum() - 75.0).abs() <= tol::SUM * 75.0,
        "{}",
        m.mass.sum()
    );
    // Σ_ij K_ij = 0: K annihilates translations.
    assert!(m.stiffness.sum().abs() <= tol::TRANSLATION * m.stiffness.frobenius_norm());
}

#[test]
fn stiffness_is_symmetric_psd_and_annihilates_translations() {
    for geometry in [
        Geometry::Surface(support::paper_surface()),
        Geometry::Surface(support::wavy_rational_patch()),
        Geometry::Curve(support::straight_curve(3, 4, 2.0)),
    ] {
        for integration in [Integration::Parameter, Integration::Area] {
            let options = DnurbsOptions {
                integration,
                ..DnurbsOptions::default()
            };
            let m = assemble(
                &geometry,
                &terms_for(&geometry),
                &Loads::default(),
                &options,
            )
            .unwrap();
            let k = &m.stiffness;
            assert!(
                k.symmetry_error() <= tol::SYMMETRY,
                "{}",
                k.symmetry_error()
            );
            let n = k.nrows();
            for x in 0..3 {
                let t: Vec<f64> = (0..n).map(|d| if d % 3 == x { 1.0 } else { 0.0 }).collect();
                let mut kt = vec![0.0; n];
                k.mul_vec(&t, &mut kt);
                let norm = kt.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    norm <= tol::TRANSLATION * k.frobenius_norm(),
                    "K t_{x} = {norm:e}"
                );
            }
            let eig = symmetric_eigen(&k.to_dense()).unwrap();
            let max = eig.values.last().copied().unwrap();
            assert!(
                eig.values[0] >= -tol::PSD * max,
                "λ_min = {:e}",
                eig.values[0]
            );
            assert!(m.mass.symmetry_error() <= tol::SYMMETRY);
            SpdSolver::new(&m.mass).expect("M must be positive definite");
        }
    }
}

/// `Cᵀ A_fine C = A_coarse` for a B-spline surface refined by knot insertion (docs/math.md §2): the
/// fine space contains the coarse one and Gauss quadrature is exact for both.
#[test]
fn refinement_invariance_of_scalar_matrices() {
    let coarse = support::wavy_patch();
    let (fine, c) = coarse.refine_knots(&[0.15, 0.3, 0.5], &[0.2, 0.7]).unwrap();
    let c = SparseMatrix::from_triplets(c.nrows, c.ncols, &c.triplets).unwrap();
    let options = DnurbsOptions::default();
    let sc = assemble_scalar(&Geometry::Surface(coarse), &all_terms(), &options).unwrap();
    let sf = assemble_scalar(&Geometry::Surface(fine), &all_terms(), &options).unwrap();
    let project = |a: &SparseMatrix| c.transpose().matmul(&a.matmul(&c).unwrap()).unwrap();
    for (name, f, co) in [
        ("M", &sf.mass, &sc.mass),
        ("D", &sf.damping, &sc.damping),
        ("K", &sf.stiffness, &sc.stiffness),
    ] {
        let err = support::rel_diff(&project(f), co);
        assert!(err <= tol::REFINEMENT, "{name}: {err:e}");
    }
}

#[test]
fn refinement_invariance_of_dof_matrices_for_a_curve() {
    let k = nurbspring_geom::KnotVector::try_new(vec![0., 0., 0., 0.5, 1., 1., 1.], 2).unwrap();
    let pts = vec![[0., 0., 0.], [1., 2., 0.], [2., -1., 1.], [3., 0., 0.5]];
    let coarse = nurbspring_geom::NurbsCurve::try_new(k, pts, vec![1.0; 4]).unwrap();
    let (fine, c) = coarse.refine_knots(&[0.25, 0.6, 0.6]).unwrap();
    let c = SparseMatrix::from_triplets(c.nrows, c.ncols, &c.triplets)
        .unwrap()
        .kron_identity(3);
    let material = Material {
        alpha11: 2.0,
        beta11: 0.5,
        ..terms_for(&Geometry::Curve(coarse.clone()))
    };
    let o = DnurbsOptions::default();
    let mc = assemble(&Geometry::Curve(coarse), &material, &Loads::default(), &o).unwrap();
    let mf = assemble(&Geometry::Curve(fine), &material, &Loads::default(), &o).unwrap();
    let project = |a: &SparseMatrix| c.transpose().matmul(&a.matmul(&c).unwrap()).unwrap();
    assert!(support::rel_diff(&project(&mf.mass), &mc.mass) <= tol::REFINEMENT);
    assert!(support::rel_diff(&project(&mf.stiffness), &mc.stiffness) <= tol::REFINEMENT);
}

/// With weights as unknowns the xyz blocks are the constant-weight matrices, `J p = c` gives
/// `M p = ∫ μ Jᵀ c`, and scaling every weight (which leaves c unchanged) is a null vector.
#[test]
fn weights_as_dofs_blocks_and_scaling_null_space() {
    // The B-spline patch also checks the sum-factorized scalar path against the general kernel.
    for surface in [support::wavy_patch(), support::wavy_rational_patch()] {
        weights_as_dofs_case(Geometry::Surface(surface));
    }
}

fn weights_as_dofs_case(geometry: Geometry) {
    let material = all_terms();
    let o3 = DnurbsOptions::default();
    let o4 = DnurbsOptions {
        weights_as_dofs: true,
        ..o3.clone()
    };
    let m3 = assemble(&geometry, &material, &Loads::default(), &o3).unwrap();
    let m4 = assemble(&geometry, &material, &Loads::default(), &o4).unwrap();
    let n = geometry.n_control_points();
    let xyz: Vec<usize> = (0..n)
        .flat_map(|k| (0..3).map(move |x| 4 * k + x))
        .collect();
    for (a4, a3) in [
        (&m4.mass, &m3.mass),
        (&m4.stiffness, &m3.stiffness),
        (&m4.damping, &m3.damping),
    ] {
        assert!(a4.symmetry_error() <= tol::SYMMETRY);
        let sub = a4.submatrix(&xyz, &xyz);
        assert!(
            support::rel_diff(&sub, a3) <= tol::SAME,
            "{:e}",
            support::rel_diff(&sub, a3)
        );
    }
    let w_dir: Vec<f64> = (0..4 * n)
        .map(|d| {
            if d % 4 == 3 {
                geometry.weights()[d / 4]
            } else {
                0.0
            }
        })
        .collect();
    for a in [&m4.mass, &m4.stiffness] {
        let mut y = vec![0.0; 4 * n];
        a.mul_vec(&w_dir, &mut y);
        let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(
            norm <= tol::TRANSLATION * a.frobenius_norm() * 10.0,
            "{norm:e}"
        );
    }
    // f_p with a uniform density: Σ_k f over xyz = density · ∫∫ 1 (J p = c, Σ R = 1).
    let loads = Loads {
        gravity: [0.0, 0.0, -9.81],
        ..Loads::default()
    };
    let f4 = assemble(&geometry, &material, &loads, &o4).unwrap().force;
    let f3 = assemble(&geometry, &material, &loads, &o3).unwrap().force;
    let fz: f64 = (0..n).map(|k| f4[4 * k + 2]).sum();
    assert!((fz - material.mu * -9.81).abs() <= tol::SUM * 20.0);
    let f4_xyz: Vec<f64> = xyz.iter().map(|&d| f4[d]).collect();
    assert!(support::max_abs_diff(&f4_xyz, &f3) <= tol::SAME);
}

/// A tilted plane `z = a x + b y` over `[0, 2] × [0, 3]` (the flat patch with z = a x + b y
/// at its control points, an affine map, so the surface is that plane): its area is
/// `6 √(1 + a² + b²)`, and with area integration Σ M = 3 μ · area. The normal
/// `c_u × c_v = 6 (−a, −b, 1)` has all three components non-zero, so each enters.
#[test]
fn area_integration_measures_a_tilted_plane() {
    let (a, b, mu) = (0.5, -0.75, 2.0);
    let flat = support::flat_patch(2, 3, 2, 2.0, 3.0);
    let points: Vec<[f64; 3]> = flat
        .control_points()
        .iter()
        .map(|&[x, y, _]| [x, y, a * x + b * y])
        .collect();
    let tilted = nurbspring_geom::NurbsSurface::try_new(
        flat.basis_u().knots().clone(),
        flat.basis_v().knots().clone(),
        points,
        flat.weights().to_vec(),
    )
    .unwrap();
    let material = Material {
        mu,
        ..Material::default()
    };
    let area = 6.0 * (1.0 + a * a + b * b).sqrt();
    for weights_as_dofs in [false, true] {
        let options = DnurbsOptions {
            integration: Integration::Area,
            weights_as_dofs,
            ..DnurbsOptions::default()
        };
        let m = assemble(
            &Geometry::Surface(tilted.clone()),
            &material,
            &Loads::default(),
            &options,
        )
        .unwrap();
        // The x, y, z rows and columns only (with weights as unknowns every fourth dof is a
        // weight).
        let dpp = m.dofs_per_point;
        let xyz: f64 = m
            .mass
            .triplets()
            .filter(|&(i, j, _)| i % dpp < 3 && j % dpp < 3)
            .map(|(_, _, v)| v)
            .sum();
        let want = 3.0 * mu * area;
        assert!(
            (xyz - want).abs() <= tol::SUM * want,
            "weights as dofs {weights_as_dofs}: Σ M = {xyz}, 3 μ · area = {want}"
        );
    }
}

#[test]
fn area_integration_measures_the_surface_and_the_curve() {
    let material = Material {
        mu: 2.0,
        ..Material::default()
    };
    let area = DnurbsOptions {
        integration: Integration::Area,
        ..DnurbsOptions::default()
    };
    // A flat 3 × 5 rectangle: Σ M = 3 μ · 15.
    let patch = Geometry::Surface(support::flat_patch(3, 3, 2, 3.0, 5.0));
    let m = assemble(&patch, &material, &Loads::default(), &area).unwrap();
    assert!(
        (m.mass.sum() - 3.0 * 2.0 * 15.0).abs() <= tol::SUM * 90.0,
        "{}",
        m.mass.sum()
    );
    // A straight curve of length 2.5: Σ M = 3 μ · 2.5.
    let curve = Geometry::Curve(support::straight_curve(2, 3, 2.5));
    let m = assemble(&curve, &material, &Loads::default(), &area).unwrap();
    assert!(
        (m.mass.sum() - 15.0).abs() <= tol::SUM * 15.0,
        "{}",
        m.mass.sum()
    );
    // Parameter integration of the same curve measures the parameter interval.
    let m = assemble(
        &curve,
        &material,
        &Loads::default(),
        &DnurbsOptions::default(),
    )
    .unwrap();
    assert!((m.mass.sum() - 6.0).abs() <= tol::SUM * 6.0);
}

#[test]
fn loads_sum_to_the_applied_force() {
    let g = Geometry::Surface(support::paper_surface());
    let loads = Loads {
        gravity: [0.0, 0.0, -9.81],
        distributed: [0.5, 0.0, 0.0],
        point: vec![PointLoad {
            u: 0.3,
            v: 0.6,
            force: [1.0, -2.0, 3.0],
        }],
        edges: Vec::new(),
    };
    let m = assemble(
        &g,
        &support::paper_material(),
        &loads,
        &DnurbsOptions::default(),
    )
    .unwrap();
    let total: Vec<f64> = (0..3)
        .map(|x| m.force.iter().skip(x).step_by(3).sum())
        .collect();
    // μ g · 1 + distributed · 1 + F (partition of unity).
    let expected = [0.5 + 1.0, -2.0, 25.0 * -9.81 + 3.0];
    assert!(
        support::max_abs_diff(&total, &expected) <= tol::SUM * 250.0,
        "{total:?}"
    );
    // The point load alone is J(u0, v0)ᵀ F.
    let only_point = Loads {
        point: loads.point.clone(),
        ..Loads::default()
    };
    let f = assemble(
        &g,
        &support::paper_material(),
        &only_point,
        &DnurbsOptions::default(),
    )
    .unwrap()
    .force;
    let j = g.jacobian(0.3, 0.6, 0, false).unwrap();
    let mut expected = vec![0.0; 105];
    j.apply_transpose_add(
        nurbspring_geom::Deriv::Value,
        [1.0, -2.0, 3.0],
        1.0,
        &mut expected,
    );
    assert_eq!(f, expected);
}

#[test]
fn one_thread_and_many_threads_agree_exactly() {
    let g = Geometry::Surface(support::wavy_rational_patch());
    for weights_as_dofs in [false, true] {
        let o = DnurbsOptions {
            weights_as_dofs,
            ..DnurbsOptions::default()
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let one = pool.install(|| assemble(&g, &all_terms(), &Loads::default(), &o).unwrap());
        let many = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap()
            .install(|| assemble(&g, &all_terms(), &Loads::default(), &o).unwrap());
        assert_eq!(one.mass, many.mass);
        assert_eq!(one.stiffness, many.stiffness);
        assert_eq!(one.force, many.force);
    }
}

#[test]
fn more_quadrature_points_change_nothing_for_b_splines() {
    // 4 points per direction integrate bicubic products exactly; 6 must agree to round-off.
    let g = Geometry::Surface(support::wavy_patch());
    let s4 = assemble_scalar(&g, &all_terms(), &DnurbsOptions::default()).unwrap();
    let o6 = DnurbsOptions {
        quadrature_points: Some(6),
        ..DnurbsOptions::default()
    };
    let s6 = assemble_scalar(&g, &all_terms(), &o6).unwrap();
    assert!(support::rel_diff(&s6.mass, &s4.mass) <= tol::SAME);
    assert!(support::rel_diff(&s6.stiffness, &s4.stiffness) <= tol::SAME);
}

#[test]
fn assembler_reuses_its_pattern_on_the_same_knots() {
    let coarse = support::wavy_rational_patch();
    let moved: Vec<[f64; 3]> = coarse
        .control_points()
        .iter()
        .map(|p| [p[0], p[1] + 0.1 * p[0], 2.0 * p[2]])
        .collect();
    let moved = Geometry::Surface(coarse.with_control_points(moved).unwrap());
    let loads = Loads {
        gravity: [0.0, -1.0, 0.0],
        ..Loads::default()
    };
    for weights_as_dofs in [false, true] {
        // A fixed rule: the automatic one depends on the geometry it is chosen for.
        let o = DnurbsOptions {
            weights_as_dofs,
            integration: Integration::Area,
            quadrature_points: Some(5),
            ..DnurbsOptions::default()
        };
        let assembler =
            nurbspring_dnurbs::Assembler::new(&Geometry::Surface(coarse.clone()), &o).unwrap();
        let reused = assembler.assemble(&moved, &all_terms(), &loads).unwrap();
        let fresh = assemble(&moved, &all_terms(), &loads, &o).unwrap();
        assert_eq!(reused.mass, fresh.mass);
        assert_eq!(reused.stiffness, fresh.stiffness);
        assert_eq!(reused.force, fresh.force);
        let other = Geometry::Surface(support::paper_surface());
        assert!(matches!(
            assembler.assemble(&other, &all_terms(), &loads),
            Err(nurbspring_dnurbs::DnurbsError::InvalidOption {
                name: "geometry",
                ..
            })
        ));
    }
}

#[test]
fn automatic_quadrature_is_exact_for_b_splines_and_converged_otherwise() {
    use nurbspring_dnurbs::QUADRATURE_TOLERANCE;
    let g = Geometry::Surface(support::wavy_patch());
    let auto = DnurbsOptions::default().quadrature_for(&g).unwrap();
    assert_eq!(
        (auto.points, auto.polynomial, auto.estimated_error),
        (4, true, 0.0)
    );
    let rational = Geometry::Surface(support::wavy_rational_patch());
    for (integration, wad) in [
        (Integration::Parameter, false),
        (Integration::Area, false),
        (Integration::Parameter, true),
    ] {
        let o = DnurbsOptions {
            integration,
            weights_as_dofs: wad,
            ..DnurbsOptions::default()
        };
        let choice = o.quadrature_for(&rational).unwrap();
        assert!(!choice.polynomial && choice.automatic);
        assert!(choice.estimated_error <= QUADRATURE_TOLERANCE, "{choice:?}");
        assert!(choice.warning().is_none());
        // The estimate is honest: the chosen rule against a much finer one.
        let at = |points| {
            let o = DnurbsOptions {
                quadrature_points: Some(points),
                weights_as_dofs: false,
                ..o.clone()
            };
            assemble_scalar(&rational, &all_terms(), &o).unwrap()
        };
        let (chosen, fine) = (at(choice.points), at(24));
        let err = support::rel_diff(&chosen.mass, &fine.mass)
            .max(support::rel_diff(&chosen.stiffness, &fine.stiffness));
        assert!(
            err <= 10.0 * QUADRATURE_TOLERANCE,
            "{integration:?}: {err:e} at {choice:?}"
        );
        // A too small explicit rule is reported with its estimate and the key.
        let coarse = DnurbsOptions {
            quadrature_points: Some(2),
            ..o.clone()
        }
        .quadrature_for(&rational)
        .unwrap();
        let warning = coarse.warning().unwrap();
        assert!(
            warning.contains("dnurbs.quadrature_points = 2"),
            "{warning}"
        );
        eprintln!(
            "{integration:?} wad {wad}: {choice:?}; 2 points: {:.1e}",
            coarse.estimated_error
        );
    }
}

#[test]
fn automatic_quadrature_search_is_bounded_on_extreme_weights() {
    use nurbspring_dnurbs::{AUTO_SPAN, QUADRATURE_TOLERANCE};
    // Weights spanning six orders of magnitude: the integrands are far from polynomials, so no
    // rule near the start reaches the tolerance. The search stops AUTO_SPAN rules above the
    // start (one assembly each) and reports what it reached, with a warning naming the key.
    let s = support::wavy_patch();
    let w: Vec<f64> = (0..s.n_control_points())
        .map(|k| 10f64.powi(((k * 5) % 7) as i32 - 3))
        .collect();
    let extreme = Geometry::Surface(
        s.with_control_points_and_weights(s.control_points().to_vec(), w)
            .unwrap(),
    );
    let choice = DnurbsOptions::default().quadrature_for(&extreme).unwrap();
    let start = 4;
    assert!(choice.automatic && !choice.polynomial);
    assert!(choice.points <= start + AUTO_SPAN, "{choice:?}");
    if choice.estimated_error > QUADRATURE_TOLERANCE {
        assert_eq!(choice.points, start + AUTO_SPAN - 1, "{choice:?}");
    }
    assert!(choice.estimated_error.is_finite());
}

/// The exact Kronecker form (parameter integration of a B-spline) against the Gauss-point
/// kernel, through the public model with constraints: on the affine sheet
/// `c(u, v) = (a u, b v, 0)` the area element is the constant `a b`, so the area-integrated
/// matrices (Gauss-point kernel) are `a b` times the parameter-integrated ones (Kronecker
/// form), on repeated interior knots, with fixed rings, fixed points and a linear constraint.
#[test]
fn kronecker_form_equals_the_gauss_point_kernel_under_constraints() {
    use nurbspring_dnurbs::{Constraints, DnurbsModel, LinearConstraint};
    use nurbspring_geom::{KnotVector, NurbsSurface};
    let ku =
        KnotVector::try_new(vec![0., 0., 0., 0., 0.2, 0.2, 0.5, 0.8, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0.3, 0.3, 0.6, 1., 1., 1.], 2).unwrap();
    let (a, b) = (2.0, 3.5);
    let (gu, gv) = (ku.greville(), kv.greville());
    let pts: Vec<[f64; 3]> = gu
        .iter()
        .flat_map(|&u| gv.iter().map(move |&v| [a * u, b * v, 0.0]))
        .collect();
    let n = pts.len();
    let sheet = NurbsSurface::try_new(ku, kv, pts, vec![1.0; n]).unwrap();
    let constraints = [
        Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        Constraints {
            fixed_points: vec![0, 5, 17],
            linear: vec![LinearConstraint {
                terms: vec![(30, 1.0), (31, -0.5)],
                rhs: 0.0,
            }],
            ..Constraints::default()
        },
    ];
    let loads = Loads {
        gravity: [0.0, 0.0, -9.81],
        ..Loads::default()
    };
    for c in &constraints {
        let model = |integration| {
            let options = DnurbsOptions {
                quadrature_points: Some(4),
                integration,
                ..DnurbsOptions::default()
            };
            DnurbsModel::new(
                Geometry::Surface(sheet.clone()),
                all_terms(),
                loads.clone(),
                c,
                options,
            )
            .unwrap()
        };
        let (fast, gauss) = (model(Integration::Parameter), model(Integration::Area));
        let scaled = |m: &SparseMatrix| {
            let mut m = m.clone();
            m.scale(a * b);
            m
        };
        assert!(support::rel_diff(gauss.reduced_mass(), &scaled(fast.reduced_mass())) < 1e-14);
        assert!(
            support::rel_diff(gauss.reduced_stiffness(), &scaled(fast.reduced_stiffness())) < 1e-14
        );
        let f: Vec<f64> = fast.reduced_force().iter().map(|x| a * b * x).collect();
        assert!(support::rel_vec(gauss.reduced_force(), &f) < 1e-14);
    }
}
