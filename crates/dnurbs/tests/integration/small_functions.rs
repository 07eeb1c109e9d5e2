//! Values of the model's small public functions and of the checks behind them, each against a
//! hand computation or an independent recomputation: domains and measures, `Loads::is_zero`,
//! `Matrices::n_dofs`, periods, initial states from per-point velocities and displacements,
//! reduced coordinates under linear constraints, the consistency checks of linear
//! constraints, and the quadrature estimate of a rational curve.

use nurbspring_dnurbs::{
    Constraints, DnurbsError, DnurbsModel, DnurbsOptions, Geometry, LinearConstraint, Loads,
    Material, Modes, PointLoad, assemble,
};
use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_linalg::{DenseMatrix, SparseMatrix};

use crate::support::{self, tol};

#[test]
fn domain_and_parameter_measure_by_hand() {
    let ku = KnotVector::try_new(vec![1., 1., 2., 3., 3.], 1).unwrap();
    let kv = KnotVector::try_new(vec![2., 2., 5., 5.], 1).unwrap();
    let pts = (0..6).map(|k| [k as f64, (k % 2) as f64, 0.0]).collect();
    let surface = Geometry::Surface(NurbsSurface::try_new(ku, kv, pts, vec![1.0; 6]).unwrap());
    assert_eq!(surface.domain(), ((1.0, 3.0), (2.0, 5.0)));
    assert_eq!(surface.parameter_measure(), 6.0);
    let k = KnotVector::try_new(vec![0.5, 0.5, 2.0, 2.0], 1).unwrap();
    let curve = Geometry::Curve(
        NurbsCurve::try_new(k, vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![1.0; 2]).unwrap(),
    );
    assert_eq!(curve.domain(), ((0.5, 2.0), (0.0, 0.0)));
    assert_eq!(curve.parameter_measure(), 1.5);
}

#[test]
fn loads_are_zero_only_without_any_load() {
    assert!(Loads::default().is_zero());
    let gravity = Loads {
        gravity: [0.0, 0.0, -1.0],
        ..Loads::default()
    };
    let distributed = Loads {
        distributed: [0.5, 0.0, 0.0],
        ..Loads::default()
    };
    let point = |force| Loads {
        point: vec![PointLoad {
            u: 0.5,
            v: 0.5,
            force,
        }],
        ..Loads::default()
    };
    assert!(!gravity.is_zero() && !distributed.is_zero());
    assert!(!point([0.0, 1.0, 0.0]).is_zero());
    assert!(point([0.0; 3]).is_zero());
}

#[test]
fn matrices_have_three_or_four_dofs_per_control_point() {
    for (weights_as_dofs, per_point) in [(false, 3), (true, 4)] {
        let options = DnurbsOptions {
            weights_as_dofs,
            ..DnurbsOptions::default()
        };
        let m = assemble(
            &Geometry::Surface(support::paper_surface()),
            &support::paper_material(),
            &Loads::default(),
            &options,
        )
        .unwrap();
        assert_eq!((m.n_dofs(), m.dofs_per_point), (35 * per_point, per_point));
        assert_eq!(m.mass.nrows(), m.n_dofs());
    }
}

#[test]
fn periods_are_two_pi_over_omega_and_infinite_for_rigid_modes() {
    let pi = std::f64::consts::PI;
    let modes = Modes {
        omega: vec![0.0, 2.0 * pi, 4.0 * pi],
        vectors: DenseMatrix::zeros(3, 3),
    };
    assert_eq!(modes.periods(), vec![f64::INFINITY, 1.0, 0.5]);
}

