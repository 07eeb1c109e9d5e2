//! Weights as unknowns (docs/math.md §3, last bullet): with the weights fixed the stepper reproduces
//! the constant-weight motion; with free weights it converges as Δt → 0.

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material, RationalStepper,
};
use nurbspring_sim::{IntegratorKind, make_stepper};

use crate::support::{self, tol};

fn model(
    weights_as_dofs: bool,
    fixed_weights: bool,
    surface: nurbspring_geom::NurbsSurface,
    rings: usize,
) -> DnurbsModel {
    DnurbsModel::new(
        Geometry::Surface(surface),
        // Damped, to cover the D terms of both schemes.
        Material {
            gamma: 0.5,
            ..support::paper_material()
        },
        Loads {
            gravity: [0.0, 0.0, -0.5],
            ..Loads::default()
        },
        &Constraints {
            fixed_weights,
            fixed_rings: rings,
            ..Constraints::default()
        },
        DnurbsOptions {
            weights_as_dofs,
            ..DnurbsOptions::default()
        },
    )
    .unwrap()
}

/// Full coordinates after `steps` steps of the rational stepper.
fn run_rational(model: &DnurbsModel, dt: f64, steps: usize, weight_velocity: f64) -> Vec<f64> {
    let initial = model.initial_state(&[[0.0, 0.0, -0.2]], weight_velocity);
    let mut stepper = RationalStepper::new(model, initial, dt).unwrap();
    for _ in 0..steps {
        stepper.step().unwrap();
    }
    stepper.full_coordinates().to_vec()
}

#[test]
fn fixed_weights_reproduce_the_constant_weight_motion() {
    let surface = support::wavy_rational_patch();
    let constant = model(false, false, surface.clone(), 1);
    let with_weights = model(true, true, surface, 1);
    assert_eq!(with_weights.gauge_weight(), None);
    let (dt, steps) = (0.02, 60);
    // Reference: sim's Terzopoulos–Qin on the constant-weight model.
    let mut state = constant.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
    let mut tq = make_stepper(IntegratorKind::TerzopoulosQin, &constant, &state, dt).unwrap();
    for _ in 0..steps {
        tq.step(&constant, &mut state, dt).unwrap();
    }
    let reference = constant.full_coordinates(&state.q);
    // The rational stepper on the constant-weight model is the same scheme.
    let p3 = run_rational(&constant, dt, steps, 0.0);
    let scale = reference.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(
        support::max_abs_diff(&p3, &reference) <= tol::SCHEME_ROUNDOFF * scale,
        "{:e}",
        support::max_abs_diff(&p3, &reference)
    );
    // With four dofs and every weight fixed, the xyz part is the same motion.
    let p4 = run_rational(&with_weights, dt, steps, 0.0);
    let xyz: Vec<f64> = p4
        .chunks_exact(4)
        .flat_map(|c| [c[0], c[1], c[2]])
        .collect();
    assert!(
        support::max_abs_diff(&xyz, &reference) <= tol::SCHEME_ROUNDOFF * scale,
        "{:e}",
        support::max_abs_diff(&xyz, &reference)
    );
    assert!(
        p4.chunks_exact(4)
            .zip(with_weights.geometry().weights())
            .all(|(c, &w)| c[3] == w)
    );
}

