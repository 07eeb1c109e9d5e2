//! Constraints (docs/math.md §4): rings, fixed dofs in the initial state, linear constraints checked
//! against a Lagrange-multiplier solution.

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, LinearConstraint, Loads, outer_ring_points,
};
use nurbspring_linalg::{DenseMatrix, solve_dense};
use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Sample, simulate};

use crate::support::{self, tol};

#[test]
fn rings_and_initial_state() {
    assert_eq!(outer_ring_points(7, 5, 1).len(), 20);
    assert_eq!(outer_ring_points(7, 5, 3).len(), 35);
    assert_eq!(outer_ring_points(5, 1, 2), vec![0, 1, 3, 4]);
    assert!(outer_ring_points(7, 5, 0).is_empty());
    let model = support::paper_model(DnurbsOptions::default());
    assert_eq!(model.fixed_points().len(), 32);
    assert_eq!(model.dof_map().n_free(), 9);
    let s = model.initial_state(&[[0.1, 0.2, -0.2]], 0.0);
    assert_eq!(s.v, [0.1, 0.2, -0.2].repeat(3));
    let v = model.full_velocity(&s.v);
    for &k in model.fixed_points() {
        assert_eq!(&v[3 * k..3 * k + 3], &[0.0; 3]);
    }
    assert_eq!(model.full_coordinates(&s.q), model.p0());
    // With weights as dofs, the weights of every point are free except the gauge one.
    let m4 = support::paper_model(DnurbsOptions {
        weights_as_dofs: true,
        ..DnurbsOptions::default()
    });
    assert_eq!(m4.gauge_weight(), Some(3));
    assert_eq!(m4.n_free(), 9 + 34);
    let s4 = m4.initial_state(&[[0.0, 0.0, -0.2]], 0.1);
    assert_eq!(s4.v.len(), 43);
}

/// Steady state under gravity with the centre points' z tied together (z_12 = z_22) and the
/// middle one held at a given height, checked against the KKT system with multipliers.
#[test]
fn linear_constraints_match_lagrange_multipliers() {
    let z = |k: usize| 3 * k + 2;
    let constraints = Constraints {
        fixed_rings: 2,
        linear: vec![
            LinearConstraint {
                terms: vec![(z(12), 1.0), (z(22), -1.0)],
                rhs: 0.0,
            },
            LinearConstraint {
                terms: vec![(3 * 17, 1.0), (3 * 17 + 1, 1.0)],
                rhs: 1.5 + 2.5 + 0.01,
            },
        ],
        ..Constraints::default()
    };
    let loads = Loads {
        gravity: [0.0, 0.0, -9.81],
        ..Loads::default()
    };
    let model = DnurbsModel::new(
        Geometry::Surface(support::paper_surface()),
        support::paper_material(),
        loads,
        &constraints,
        DnurbsOptions::default(),
    )
    .unwrap();
    assert!(model.has_linear_constraints());
    assert_eq!(model.n_free(), 9 - 2);
    let p = model.steady_state().unwrap();
    assert!((p[z(12)] - p[z(22)]).abs() <= tol::SAME);
    assert!((p[51] + p[52] - 4.01).abs() <= tol::SAME);
    // KKT on the 9 free dofs: [K_ff Aᵀ; A 0] [d; λ] = [f_f − K_fc d_c; b − A p_rest].
    let free = model.dof_map().free().to_vec();
    let k = model
        .matrices()
        .stiffness
        .submatrix(&free, &free)
        .to_dense();
    let n = free.len();
    let mut a = DenseMatrix::zeros(n + 2, n + 2);
    for i in 0..n {
        for j in 0..n {
            a[(i, j)] = k[(i, j)];
        }
    }
    let pos = |d: usize| free.iter().position(|&f| f == d).unwrap();
    let rows = [[(z(12), 1.0), (z(22), -1.0)], [(51, 1.0), (52, 1.0)]];
    let rhs_c = [0.0, 4.01];
    let mut b = vec![0.0; n + 2];
    for (r, terms) in rows.iter().enumerate() {
        let mut at_rest = 0.0;
        for &(d, c) in terms {
            a[(n + r, pos(d))] = c;
            a[(pos(d), n + r)] = c;
            at_rest += c * model.p_rest()[d];
        }
        b[n + r] = rhs_c[r] - at_rest;
    }
    for i in 0..n {
        b[i] = model.matrices().force[free[i]];
    }
    let x = solve_dense(&a, &b).unwrap();
    for i in 0..n {
        let d = free[i];
        assert!(
            (p[d] - (model.p_rest()[d] + x[i])).abs() <= tol::SAME,
            "dof {d}"
        );
    }
    // The constraints hold along a motion too.
    let initial = model.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
    let mut worst: f64 = 0.0;
    let mut observer = |s: &Sample<'_>| {
        let p = model.full_coordinates(s.q);
        worst = worst.max((p[z(12)] - p[z(22)]).abs());
    };
    simulate(
        &model,
        initial,
        &RunOptions::new(0.05, 1.0, IntegratorKind::Newmark),
        &mut observer,
    )
    .unwrap();
    assert!(worst <= tol::SAME, "{worst:e}");
    assert_eq!(model.n_dofs(), 7);
}