/// The paper's model moves control points 12, 17 and 22 (9 free dofs). A velocity per control
/// point gives each free point its own; a shorter list leaves the points beyond it at rest;
/// a displacement moves the free points only.
#[test]
fn initial_states_from_per_point_velocities_and_a_displacement() {
    let model = support::paper_model(DnurbsOptions::default());
    let velocities: Vec<[f64; 3]> = (0..35).map(|k| [k as f64, 0.5, -1.0]).collect();
    let s = model.initial_state(&velocities, 0.0);
    assert_eq!(s.v, vec![12.0, 0.5, -1.0, 17.0, 0.5, -1.0, 22.0, 0.5, -1.0]);
    let s = model.initial_state(&velocities[..13], 0.0);
    assert_eq!(s.v, vec![12.0, 0.5, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);

    let d = [0.1, -0.2, 0.3];
    let s = model.initial_state_displaced(&[[0.0; 3]], 0.0, d);
    let p = model.full_coordinates(&s.q);
    for k in 0..35 {
        for x in 0..3 {
            let moved = if [12, 17, 22].contains(&k) { d[x] } else { 0.0 };
            assert_eq!(
                p[3 * k + x],
                model.p0()[3 * k + x] + moved,
                "point {k}, {x}"
            );
        }
    }
}

fn paper_with(linear: Vec<LinearConstraint>) -> Result<DnurbsModel, DnurbsError> {
    DnurbsModel::new(
        Geometry::Surface(support::paper_surface()),
        support::paper_material(),
        Loads::default(),
        &Constraints {
            fixed_rings: 2,
            linear,
            ..Constraints::default()
        },
        DnurbsOptions::default(),
    )
}

/// With a constraint whose right-hand side moves the net off its initial shape the reduced
/// coordinates have an offset (`p_f = G q + g`, g ≠ 0): `reduced_coordinates` inverts
/// `full_coordinates` all the same.
#[test]
fn reduced_coordinates_invert_full_coordinates_under_linear_constraints() {
    let z = |k: usize| 3 * k + 2;
    let model = paper_with(vec![
        LinearConstraint {
            terms: vec![(z(12), 1.0), (z(22), 1.0)],
            rhs: 4.5,
        },
        LinearConstraint {
            terms: vec![(3 * 17, 2.0), (3 * 17 + 1, -1.0)],
            rhs: 0.25,
        },
    ])
    .unwrap();
    let n = model.n_free();
    assert_eq!(n, 7);
    let q: Vec<f64> = (0..n).map(|i| 0.1 * i as f64 - 0.2).collect();
    let p = model.full_coordinates(&q);
    assert!((p[z(12)] + p[z(22)] - 4.5).abs() <= tol::SAME);
    assert!((2.0 * p[51] - p[52] - 0.25).abs() <= tol::SAME);
    let back = model.reduced_coordinates(&p);
    assert!(support::max_abs_diff(&back, &q) <= tol::SAME, "{back:?}");
}

/// A constraint on fixed dofs only is checked relative to the size of its terms: with
/// coefficients of 10⁶ on x of point 0 and y of point 1 (both on the fixed ring), a right-hand
/// side off by 10⁻⁶ (10⁻¹² of the terms) is round-off and accepted; off by 1 it contradicts
/// the fixed points and is refused.
#[test]
fn constraints_on_fixed_dofs_are_checked_relative_to_their_terms() {
    let p0 = support::paper_model(DnurbsOptions::default()).p0().to_vec();
    let c = 1e6;
    let exact = c * p0[0] + c * p0[4];
    assert!(exact.abs() > 0.5 * c);
    let with_rhs = |rhs: f64| {
        paper_with(vec![LinearConstraint {
            terms: vec![(0, c), (4, c)],
            rhs,
        }])
    };
    assert!(with_rhs(exact + 1e-6).is_ok());
    match with_rhs(exact + 1.0) {
        Err(DnurbsError::InvalidConstraint { detail }) => {
            assert!(detail.contains("only fixed dofs"), "{detail}")
        }
        other => panic!("expected InvalidConstraint, got {other:?}"),
    }
}

/// The size a fixed-only constraint is measured against is that of its terms `a_i p_i`, not
/// of its coefficients: a coefficient of 10⁶ on x of point 0, which sits at x = 0, adds
/// nothing, so with z of point 0 (= 2) the terms are of size 2 + |b| ≈ 4, and a violation of
/// 10⁻⁶ (2.5·10⁻⁷ of that) is a real conflict with the fixed points; one of 10⁻¹⁵ is round-off.
#[test]
fn fixed_only_constraints_are_measured_by_their_terms_not_their_coefficients() {
    let p0 = support::paper_model(DnurbsOptions::default()).p0().to_vec();
    assert_eq!((p0[0], p0[2]), (0.0, 2.0));
    let with_rhs = |rhs: f64| {
        paper_with(vec![LinearConstraint {
            terms: vec![(0, 1e6), (2, 1.0)],
            rhs,
        }])
    };
    assert!(with_rhs(2.0 + 1e-15).is_ok());
    match with_rhs(2.0 + 1e-6).map(|_| ()) {
        Err(DnurbsError::InvalidConstraint { detail }) => {
            assert!(detail.contains("only fixed dofs"), "{detail}")
        }
        other => panic!("expected InvalidConstraint, got {other:?}"),
    }
}

/// Consistent constraints whose right-hand sides are large and negative (a net placed far from
/// the origin, as georeferenced coordinates are) are accepted, and the shape they give at
/// q = 0 satisfies them to round-off relative to |b|, recomputed here. The particular solution
/// of `0.3 x₁₂ + 0.7 x₁₇ = b`, `0.6 x₁₇ + 0.9 x₂₂ = 0.37 b` carries a residual of about ε|b|
/// (10⁻⁸ at |b| = 4.5·10⁷), which the consistency check must measure against |b|.
#[test]
fn consistent_constraints_with_large_negative_right_hand_sides_are_accepted() {
    let x = |k: usize| 3 * k;
    for b in [-4.5e7, -4.5e8] {
        let rows = vec![
            LinearConstraint {
                terms: vec![(x(12), 0.3), (x(17), 0.7)],
                rhs: b,
            },
            LinearConstraint {
                terms: vec![(x(17), 0.6), (x(22), 0.9)],
                rhs: 0.37 * b,
            },
        ];
        let model = paper_with(rows).unwrap_or_else(|e| panic!("b = {b}: {e}"));
        let p = model.full_coordinates(&vec![0.0; model.n_free()]);
        let r1 = 0.3 * p[x(12)] + 0.7 * p[x(17)] - b;
        let r2 = 0.6 * p[x(17)] + 0.9 * p[x(22)] - 0.37 * b;
        assert!(
            r1.abs().max(r2.abs()) <= tol::SAME * b.abs(),
            "b = {b}: residuals {r1:e}, {r2:e}"
        );
    }
}

#[test]
fn inconsistent_linear_constraints_are_refused() {
    let z12 = 3 * 12 + 2;
    let fix = |rhs: f64| LinearConstraint {
        terms: vec![(z12, 1.0)],
        rhs,
    };
    assert!(paper_with(vec![fix(2.5), fix(2.5)]).is_ok());
    match paper_with(vec![fix(2.5), fix(2.7)]) {
        Err(DnurbsError::InvalidConstraint { detail }) => {
            assert!(detail.contains("inconsistent"), "{detail}")
        }
        other => panic!("expected InvalidConstraint, got {other:?}"),
    }
    // Rows equal to within the rank tolerance but with other right-hand sides are refused too.
    let nearly = LinearConstraint {
        terms: vec![(z12, 1.0 + 1e-14)],
        rhs: 2.7,
    };
    match paper_with(vec![fix(2.5), nearly]) {
        Err(DnurbsError::InvalidConstraint { detail }) => {
            assert!(detail.contains("inconsistent"), "{detail}")
        }
        other => panic!("expected InvalidConstraint, got {other:?}"),
    }
}

/// `max(‖M_g − M_{g+1}‖/‖M_{g+1}‖, ‖K_g − K_{g+1}‖/‖K_{g+1}‖)` for unit coefficients (μ;
/// α11, β11 on a curve; α11, α22, β11, β12, β22 on a surface), recomputed here from the
/// assembled matrices.
fn estimate(geometry: &Geometry, g: usize) -> (f64, f64) {
    let at = |material: &Material, g| {
        let options = DnurbsOptions {
            quadrature_points: Some(g),
            ..DnurbsOptions::default()
        };
        assemble(geometry, material, &Loads::default(), &options).unwrap()
    };
    let rel = |a: &SparseMatrix, b: &SparseMatrix| {
        SparseMatrix::linear_combination(1.0, a, -1.0, b)
            .unwrap()
            .frobenius_norm()
            / b.frobenius_norm()
    };
    let mass = Material {
        mu: 1.0,
        ..Material::default()
    };
    let stiffness = if geometry.is_curve() {
        Material {
            alpha11: 1.0,
            beta11: 1.0,
            ..Material::default()
        }
    } else {
        Material {
            alpha11: 1.0,
            alpha22: 1.0,
            beta11: 1.0,
            beta12: 1.0,
            beta22: 1.0,
            ..Material::default()
        }
    };
    (
        rel(&at(&mass, g).mass, &at(&mass, g + 1).mass),
        rel(
            &at(&stiffness, g).stiffness,
            &at(&stiffness, g + 1).stiffness,
        ),
    )
}

/// The estimated quadrature error of a rational curve (unequal weights: no rule is exact)
/// is the larger of the mass's and the stiffness's changes to the next rule. The largest rule
/// is usable as given, estimated against the one below it.
#[test]
fn quadrature_estimate_of_a_rational_curve_counts_mass_and_stiffness() {
    let k = KnotVector::try_new(vec![0., 0., 0., 0.5, 1., 1., 1.], 2).unwrap();
    let pts = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.5, 0.0],
        [2.0, -0.5, 0.2],
        [3.0, 0.0, 0.0],
    ];
    let curve = Geometry::Curve(NurbsCurve::try_new(k, pts, vec![1.0, 0.3, 2.5, 1.0]).unwrap());
    for g in 2..6 {
        let options = DnurbsOptions {
            quadrature_points: Some(g),
            ..DnurbsOptions::default()
        };
        let choice = options.quadrature_for(&curve).unwrap();
        let (dm, dk) = estimate(&curve, g);
        let expected = dm.max(dk);
        assert!(
            (choice.estimated_error - expected).abs() <= 1e-6 * expected,
            "g = {g}: {} vs {expected} (mass {dm:e}, stiffness {dk:e})",
            choice.estimated_error
        );
        // Measured: the stiffness changes 7–70 times more than the mass at g = 2..5.
        assert!(dk > dm);
    }
    let largest = nurbspring_dnurbs::MAX_QUADRATURE_POINTS;
    let options = DnurbsOptions {
        quadrature_points: Some(largest),
        ..DnurbsOptions::default()
    };
    let choice = options.quadrature_for(&curve).unwrap();
    let (dm, dk) = estimate(&curve, largest - 1);
    assert_eq!(choice.points, largest);
    assert!((choice.estimated_error - dm.max(dk)).abs() <= 1e-3 * dm.max(dk) + 1e-15);
}

