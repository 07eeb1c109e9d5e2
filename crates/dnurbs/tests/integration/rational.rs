//! Weights as unknowns (SPEC §3, last bullet): with the weights fixed the stepper reproduces
//! the constant-weight motion; with free weights it converges as Δt → 0.

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, RationalStepper,
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
        support::paper_material(),
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