#[test]
fn free_weights_converge_as_the_step_shrinks() {
    // Free weights, excited by an initial weight velocity; compare with a fine reference.
    let m = model(true, false, support::paper_surface(), 2);
    assert!(m.gauge_weight().is_some());
    let t_end = 0.8;
    let wv = 0.5;
    let steps = |dt: f64| (t_end / dt).round() as usize;
    let reference = run_rational(&m, 0.000625, steps(0.000625), wv);
    let coarse = run_rational(&m, 0.02, steps(0.02), wv);
    let fine = run_rational(&m, 0.01, steps(0.01), wv);
    let e_coarse = support::max_abs_diff(&coarse, &reference);
    let e_fine = support::max_abs_diff(&fine, &reference);
    // The weights really moved.
    let w_moved = reference
        .chunks_exact(4)
        .map(|c| (c[3] - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(w_moved > 0.1, "weights moved by {w_moved}");
    // The reference itself carries a first-order error of ~ e_fine / 16; allow for it.
    let r = support::rate(e_coarse, e_fine);
    eprintln!(
        "free weights: errors {e_coarse:e} (dt 0.02), {e_fine:e} (dt 0.01), rate {r:.3}, max |w − 1| = {w_moved:.3}"
    );
    assert!(
        (r - 1.0).abs() <= tol::RATE_SLACK,
        "errors {e_coarse:e}, {e_fine:e}, rate {r}"
    );
}

#[test]
fn weights_stay_above_the_floor() {
    let m = model(true, false, support::paper_surface(), 2);
    let initial = m.initial_state(&[[0.0; 3]], -20.0);
    let mut stepper = RationalStepper::new(&m, initial, 0.05)
        .unwrap()
        .with_min_weight(0.05)
        .unwrap();
    for _ in 0..20 {
        stepper.step().unwrap();
        let min_w = stepper
            .full_coordinates()
            .chunks_exact(4)
            .map(|c| c[3])
            .fold(f64::INFINITY, f64::min);
        assert!(min_w >= 0.05, "{min_w}");
    }
    assert_eq!(stepper.steps(), 20);
    assert!((stepper.state().t - 1.0).abs() < 1e-12);
}

/// The frozen 4-dof model (matrices at p(0)) is SPD on its free dofs thanks to the gauge
/// weight, so the sim integrators and the modes apply to it too.
#[test]
fn frozen_weights_as_dofs_model_is_positive_definite() {
    let m = model(true, false, support::paper_surface(), 2);
    assert!(nurbspring_linalg::SpdSolver::new(m.reduced_mass()).is_ok());
    let modes = m.modes(5).unwrap();
    assert!(modes.omega.iter().all(|w| w.is_finite() && *w >= 0.0));
    let state = m.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
    let mut s = state.clone();
    let mut newmark = make_stepper(IntegratorKind::Newmark, &m, &state, 0.08).unwrap();
    for _ in 0..10 {
        newmark.step(&m, &mut s, 0.08).unwrap();
    }
    assert!(s.q.iter().all(|v| v.is_finite()));
}

/// An independent reference for the free-weight motion: RK4 on the continuous equation
/// `M(p) p̈ = f(p) − K(p)(p − p_rest) − D(p) ṗ − I(p, ṗ) ṗ` (paper eq. (2)) with
/// `I ṗ = ∫∫ μ Jᵀ J̇ ṗ` and `J̇ ṗ` by a central difference of `J(p + ε ṗ) ṗ` (docs/math.md §3), on the same
/// free dofs (gauge weight pinned). The rational stepper must converge to it at first order:
/// an inconsistent treatment of `I ṗ` would converge (to itself) but not to this.
#[test]
fn free_weights_converge_to_an_independent_rk4_reference() {
    use nurbspring_dnurbs::assemble;
    use nurbspring_geom::{Deriv, surface_rule};
    use nurbspring_linalg::{DenseMatrix, cholesky_solve_dense};

    let m = model(true, false, support::paper_surface(), 2);
    let options = m.options().clone();
    let free = m.dof_map().free().to_vec();
    let n = m.p0().len();
    let surface = match m.geometry() {
        Geometry::Surface(s) => s.clone(),
        Geometry::Curve(_) => unreachable!(),
    };
    let rule = surface_rule(
        surface.basis_u(),
        surface.basis_v(),
        options.quadrature_points.unwrap(),
    )
    .unwrap();
    let acceleration = |p: &[f64], v: &[f64]| -> Vec<f64> {
        let geo = m.geometry().with_coordinates(p, true).unwrap();
        let mats = assemble(&geo, m.material(), m.loads(), &options).unwrap();
        let mut rhs = mats.force.clone();
        let d: Vec<f64> = p.iter().zip(m.p_rest()).map(|(a, b)| a - b).collect();
        mats.stiffness.mul_vec_add(-1.0, &d, &mut rhs);
        mats.damping.mul_vec_add(-1.0, v, &mut rhs);
        // −I ṗ = −∫∫ μ Jᵀ (J̇ ṗ).
        let eps = 1e-6;
        let plus: Vec<f64> = p.iter().zip(v).map(|(a, b)| a + eps * b).collect();
        let minus: Vec<f64> = p.iter().zip(v).map(|(a, b)| a - eps * b).collect();
        let geo_p = m.geometry().with_coordinates(&plus, true).unwrap();
        let geo_m = m.geometry().with_coordinates(&minus, true).unwrap();
        for el in &rule {
            for q in &el.points {
                let jv_p = geo_p
                    .jacobian(q.u, q.v, 0, true)
                    .unwrap()
                    .apply(Deriv::Value, v);
                let jv_m = geo_m
                    .jacobian(q.u, q.v, 0, true)
                    .unwrap()
                    .apply(Deriv::Value, v);
                let jdot_v: [f64; 3] = std::array::from_fn(|x| (jv_p[x] - jv_m[x]) / (2.0 * eps));
                let j = geo.jacobian(q.u, q.v, 0, true).unwrap();
                j.apply_transpose_add(Deriv::Value, jdot_v, -m.material().mu * q.weight, &mut rhs);
            }
        }
        let mff = DenseMatrix::from_fn(free.len(), free.len(), |i, j| {
            mats.mass.get(free[i], free[j])
        });
        let rhs_f: Vec<f64> = free.iter().map(|&d| rhs[d]).collect();
        let a_f = cholesky_solve_dense(&mff, &rhs_f).unwrap();
        let mut a = vec![0.0; n];
        for (i, &d) in free.iter().enumerate() {
            a[d] = a_f[i];
        }
        a
    };
    let (t_end, wv): (f64, f64) = (0.4, 0.5);
    // RK4 reference.
    let s0 = m.initial_state(&[[0.0, 0.0, -0.2]], wv);
    let mut p = m.full_coordinates(&s0.q);
    let mut v = m.full_velocity(&s0.v);
    let h: f64 = 0.004;
    for _ in 0..(t_end / h).round() as usize {
        let axpy = |x: &[f64], a: f64, y: &[f64]| -> Vec<f64> {
            x.iter().zip(y).map(|(x, y)| x + a * y).collect()
        };
        let k1v = acceleration(&p, &v);
        let k1p = v.clone();
        let (p2, v2) = (axpy(&p, 0.5 * h, &k1p), axpy(&v, 0.5 * h, &k1v));
        let k2v = acceleration(&p2, &v2);
        let (p3, v3) = (axpy(&p, 0.5 * h, &v2), axpy(&v, 0.5 * h, &k2v));
        let k3v = acceleration(&p3, &v3);
        let (p4, v4) = (axpy(&p, h, &v3), axpy(&v, h, &k3v));
        let k4v = acceleration(&p4, &v4);
        for i in 0..n {
            p[i] += h / 6.0 * (k1p[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            v[i] += h / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
        }
    }
    let steps = |dt: f64| (t_end / dt).round() as usize;
    let errors: Vec<f64> = [0.02, 0.01, 0.005]
        .iter()
        .map(|&dt| support::max_abs_diff(&run_rational(&m, dt, steps(dt), wv), &p))
        .collect();
    let r1 = support::rate(errors[0], errors[1]);
    let r2 = support::rate(errors[1], errors[2]);
    eprintln!("free weights vs RK4 reference: errors {errors:?}, rates {r1:.3}, {r2:.3}");
    assert!(
        (r2 - 1.0).abs() <= tol::RATE_SLACK,
        "errors {errors:?}, rates {r1}, {r2}"
    );
}