/// A free flat patch over `[0, 2] × [0, 3]` moving rigidly with velocity `w`: by the partition
/// of unity `ṗᵀ M ṗ = ∫∫ μ |w|² du dv` (parameter integration, unit square), so the kinetic
/// energy is `½ μ |w|²`; at its initial shape the elastic energy is 0, and after stretching
/// x by 1 % it is the model's own `elastic_energy` of that shape.
#[test]
fn energies_of_a_rigid_motion_by_hand() {
    let model = DnurbsModel::new(
        Geometry::Surface(support::flat_patch(2, 3, 2, 2.0, 3.0)),
        Material {
            mu: 2.0,
            alpha11: 1.0,
            alpha22: 1.0,
            ..Material::default()
        },
        Loads::default(),
        &Constraints::default(),
        DnurbsOptions::default(),
    )
    .unwrap();
    let w = [1.0, -2.0, 0.5];
    let s = model.initial_state(&[w], 0.0);
    let (kinetic, elastic) = model.energies(&s.q, &s.v).unwrap();
    let expected = 0.5 * 2.0 * (1.0 + 4.0 + 0.25);
    assert!(
        (kinetic - expected).abs() <= tol::SAME * expected,
        "{kinetic}"
    );
    assert!(elastic.abs() <= tol::SAME);
    let mut p = model.p0().to_vec();
    for x in p.iter_mut().step_by(3) {
        *x *= 1.01;
    }
    let q = model.reduced_coordinates(&p);
    let (_, stretched) = model.energies(&q, &s.v).unwrap();
    assert!(stretched > 0.0);
    let direct = model.elastic_energy(&p);
    assert!((stretched - direct).abs() <= tol::SAME * direct);
}

/// The load's potential is `−qᵀ f` with `f` the consistent load, so a rigid translation by
/// `w` of a free flat patch over `[0, 2] × [0, 3]` under gravity g and a distributed load
/// `f_d` (parameter integration, unit square) changes it by `−w · (μ g + f_d)` (partition of
/// unity).
#[test]
fn external_potential_of_a_rigid_translation_by_hand() {
    use nurbspring_sim::DynamicModel;
    let (mu, g, f_d) = (2.0, [0.0, 0.5, -9.81], [0.7, -0.2, 0.4]);
    let model = DnurbsModel::new(
        Geometry::Surface(support::flat_patch(2, 3, 2, 2.0, 3.0)),
        Material {
            mu,
            alpha11: 1.0,
            alpha22: 1.0,
            ..Material::default()
        },
        Loads {
            gravity: g,
            distributed: f_d,
            ..Loads::default()
        },
        &Constraints::default(),
        DnurbsOptions::default(),
    )
    .unwrap();
    let w = [1.0, -2.0, 0.5];
    let p0 = model.p0().to_vec();
    let moved: Vec<f64> = p0.iter().enumerate().map(|(d, x)| x + w[d % 3]).collect();
    let (q0, q1) = (
        model.reduced_coordinates(&p0),
        model.reduced_coordinates(&moved),
    );
    let change = model.external_potential(0.0, &q1) - model.external_potential(0.0, &q0);
    let want: f64 = -(0..3).map(|x| w[x] * (mu * g[x] + f_d[x])).sum::<f64>();
    assert!(
        (change - want).abs() <= tol::SAME * want.abs(),
        "{change} vs {want} by hand"
    );
}

/// `simulate` with weights as unknowns steps while `t < t_end − Δt/2`, as `run_until`: with
/// Δt = 0.5 and t_end = 1.25 it stops at t = 1 (2 steps), with t_end = 1.3 it takes a third.
#[test]
fn rational_simulate_runs_to_the_nearest_step() {
    use nurbspring_sim::{IntegratorKind, RunOptions, Sample};
    let model = support::paper_model(DnurbsOptions {
        weights_as_dofs: true,
        ..DnurbsOptions::default()
    });
    for (t_end, steps) in [(1.25, 2), (1.3, 3)] {
        let s = model.initial_state(&[[0.0; 3]], 0.0);
        let opts = RunOptions::new(0.5, t_end, IntegratorKind::TerzopoulosQin);
        let mut times = Vec::new();
        let mut observer = |s: &Sample<'_>| times.push(s.t);
        let summary = model.simulate(s, &opts, &mut observer).unwrap();
        assert_eq!(summary.steps, steps, "t_end = {t_end}");
        assert_eq!(summary.t_final, 0.5 * steps as f64);
        assert_eq!(times.len(), steps + 1);
    }
}

/// `run_until` steps while `t < t_end − Δt/2`: with Δt = 0.5 and t_end = 1.25 it stops at
/// t = 1 (2 steps, the remaining 0.25 is half a step), with t_end = 1.3 it takes a third.
#[test]
fn rational_stepper_runs_to_the_nearest_step() {
    let model = support::paper_model(DnurbsOptions {
        weights_as_dofs: true,
        ..DnurbsOptions::default()
    });
    for (t_end, steps) in [(1.25, 2), (1.3, 3)] {
        let s = model.initial_state(&[[0.0; 3]], 0.0);
        let mut stepper = nurbspring_dnurbs::RationalStepper::new(&model, s, 0.5).unwrap();
        let mut seen = 0;
        stepper.run_until(t_end, |_| seen += 1).unwrap();
        assert_eq!((stepper.steps(), seen), (steps, steps), "t_end = {t_end}");
        assert_eq!(stepper.state().t, 0.5 * steps as f64);
    }
}

/// `assemble_scalar` ignores `weights_as_dofs` (the scalar matrices are of constant weights):
/// the same matrices either way, and `M = S_M ⊗ I₃` against `assemble`.
#[test]
fn scalar_assembly_ignores_weights_as_dofs() {
    let geometry = Geometry::Surface(support::paper_surface());
    let material = support::paper_material();
    let plain = nurbspring_dnurbs::assemble_scalar(&geometry, &material, &DnurbsOptions::default())
        .unwrap();
    let options = DnurbsOptions {
        weights_as_dofs: true,
        ..DnurbsOptions::default()
    };
    let asked = nurbspring_dnurbs::assemble_scalar(&geometry, &material, &options).unwrap();
    assert_eq!(plain.mass.to_dense().data(), asked.mass.to_dense().data());
    assert_eq!(
        plain.stiffness.to_dense().data(),
        asked.stiffness.to_dense().data()
    );
    let full = assemble(
        &geometry,
        &material,
        &Loads::default(),
        &DnurbsOptions::default(),
    )
    .unwrap();
    let (s, m) = (plain.mass.to_dense(), full.mass.to_dense());
    for i in 0..35 {
        for j in 0..35 {
            for x in 0..3 {
                assert!((m[(3 * i + x, 3 * j + x)] - s[(i, j)]).abs() <= 1e-15 * s[(i, i)].abs());
            }
        }
    }
}

/// The same on a rational surface, at rules 2 to 8: every unit term enters the stiffness
/// change (one left out changes it by 10⁻⁴ to 10⁻³ of itself), and the mass the rest.
#[test]
fn quadrature_estimate_of_a_rational_surface_counts_every_term() {
    let surface = Geometry::Surface(support::wavy_rational_patch());
    let (mut mass_larger, mut stiffness_larger) = (false, false);
    for g in 2..9 {
        let options = DnurbsOptions {
            quadrature_points: Some(g),
            ..DnurbsOptions::default()
        };
        let choice = options.quadrature_for(&surface).unwrap();
        let (dm, dk) = estimate(&surface, g);
        let expected = dm.max(dk);
        assert!(
            (choice.estimated_error - expected).abs() <= 1e-6 * expected,
            "g = {g}: {} vs {expected} (mass {dm:e}, stiffness {dk:e})",
            choice.estimated_error
        );
        mass_larger |= dm > 1.1 * dk;
        stiffness_larger |= dk > 1.1 * dm;
    }
    // On this patch each of the two decides the estimate at some rule (measured: the mass at
    // g = 4, 5; the stiffness at g = 6, 7), so neither can be dropped unseen.
    assert!(mass_larger && stiffness_larger);
}

/// The modal solution is refused for a damped material, naming γ, and accepted undamped;
/// with weights as unknowns only the Terzopoulos–Qin step runs.
#[test]
fn which_integrators_a_material_admits() {
    use nurbspring_dnurbs::{DnurbsOptions, Material, MaterialModel, integrator_problem};
    use nurbspring_sim::IntegratorKind;
    let damped = MaterialModel::TensionPlate(Material {
        gamma: 0.25,
        ..Material::default()
    });
    let why = integrator_problem(IntegratorKind::Modal, &damped, &DnurbsOptions::default())
        .expect("a damped model has no modal solution");
    assert!(why.contains("material.gamma = 0.25"), "{why}");
    let undamped = MaterialModel::TensionPlate(Material::default());
    assert_eq!(undamped.gamma(), 0.0);
    assert_eq!(
        integrator_problem(IntegratorKind::Modal, &undamped, &DnurbsOptions::default()),
        None
    );
    let rational = DnurbsOptions {
        weights_as_dofs: true,
        ..DnurbsOptions::default()
    };
    assert!(integrator_problem(IntegratorKind::Newmark, &undamped, &rational).is_some());
    assert_eq!(
        integrator_problem(IntegratorKind::TerzopoulosQin, &undamped, &rational),
        None
    );
}
