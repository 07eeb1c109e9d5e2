//! Integration tests of nurbspring-sim: closed-form solutions, convergence orders, energy,
//! stability limits, divergence, cancellation, dof maps.

mod support;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_linalg::{DenseMatrix, SparseMatrix, SpdSolver};
use nurbspring_sim::*;
use support::{
    Chain, DoubleWell, Duffing, Opaque, assert_order, initial_positions, initial_velocities,
    max_abs_diff, tol,
};

/// Runs `simulate` and returns the final state.
fn run(
    model: &dyn DynamicModel,
    kind: IntegratorKind,
    q0: &[f64],
    v0: &[f64],
    dt: f64,
    t_end: f64,
) -> State {
    let opts = RunOptions::new(dt, t_end, kind);
    run_with(model, q0, v0, &opts).unwrap()
}

fn run_with(
    model: &dyn DynamicModel,
    q0: &[f64],
    v0: &[f64],
    opts: &RunOptions,
) -> Result<State, SimError> {
    let mut last = State::new(q0.to_vec(), v0.to_vec());
    let mut obs = |s: &Sample<'_>| {
        last.t = s.t;
        last.q.copy_from_slice(s.q);
        last.v.copy_from_slice(s.v);
    };
    simulate(model, State::new(q0.to_vec(), v0.to_vec()), opts, &mut obs)?;
    Ok(last)
}

fn chain() -> Chain {
    Chain {
        n: 8,
        k: 3.0,
        m: 0.5,
    }
}

/// Equilibrium `rest + K⁻¹ f` of a linear model.
fn equilibrium(model: &LinearModel) -> Vec<f64> {
    let u = SpdSolver::new(&model.stiffness)
        .unwrap()
        .solve(&model.force);
    u.iter().zip(&model.rest).map(|(a, b)| a + b).collect()
}

fn loaded_chain_model(c: &Chain) -> LinearModel {
    let mut model = c.model();
    model.rest = (0..c.n).map(|i| 0.1 * i as f64).collect();
    model.force = (0..c.n).map(|i| 0.4 - 0.1 * i as f64).collect();
    model
}

// ------------------------------------------------------------------ names and validation

#[test]
fn integrator_names_round_trip() {
    for kind in IntegratorKind::ALL {
        assert_eq!(IntegratorKind::parse(kind.name()), Some(kind));
    }
    assert_eq!(
        IntegratorKind::parse("velocity-verlet"),
        Some(IntegratorKind::VelocityVerlet)
    );
    assert_eq!(IntegratorKind::parse("euler"), None);
    // `central-difference` names Verlet (an alias, as in scenes); generalized-α by its name.
    for (name, kind) in [
        ("central-difference", IntegratorKind::VelocityVerlet),
        ("Central_Difference", IntegratorKind::VelocityVerlet),
        ("velocity-verlet", IntegratorKind::VelocityVerlet),
        ("generalized-alpha", IntegratorKind::GeneralizedAlpha),
    ] {
        assert_eq!(IntegratorKind::parse(name), Some(kind), "{name}");
        if !name.contains('_') && !name.contains('C') {
            use serde::Deserialize;
            let de = serde::de::value::StrDeserializer::<serde::de::value::Error>::new(name);
            assert_eq!(IntegratorKind::deserialize(de).unwrap(), kind, "{name}");
        }
    }
    assert_eq!(IntegratorKind::GeneralizedAlpha.name(), "generalized-alpha");
    assert_eq!(IntegratorKind::VelocityVerlet.name(), "verlet");
    let explicit: Vec<_> = IntegratorKind::ALL
        .into_iter()
        .filter(|k| k.is_explicit())
        .collect();
    assert_eq!(
        explicit,
        vec![
            IntegratorKind::SymplecticEuler,
            IntegratorKind::VelocityVerlet,
            IntegratorKind::Rk4
        ]
    );
}

#[test]
fn invalid_inputs_are_rejected() {
    let c = chain();
    let model = c.model();
    let q0 = initial_positions(c.n);
    let v0 = vec![0.0; c.n];
    for dt in [0.0, -1.0, f64::NAN] {
        let e = run_with(
            &model,
            &q0,
            &v0,
            &RunOptions::new(dt, 1.0, IntegratorKind::Newmark),
        )
        .unwrap_err();
        assert!(matches!(e, SimError::InvalidTimeStep { .. }));
    }
    let e = run_with(
        &model,
        &q0,
        &v0,
        &RunOptions::new(0.1, f64::INFINITY, IntegratorKind::Newmark),
    )
    .unwrap_err();
    assert!(matches!(e, SimError::InvalidDuration { .. }));
    let e = run_with(
        &model,
        &q0[..3],
        &v0[..3],
        &RunOptions::new(0.1, 1.0, IntegratorKind::Newmark),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        SimError::DimensionMismatch {
            expected: 8,
            found: 3,
            ..
        }
    ));
    // Unsupported combinations.
    let duffing = Duffing::new(&c, 1.0);
    let s = State::new(q0.clone(), v0.clone());
    for kind in [IntegratorKind::TerzopoulosQin, IntegratorKind::Modal] {
        assert!(matches!(
            make_stepper(kind, &duffing, &s, 0.01),
            Err(SimError::NotSupported { .. })
        ));
    }
    let mut damped = c.model();
    damped.damping = Some(SystemMatrix::Diagonal(vec![0.1; c.n]));
    assert!(matches!(
        make_stepper(IntegratorKind::Modal, &damped, &s, 0.01),
        Err(SimError::NotSupported { .. })
    ));
    // A consistent (non-diagonal) mass is factored by the explicit schemes and accepted by the
    // implicit ones (tests/consistent_mass.rs); one that is not positive definite by none.
    let mut consistent = c.model();
    consistent.mass = SystemMatrix::Sparse(
        SparseMatrix::linear_combination(0.5, &SparseMatrix::identity(c.n), 0.01, &c.stiffness())
            .unwrap(),
    );
    for kind in IntegratorKind::ALL {
        if kind != IntegratorKind::Modal {
            assert!(make_stepper(kind, &consistent, &s, 0.01).is_ok(), "{kind}");
        }
    }
    run(&consistent, IntegratorKind::Newmark, &q0, &v0, 0.05, 0.5);
    let mut indefinite = c.model();
    indefinite.mass = SystemMatrix::Sparse(
        SparseMatrix::linear_combination(0.5, &SparseMatrix::identity(c.n), -0.2, &c.stiffness())
            .unwrap(),
    );
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
    ] {
        assert!(matches!(
            make_stepper(kind, &indefinite, &s, 0.01),
            Err(SimError::NotSupported { .. })
        ));
    }
}

// ------------------------------------------------------------------ exact and energy

#[test]
fn modal_integrator_equals_closed_form() {
    let c = chain();
    let model = loaded_chain_model(&c);
    let q_eq = equilibrium(&model);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let dt = 0.05;
    let mut worst = 0.0_f64;
    let mut obs =
        |s: &Sample<'_>| worst = worst.max(max_abs_diff(s.q, &c.exact(&q_eq, &q0, &v0, s.t)));
    let summary = simulate(
        &model,
        State::new(q0.clone(), v0.clone()),
        &RunOptions::new(dt, 20.0, IntegratorKind::Modal),
        &mut obs,
    )
    .unwrap();
    assert_eq!(summary.steps, 400);
    assert!(worst < tol::MODAL, "modal vs closed form: {worst:e}");
}

#[test]
fn newmark_conserves_energy_without_damping() {
    let c = chain();
    let model = loaded_chain_model(&c);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let mut energies = Vec::new();
    let mut obs = |s: &Sample<'_>| energies.push(s.kinetic + s.potential);
    simulate(
        &model,
        State::new(q0, v0),
        &RunOptions::new(0.1, 200.0, IntegratorKind::Newmark),
        &mut obs,
    )
    .unwrap();
    assert_eq!(energies.len(), 2001);
    let e0 = energies[0];
    let drift = energies.iter().fold(0.0_f64, |m, e| m.max((e - e0).abs())) / e0.abs();
    assert!(
        drift < tol::ENERGY_ROUNDOFF,
        "Newmark energy drift {drift:e}"
    );
}

#[test]
fn observer_sees_initial_state_and_every_step() {
    let c = chain();
    let model = c.model();
    let q0 = initial_positions(c.n);
    let mut steps = Vec::new();
    let mut obs = |s: &Sample<'_>| steps.push((s.step, s.t));
    let summary = simulate(
        &model,
        State::new(q0, vec![0.0; c.n]),
        &RunOptions::new(0.1, 1.0, IntegratorKind::BackwardEuler),
        &mut obs,
    )
    .unwrap();
    assert_eq!(summary.steps, 10);
    assert!((summary.t_final - 1.0).abs() < 1e-15);
    assert_eq!(steps.len(), 11);
    assert_eq!(steps[0], (0, 0.0));
    assert!(
        steps
            .iter()
            .enumerate()
            .all(|(k, &(s, t))| s == k && (t - 0.1 * k as f64).abs() < 1e-15)
    );
    assert_eq!(summary.omega_max, None);
}

/// The energies of every sample, recomputed by hand from the sample's own state on the loaded
/// chain: kinetic `½ m Σ vᵢ²`, elastic `½ k Σ (differences of u = q − rest, with the fixed
/// ends)²`, external `−qᵀ f`, potential = elastic + external.
#[test]
fn samples_carry_the_energies_of_their_state() {
    let c = chain();
    let model = loaded_chain_model(&c);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let mut seen = 0;
    let mut obs = |s: &Sample<'_>| {
        let kinetic = 0.5 * c.m * s.v.iter().map(|v| v * v).sum::<f64>();
        let u: Vec<f64> = s.q.iter().zip(&model.rest).map(|(q, r)| q - r).collect();
        let mut stretch = u[0] * u[0] + u[c.n - 1] * u[c.n - 1];
        for i in 0..c.n - 1 {
            stretch += (u[i + 1] - u[i]).powi(2);
        }
        let elastic = 0.5 * c.k * stretch;
        let external =
            -s.q.iter()
                .zip(&model.force)
                .map(|(q, f)| q * f)
                .sum::<f64>();
        let scale = kinetic + elastic + external.abs();
        for (name, got, want) in [
            ("kinetic", s.kinetic, kinetic),
            ("elastic", s.elastic, elastic),
            ("external", s.external, external),
            ("potential", s.potential, elastic + external),
        ] {
            assert!(
                (got - want).abs() <= tol::EXACT * scale,
                "step {}: {name} {got} vs {want} by hand",
                s.step
            );
        }
        seen += 1;
    };
    simulate(
        &model,
        State::new(q0, v0),
        &RunOptions::new(0.1, 1.0, IntegratorKind::Newmark),
        &mut obs,
    )
    .unwrap();
    assert_eq!(seen, 11);
}

/// `step_count` is `⌈(t_end − t₀)/Δt⌉` from any start, not only from 0.
#[test]
fn step_count_by_hand_from_a_non_zero_start() {
    assert_eq!(step_count(1.0, 2.0, 0.25), 4);
    assert_eq!(step_count(1.0, 2.1, 0.25), 5);
    assert_eq!(step_count(-1.0, 0.5, 0.5), 3);
    assert_eq!(step_count(3.0, 3.0, 0.1), 0);
    assert_eq!(step_count(3.0, 2.0, 0.1), 0);
    // (0.3 − 0.1)/0.1 is 1.9999999999999998 in f64: within 1e-9 of 2, so 2 steps.
    assert_eq!(step_count(0.1, 0.3, 0.1), 2);
}

/// The modal stepper's eigenvalues are the chain's `ω_j²` (closed form), ascending.
#[test]
fn modal_eigenvalues_are_the_squared_chain_frequencies() {
    let c = chain();
    let model = c.model();
    let modal = integrators::Modal::new(&model, 0.05).unwrap();
    let lambda = modal.eigenvalues();
    assert_eq!(lambda.len(), c.n);
    let top = c.omega(c.n).powi(2);
    for (j, &l) in lambda.iter().enumerate() {
        let want = c.omega(j + 1).powi(2);
        assert!(
            (l - want).abs() <= tol::MODAL * top,
            "λ_{} = {l}, closed form {want}",
            j + 1
        );
    }
}

// ------------------------------------------------------------------ Terzopoulos–Qin

#[test]
fn terzopoulos_qin_amplification_per_step() {
    // Single dof, M = 1, K = ω²: each step multiplies the mode by (1 + ω²Δt²)^(-1/2). For the
    // two-term recurrence, D_n = q_{n+1} q_{n-1} − q_n² scales by the product of the roots = r².
    let omega: f64 = 2.0;
    let dt = 0.1;
    let model = LinearModel::new(
        SystemMatrix::Diagonal(vec![1.0]),
        SparseMatrix::from_diagonal(&[omega * omega]),
    );
    let mut state = State::new(vec![1.0], vec![0.3]);
    let mut stepper = make_stepper(IntegratorKind::TerzopoulosQin, &model, &state, dt).unwrap();
    let mut q = vec![state.q[0] - dt * state.v[0], state.q[0]];
    for _ in 0..30 {
        stepper.step(&model, &mut state, dt).unwrap();
        q.push(state.q[0]);
    }
    let r2 = 1.0 / (1.0 + omega * omega * dt * dt);
    for n in 1..q.len() - 2 {
        let d0 = q[n + 1] * q[n - 1] - q[n] * q[n];
        let d1 = q[n + 2] * q[n] - q[n + 1] * q[n + 1];
        assert!(
            (d1 / d0 - r2).abs() < tol::AMPLIFICATION,
            "step {n}: {} vs {r2}",
            d1 / d0
        );
    }
    // The amplitude decays: TQ is dissipative.
    assert!(q.last().unwrap().abs() < 1.0);
}

#[test]
fn terzopoulos_qin_converges_at_first_order_to_modal() {
    let c = chain();
    let model = loaded_chain_model(&c);
    let q_eq = equilibrium(&model);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let t_end = 1.0;
    let exact = c.exact(&q_eq, &q0, &v0, t_end);
    let modal = run(&model, IntegratorKind::Modal, &q0, &v0, 0.01, t_end);
    assert!(max_abs_diff(&modal.q, &exact) < tol::MODAL);
    let err = |dt: f64| {
        max_abs_diff(
            &run(&model, IntegratorKind::TerzopoulosQin, &q0, &v0, dt, t_end).q,
            &modal.q,
        )
    };
    let (e1, e2, e3) = (err(0.004), err(0.002), err(0.001));
    assert_order("terzopoulos-qin", e1 / e2, 1);
    assert_order("terzopoulos-qin", e2 / e3, 1);
}

#[test]
fn terzopoulos_qin_with_damping_reaches_the_static_equilibrium() {
    let c = chain();
    let mut model = loaded_chain_model(&c);
    model.damping = Some(SystemMatrix::Diagonal(vec![2.0; c.n]));
    let q_eq = equilibrium(&model);
    let end = run(
        &model,
        IntegratorKind::TerzopoulosQin,
        &initial_positions(c.n),
        &initial_velocities(c.n),
        0.05,
        200.0,
    );
    assert!(
        max_abs_diff(&end.q, &q_eq) < 1e-10,
        "{:e}",
        max_abs_diff(&end.q, &q_eq)
    );
}

// ------------------------------------------------------------------ convergence orders (linear)

fn order_on_chain(kind: IntegratorKind, dts: [f64; 3], order: i32) {
    let c = chain();
    let model = loaded_chain_model(&c);
    let q_eq = equilibrium(&model);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let t_end = 1.0;
    let exact = c.exact(&q_eq, &q0, &v0, t_end);
    let err = |dt: f64| max_abs_diff(&run(&model, kind, &q0, &v0, dt, t_end).q, &exact);
    let e: Vec<f64> = dts.iter().map(|&dt| err(dt)).collect();
    assert_order(kind.name(), e[0] / e[1], order);
    assert_order(kind.name(), e[1] / e[2], order);
}

#[test]
fn rk4_converges_at_fourth_order() {
    order_on_chain(IntegratorKind::Rk4, [0.04, 0.02, 0.01], 4);
}

#[test]
fn backward_euler_converges_at_first_order() {
    order_on_chain(IntegratorKind::BackwardEuler, [0.004, 0.002, 0.001], 1);
}

#[test]
fn newmark_converges_at_second_order() {
    order_on_chain(IntegratorKind::Newmark, [0.04, 0.02, 0.01], 2);
}

#[test]
fn verlet_converges_at_second_order_and_symplectic_euler_at_first() {
    order_on_chain(IntegratorKind::VelocityVerlet, [0.04, 0.02, 0.01], 2);
    order_on_chain(IntegratorKind::SymplecticEuler, [0.004, 0.002, 0.001], 1);
}

// ------------------------------------------------------------------ velocities

/// The velocity each scheme returns against `q̇` of the closed form, with the scheme's order
/// (the velocity of every scheme here converges at the order of its positions).
fn velocity_order_on_chain(kind: IntegratorKind, dts: [f64; 3], order: i32) {
    let c = chain();
    let model = loaded_chain_model(&c);
    let q_eq = equilibrium(&model);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let t_end = 1.0;
    let exact = c.exact_velocity(&q_eq, &q0, &v0, t_end);
    let err = |dt: f64| max_abs_diff(&run(&model, kind, &q0, &v0, dt, t_end).v, &exact);
    let e: Vec<f64> = dts.iter().map(|&dt| err(dt)).collect();
    assert_order(&format!("{} velocity", kind.name()), e[0] / e[1], order);
    assert_order(&format!("{} velocity", kind.name()), e[1] / e[2], order);
}

#[test]
fn the_closed_form_velocity_is_the_derivative_of_the_closed_form_position() {
    // Checks the reference itself: central differences of `exact` in t (h = 1e-4, error
    // ~ h² |q⃛| ≈ 1e-8 · ω³ ≲ 1e-6 for ω_max ≈ 4.9).
    let c = chain();
    let model = loaded_chain_model(&c);
    let q_eq = equilibrium(&model);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let h = 1e-4;
    for t in [0.0, 0.37, 1.0] {
        let (qp, qm) = (
            c.exact(&q_eq, &q0, &v0, t + h),
            c.exact(&q_eq, &q0, &v0, t - h),
        );
        let fd: Vec<f64> = qp
            .iter()
            .zip(&qm)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        assert!(max_abs_diff(&fd, &c.exact_velocity(&q_eq, &q0, &v0, t)) < 1e-6);
    }
    assert!(max_abs_diff(&c.exact_velocity(&q_eq, &q0, &v0, 0.0), &v0) < tol::EXACT);
}

#[test]
fn modal_velocity_equals_the_closed_form() {
    let c = chain();
    let model = loaded_chain_model(&c);
    let q_eq = equilibrium(&model);
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let end = run(&model, IntegratorKind::Modal, &q0, &v0, 0.01, 1.0);
    let exact = c.exact_velocity(&q_eq, &q0, &v0, 1.0);
    assert!(
        max_abs_diff(&end.v, &exact) < tol::MODAL,
        "{:e}",
        max_abs_diff(&end.v, &exact)
    );
}

#[test]
fn velocities_converge_at_the_order_of_each_scheme() {
    velocity_order_on_chain(IntegratorKind::Rk4, [0.04, 0.02, 0.01], 4);
    velocity_order_on_chain(IntegratorKind::Newmark, [0.04, 0.02, 0.01], 2);
    velocity_order_on_chain(IntegratorKind::VelocityVerlet, [0.04, 0.02, 0.01], 2);
    velocity_order_on_chain(IntegratorKind::SymplecticEuler, [0.004, 0.002, 0.001], 1);
    velocity_order_on_chain(IntegratorKind::BackwardEuler, [0.004, 0.002, 0.001], 1);
    velocity_order_on_chain(IntegratorKind::TerzopoulosQin, [0.004, 0.002, 0.001], 1);
}

// ------------------------------------------------------------------ one step by hand

/// `make_stepper_with_options` takes Δt from the options: one step of a unit oscillator
/// (`m = 2`, `k = 8`, ω² = 4) against the update formulas of each scheme done by hand.
#[test]
fn make_stepper_with_options_steps_by_the_formulas() {
    let model = LinearModel::new(
        SystemMatrix::Diagonal(vec![2.0]),
        SparseMatrix::from_triplets(1, 1, &[(0, 0, 8.0)]).unwrap(),
    );
    let (q0, v0, w2) = (0.3, -0.7, 4.0);
    let dt = 0.1;
    let opts = RunOptions::new(dt, 1.0, IntegratorKind::SymplecticEuler);
    let one_step = |kind: IntegratorKind| {
        let initial = State::new(vec![q0], vec![v0]);
        let mut stepper = make_stepper_with_options(kind, &model, &initial, &opts).unwrap();
        let mut s = initial.clone();
        stepper.step(&model, &mut s, dt).unwrap();
        (s.q[0], s.v[0])
    };
    let close = |name: &str, got: (f64, f64), want: (f64, f64)| {
        assert!(
            (got.0 - want.0).abs() < tol::EXACT && (got.1 - want.1).abs() < tol::EXACT,
            "{name}: {got:?} vs {want:?}"
        );
    };
    // Symplectic Euler: v₁ = v₀ − Δt ω² q₀, q₁ = q₀ + Δt v₁.
    let v1 = v0 - dt * w2 * q0;
    close(
        "symplectic Euler",
        one_step(IntegratorKind::SymplecticEuler),
        (q0 + dt * v1, v1),
    );
    // Velocity Verlet: a₀ = −ω² q₀, q₁ = q₀ + Δt v₀ + Δt² a₀ / 2, v₁ = v₀ + Δt (a₀ + a₁) / 2.
    let a0 = -w2 * q0;
    let q1 = q0 + dt * v0 + 0.5 * dt * dt * a0;
    close(
        "velocity Verlet",
        one_step(IntegratorKind::VelocityVerlet),
        (q1, v0 + 0.5 * dt * (a0 - w2 * q1)),
    );
    // Newmark average acceleration: q₁ = ((1 − Δt²ω²/4) q₀ + Δt v₀) / (1 + Δt²ω²/4),
    // v₁ = v₀ + Δt (a₀ + a₁) / 2.
    let c = dt * dt * w2 / 4.0;
    let q1 = ((1.0 - c) * q0 + dt * v0) / (1.0 + c);
    close(
        "newmark",
        one_step(IntegratorKind::Newmark),
        (q1, v0 + 0.5 * dt * (a0 - w2 * q1)),
    );
    // Backward Euler: v₁ = v₀ − Δt ω² q₁, q₁ = q₀ + Δt v₁ ⇒ q₁ = (q₀ + Δt v₀) / (1 + Δt² ω²).
    let q1 = (q0 + dt * v0) / (1.0 + dt * dt * w2);
    close(
        "backward Euler",
        one_step(IntegratorKind::BackwardEuler),
        (q1, v0 - dt * w2 * q1),
    );
    // Terzopoulos–Qin (D = 0): q⁻ = q₀ − Δt v₀, (2 + 2Δt²ω²) q₁ = 4 q₀ − 2 q⁻, and the velocity
    // at the new time is the backward difference (3q₁ − 4q₀ + q⁻) / 2Δt.
    let qm = q0 - dt * v0;
    let q1 = (4.0 * q0 - 2.0 * qm) / (2.0 + 2.0 * dt * dt * w2);
    close(
        "terzopoulos-qin",
        one_step(IntegratorKind::TerzopoulosQin),
        (q1, (3.0 * q1 - 4.0 * q0 + qm) / (2.0 * dt)),
    );
    // RK4 on the linear system y' = A y is the Taylor polynomial of exp(AΔt) to order 4;
    // A² = −ω² I: c = 1 − Δt²ω²/2 + Δt⁴ω⁴/24, s = Δt − Δt³ω²/6.
    let (cc, ss) = (
        1.0 - dt * dt * w2 / 2.0 + dt.powi(4) * w2 * w2 / 24.0,
        dt - dt.powi(3) * w2 / 6.0,
    );
    close(
        "rk4",
        one_step(IntegratorKind::Rk4),
        (cc * q0 + ss * v0, cc * v0 - ss * w2 * q0),
    );
    // Modal (exact): q₁ = q₀ cos ωΔt + v₀/ω sin ωΔt.
    let w = w2.sqrt();
    close(
        "modal",
        one_step(IntegratorKind::Modal),
        (
            q0 * (w * dt).cos() + v0 / w * (w * dt).sin(),
            -q0 * w * (w * dt).sin() + v0 * (w * dt).cos(),
        ),
    );
    // A non-positive Δt in the options is refused.
    let bad = RunOptions::new(-0.1, 1.0, IntegratorKind::Newmark);
    let initial = State::new(vec![q0], vec![v0]);
    assert!(matches!(
        make_stepper_with_options(IntegratorKind::Newmark, &model, &initial, &bad),
        Err(SimError::InvalidTimeStep { .. })
    ));
}

// ------------------------------------------------------------------ symplectic energy behaviour

#[test]
fn symplectic_schemes_keep_energy_bounded_over_1e5_steps() {
    let c = Chain {
        n: 5,
        k: 1.0,
        m: 1.0,
    };
    let model = c.model();
    let q0 = initial_positions(c.n);
    let limit = stability_limit(&model, &q0).unwrap();
    let dt = 0.3 * limit.dt_critical;
    for (kind, bound) in [
        (IntegratorKind::SymplecticEuler, 0.5),
        (IntegratorKind::VelocityVerlet, 0.05),
    ] {
        let mut e0 = None;
        let (mut early, mut late) = (0.0_f64, 0.0_f64);
        let mut obs = |s: &Sample<'_>| {
            let e = s.kinetic + s.potential;
            let e0 = *e0.get_or_insert(e);
            let dev = (e - e0).abs() / e0;
            if s.step <= 10_000 {
                early = early.max(dev);
            } else if s.step > 90_000 {
                late = late.max(dev);
            }
        };
        let summary = simulate(
            &model,
            State::new(q0.clone(), vec![0.0; c.n]),
            &RunOptions::new(dt, 100_000.0 * dt, kind),
            &mut obs,
        )
        .unwrap();
        assert_eq!(summary.steps, 100_000);
        assert!(
            early < bound,
            "{kind}: energy error {early} in the first 10⁴ steps"
        );
        // No drift: the last 10⁴ steps are no worse than the first 10⁴ (up to round-off).
        assert!(
            late <= early * 1.05 + 1e-12,
            "{kind}: energy error grew from {early:e} to {late:e}"
        );
    }
}

// ------------------------------------------------------------------ stability limit

#[test]
fn stability_limit_matches_the_analytic_highest_frequency() {
    let c = chain();
    let model = c.model();
    let limit = stability_limit(&model, &vec![0.0; c.n]).unwrap();
    let w = c.omega(c.n);
    assert!((limit.omega_max - w).abs() < tol::OMEGA * w);
    assert!((limit.dt_critical - 2.0 / w).abs() < tol::OMEGA * 2.0 / w);
}

#[test]
fn explicit_substeps_by_hand() {
    // n = ⌈Δt / (0.9 · limit)⌉: 1 / 0.27 = 3.7 → 4.
    assert_eq!(SUBSTEP_MARGIN, 0.9);
    assert_eq!(explicit_substeps(1.0, 0.3), Some(4));
    assert_eq!(explicit_substeps(0.2, 0.3), Some(1));
    assert_eq!(explicit_substeps(0.27, 0.3), Some(1));
    assert_eq!(explicit_substeps(0.28, 0.3), Some(2));
    assert_eq!(explicit_substeps(1.0, f64::INFINITY), Some(1));
    assert_eq!(
        explicit_substeps(0.9 * MAX_SUBSTEPS as f64, 1.0),
        Some(MAX_SUBSTEPS)
    );
    assert_eq!(
        explicit_substeps(0.9 * MAX_SUBSTEPS as f64 + 0.01, 1.0),
        None
    );
    for bad in [0.0, -1.0, f64::NAN] {
        assert_eq!(explicit_substeps(1.0, bad), None, "{bad}");
    }
}

#[test]
fn a_linear_model_is_its_own_bound_and_schedules_substeps_above_its_limit() {
    let c = chain();
    let model = c.model();
    let q0 = initial_positions(c.n);
    // The bound of a linear model is K: the uniform limit is the analytic 2/ω_max.
    let uniform = uniform_stability_limit(&model).unwrap().unwrap();
    let w = c.omega(c.n);
    assert!((uniform.omega_max - w).abs() < tol::OMEGA * w);
    // A model without a bound (the opaque wrapper hides K) has none.
    assert!(
        uniform_stability_limit(&Opaque(c.model()))
            .unwrap()
            .is_none()
    );
    let dt_crit = 2.0 / w;
    for kind in [IntegratorKind::SymplecticEuler, IntegratorKind::Rk4] {
        // Below 0.9 of the limit: plain steps, with the limit for `simulate`.
        let (plain, limit) = Schedule::stable(&model, &q0, kind, 0.5 * dt_crit).unwrap();
        assert_eq!(plain, Schedule::plain(kind));
        assert_eq!(limit, Some(uniform));
        // Above: the same scheme in ⌈Δt / (0.9 Δt_crit)⌉ substeps.
        let (sub, _) = Schedule::stable(&model, &q0, kind, 10.0 * dt_crit).unwrap();
        assert_eq!(sub.integrator, kind);
        assert_eq!(sub.substeps, (10.0_f64 / 0.9).ceil() as usize);
        // Far above: Newmark.
        let (far, limit) = Schedule::stable(&model, &q0, kind, 1e4 * dt_crit).unwrap();
        assert_eq!(far, Schedule::plain(IMPLICIT_FALLBACK));
        assert_eq!(limit, None);
        // Without a bound: plain steps below the limit at q, Newmark above it.
        let opaque = Opaque(c.model());
        let (below, _) = Schedule::stable(&opaque, &q0, kind, 0.5 * dt_crit).unwrap();
        assert_eq!(below, Schedule::plain(kind));
        let (above, _) = Schedule::stable(&opaque, &q0, kind, 2.0 * dt_crit).unwrap();
        assert_eq!(above, Schedule::plain(IMPLICIT_FALLBACK));
    }
    let (implicit, limit) =
        Schedule::stable(&model, &q0, IntegratorKind::Newmark, 10.0 * dt_crit).unwrap();
    assert_eq!(
        (implicit, limit),
        (Schedule::plain(IntegratorKind::Newmark), None)
    );
}

#[test]
fn substeps_are_plain_steps_of_the_substep_observed_once_per_step() {
    let c = chain();
    let model = c.model();
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let dt_crit = 2.0 / c.omega(c.n);
    let n = 5;
    let dt = 3.0 * dt_crit;
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
    ] {
        let record = |opts: &RunOptions| {
            let mut samples: Vec<(usize, f64, Vec<f64>, Vec<f64>)> = Vec::new();
            let mut obs = |s: &Sample<'_>| samples.push((s.step, s.t, s.q.to_vec(), s.v.to_vec()));
            let summary =
                simulate(&model, State::new(q0.clone(), v0.clone()), opts, &mut obs).unwrap();
            (samples, summary)
        };
        let mut opts = RunOptions::new(dt, 20.0 * dt, kind);
        opts.substeps = n;
        let (sub, summary) = record(&opts);
        assert_eq!(summary.steps, 20);
        assert_eq!(sub.len(), 21);
        let (plain, _) = record(&RunOptions::new(dt / n as f64, 20.0 * dt, kind));
        assert_eq!(plain.len(), 20 * n + 1);
        for (k, (step, t, q, v)) in sub.iter().enumerate() {
            assert_eq!(*step, k);
            assert_eq!(*t, k as f64 * dt);
            let (_, tp, qp, vp) = &plain[k * n];
            assert!((t - tp).abs() <= 1e-12 * dt, "{kind}: t {t} vs {tp}");
            assert_eq!((q, v), (qp, vp), "{kind}: sample {k}");
        }
        // Without substeps the same Δt is refused; zero substeps are an input error.
        let e = run_with(&model, &q0, &v0, &RunOptions::new(dt, 20.0 * dt, kind)).unwrap_err();
        assert!(matches!(e, SimError::Unstable { .. }), "{e:?}");
        opts.substeps = 0;
        let e = run_with(&model, &q0, &v0, &opts).unwrap_err();
        assert_eq!(e, SimError::InvalidSubsteps);
        assert_eq!(e.kind(), ErrorKind::Input);
    }
}

#[test]
fn explicit_schemes_refuse_above_the_limit_diverge_when_forced_and_stay_bounded_below() {
    let c = chain();
    let model = c.model();
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let dt_crit = stability_limit(&model, &q0).unwrap().dt_critical;
    let amplitude = q0.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
    ] {
        // Above the limit: refused.
        let above = 1.01 * dt_crit;
        let e = run_with(
            &model,
            &q0,
            &v0,
            &RunOptions::new(above, 2000.0 * above, kind),
        )
        .unwrap_err();
        match e {
            SimError::Unstable {
                dt, dt_critical, ..
            } => {
                assert_eq!(dt, above);
                assert!((dt_critical - dt_crit).abs() < 1e-12 * dt_crit);
            }
            other => panic!("{kind}: expected Unstable, got {other:?}"),
        }
        // Forced: diverges. RK4's own limit is 2√2/ω_max, so force it beyond that.
        let forced_dt = if kind == IntegratorKind::Rk4 {
            1.5 * dt_crit
        } else {
            above
        };
        let mut opts = RunOptions::new(forced_dt, 5000.0 * forced_dt, kind);
        opts.force_unstable = true;
        match run_with(&model, &q0, &v0, &opts).unwrap_err() {
            SimError::Diverged { step, time, .. } => {
                assert!(step > 1 && step < 5000, "{kind}: diverged at step {step}");
                assert!((time - step as f64 * forced_dt).abs() < 1e-9 * time);
            }
            other => panic!("{kind}: expected Diverged, got {other:?}"),
        }
        // Just below: runs and stays bounded.
        let below = 0.99 * dt_crit;
        let mut peak = 0.0_f64;
        let mut obs =
            |s: &Sample<'_>| peak = peak.max(s.q.iter().fold(0.0_f64, |m, x| m.max(x.abs())));
        let summary = simulate(
            &model,
            State::new(q0.clone(), v0.clone()),
            &RunOptions::new(below, 20_000.0 * below, kind),
            &mut obs,
        )
        .unwrap();
        assert_eq!(summary.dt_critical, Some(dt_crit));
        assert!(
            peak < 50.0 * (amplitude + 1.0),
            "{kind}: peak {peak} just below the limit"
        );
    }
}

// ------------------------------------------------------------------ cancellation

#[test]
fn cancel_flag_stops_after_the_current_step() {
    let c = chain();
    let model = c.model();
    let flag = Arc::new(AtomicBool::new(false));
    let mut opts = RunOptions::new(0.01, 10.0, IntegratorKind::Newmark);
    opts.cancel = Some(flag.clone());
    let mut seen = 0;
    let mut obs = |s: &Sample<'_>| {
        seen += 1;
        if s.step == 5 {
            flag.store(true, Ordering::Relaxed);
        }
    };
    let summary = simulate(
        &model,
        State::new(initial_positions(c.n), vec![0.0; c.n]),
        &opts,
        &mut obs,
    )
    .unwrap();
    assert!(summary.cancelled);
    assert_eq!(summary.steps, 5);
    assert!((summary.t_final - 0.05).abs() < 1e-15);
    assert_eq!(seen, 6);
}

// ------------------------------------------------------------------ nonlinear (Newton)

fn duffing_reference(model: &Duffing, q0: &[f64], v0: &[f64], t_end: f64) -> Vec<f64> {
    let mut opts = RunOptions::new(2e-4, t_end, IntegratorKind::Rk4);
    opts.force_unstable = false;
    run_with(model, q0, v0, &opts).unwrap().q
}

#[test]
fn newton_schemes_converge_on_a_duffing_chain() {
    let c = Chain {
        n: 4,
        k: 2.0,
        m: 1.0,
    };
    let mut model = Duffing::new(&c, 8.0);
    model.force = vec![0.1, 0.0, -0.2, 0.05];
    let q0: Vec<f64> = vec![0.5, -0.3, 0.4, 0.2];
    let v0 = vec![0.0, 0.5, 0.0, -0.2];
    let t_end = 1.0;
    let reference = duffing_reference(&model, &q0, &v0, t_end);
    let err = |kind: IntegratorKind, dt: f64| {
        max_abs_diff(&run(&model, kind, &q0, &v0, dt, t_end).q, &reference)
    };
    let be: Vec<f64> = [0.004, 0.002, 0.001]
        .iter()
        .map(|&dt| err(IntegratorKind::BackwardEuler, dt))
        .collect();
    assert_order("backward-euler (Duffing)", be[0] / be[1], 1);
    assert_order("backward-euler (Duffing)", be[1] / be[2], 1);
    let nm: Vec<f64> = [0.02, 0.01, 0.005]
        .iter()
        .map(|&dt| err(IntegratorKind::Newmark, dt))
        .collect();
    assert_order("newmark (Duffing)", nm[0] / nm[1], 2);
    assert_order("newmark (Duffing)", nm[1] / nm[2], 2);
    // Newmark on the nonlinear model conserves energy up to O(Δt²) (it is not exact here).
    let mut e = Vec::new();
    let mut obs = |s: &Sample<'_>| e.push(s.kinetic + s.potential);
    simulate(
        &model,
        State::new(q0.clone(), v0.clone()),
        &RunOptions::new(0.01, 10.0, IntegratorKind::Newmark),
        &mut obs,
    )
    .unwrap();
    let drift = e.iter().fold(0.0_f64, |m, x| m.max((x - e[0]).abs())) / e[0].abs();
    assert!(drift < 1e-3, "Newmark energy drift on Duffing {drift:e}");
}

#[test]
fn newton_fails_cleanly_with_too_few_iterations() {
    let c = Chain {
        n: 4,
        k: 2.0,
        m: 1.0,
    };
    let model = Duffing::new(&c, 50.0);
    let q0 = vec![0.8, -0.6, 0.7, 0.5];
    let mut opts = RunOptions::new(0.05, 1.0, IntegratorKind::BackwardEuler);
    opts.max_newton_iterations = 1;
    opts.newton_tolerance = 1e-14;
    match run_with(&model, &q0, &[0.0; 4], &opts).unwrap_err() {
        SimError::NewtonFailed {
            step,
            iterations,
            residual,
            ..
        } => {
            assert_eq!(step, 1);
            assert_eq!(iterations, 1);
            assert!(residual > 1e-14);
        }
        other => panic!("expected NewtonFailed, got {other:?}"),
    }
}

#[test]
fn backward_euler_falls_back_to_lu_for_an_indefinite_newton_matrix() {
    // K = −κ I (an unstable "compressed" spring), large Δt: M + Δt²K is negative definite, so
    // Cholesky fails and the LU path must give the exact backward Euler step
    // q⁺ = (q + Δt v)/(1 − Δt²κ/m).
    let (kappa, m, dt) = (4.0, 1.0, 1.0);
    let k = SparseMatrix::from_triplets(
        2,
        2,
        &[(0, 0, -kappa), (1, 1, -kappa), (0, 1, 0.0), (1, 0, 0.0)],
    )
    .unwrap();
    let model = Opaque(LinearModel::new(SystemMatrix::Diagonal(vec![m, m]), k));
    let mut state = State::new(vec![1.0, -0.5], vec![0.2, 0.1]);
    let (q, v) = (state.q.clone(), state.v.clone());
    let mut stepper = make_stepper(IntegratorKind::BackwardEuler, &model, &state, dt).unwrap();
    stepper.step(&model, &mut state, dt).unwrap();
    for i in 0..2 {
        let q_new = (q[i] + dt * v[i]) / (1.0 - dt * dt * kappa / m);
        assert!(
            (state.q[i] - q_new).abs() < tol::EXACT,
            "{} vs {q_new}",
            state.q[i]
        );
        assert!((state.v[i] - (q_new - q[i]) / dt).abs() < tol::EXACT);
    }
}

/// The buckling chain of [`DoubleWell`]: 8 light masses (m = 1e-4, so every step of Δt = 0.1
/// is nearly quasi-static), springs k = 1 (smallest eigenvalue of K 0.12), κ = 1, ε = 1,
/// damping 0.02, the straight chain perturbed by 1e-3 along the first mode.
fn buckling_chain(project: bool) -> (DoubleWell, Vec<f64>) {
    let c = Chain {
        n: 8,
        k: 1.0,
        m: 1e-4,
    };
    let model = DoubleWell {
        k: c.stiffness(),
        kappa: 1.0,
        epsilon: 1.0,
        mass: SystemMatrix::Diagonal(vec![c.m; c.n]),
        damping: Some(SystemMatrix::Diagonal(vec![0.02; c.n])),
        project,
        projections: Default::default(),
        energies: Default::default(),
    };
    let q0 = (1..=c.n)
        .map(|i| 1e-3 * (i as f64 * std::f64::consts::PI / (c.n + 1) as f64).sin())
        .collect();
    (model, q0)
}

#[test]
fn implicit_schemes_settle_a_buckling_chain_into_a_well() {
    // Near q = 0, J = M + c_v D + c_q K_T has a negative eigenvalue (m + 0.05·0.02 + 0.0025·(0.12
    // − 1) < 0 for Newmark), so the first Newton matrices are not positive definite: Newton
    // runs on the projected tangent with the energy line search, and the damped chain must come
    // to rest in a well, checked without the integrator: f_int(q) = 0 there and K_T(q) is
    // positive definite (a minimum of E, not the saddle q = 0).
    for kind in [IntegratorKind::Newmark, IntegratorKind::BackwardEuler] {
        let (model, q0) = buckling_chain(true);
        let n = q0.len();
        let end = run(&model, kind, &q0, &vec![0.0; n], 0.1, 60.0);
        assert!(
            model.projections.load(Ordering::Relaxed) > 0,
            "{kind}: the projection never ran"
        );
        let mut f = vec![0.0; n];
        model.internal_force(&end.q, &mut f);
        let f_norm = f.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(
            f_norm < 1e-8,
            "{kind}: |f_int| = {f_norm:e} at rest, q {:?} v {:?}",
            end.q,
            end.v
        );
        assert!(
            SpdSolver::new(&model.tangent_stiffness(&end.q)).is_ok(),
            "{kind}: K_T not positive definite at {:?}",
            end.q
        );
        // Buckled: every mass left the straight line, to the same side as the perturbation.
        assert!(end.q.iter().all(|&x| x > 0.1), "{kind}: {:?}", end.q);
        assert!(model.potential_energy(&end.q) < model.potential_energy(&q0));
    }
}

#[test]
fn implicit_linear_and_newton_paths_agree() {
    let c = chain();
    let model = loaded_chain_model(&c);
    let opaque = Opaque(loaded_chain_model(&c));
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    for kind in [IntegratorKind::Newmark, IntegratorKind::BackwardEuler] {
        let a = run(&model, kind, &q0, &v0, 0.05, 2.0);
        let b = run(&opaque, kind, &q0, &v0, 0.05, 2.0);
        assert!(
            max_abs_diff(&a.q, &b.q) < 1e-9,
            "{kind}: {:e}",
            max_abs_diff(&a.q, &b.q)
        );
    }
}

// ------------------------------------------------------------------ dof map

#[test]
fn dof_map_restrict_extend_and_matrices() {
    let n = 7;
    let map = DofMap::new(n, &[5, 1, 5, 0]).unwrap();
    assert_eq!(map.fixed(), &[0, 1, 5]);
    assert_eq!(map.free(), &[2, 3, 4, 6]);
    assert_eq!((map.n_total(), map.n_free()), (7, 4));
    assert!(map.is_fixed(5) && !map.is_fixed(6));
    assert_eq!(map.free_index(4), Some(2));
    assert_eq!(map.free_index(1), None);
    assert!(matches!(
        DofMap::new(3, &[3]),
        Err(SimError::DimensionMismatch { .. })
    ));
    let full: Vec<f64> = (0..n).map(|i| i as f64 * 1.5 - 2.0).collect();
    let free = map.restrict(&full);
    assert_eq!(map.extend(&free, &full), full);
    let mut out = vec![-9.0; n];
    map.extend_into(&free, &mut out);
    assert!((0..n).all(|i| if map.is_fixed(i) {
        out[i] == -9.0
    } else {
        out[i] == full[i]
    }));
    // Matrices against dense slicing.
    let dense = DenseMatrix::from_fn(n, n, |i, j| {
        if (i + 2 * j) % 3 == 0 {
            (i * n + j) as f64 + 1.0
        } else {
            0.0
        }
    });
    let a = SparseMatrix::from_dense(&dense, 0.0);
    let aff = map.restrict_matrix(&a).to_dense();
    let afc = map.coupling_matrix(&a).to_dense();
    assert_eq!(
        aff,
        DenseMatrix::from_fn(4, 4, |i, j| dense[(map.free()[i], map.free()[j])])
    );
    assert_eq!(
        afc,
        DenseMatrix::from_fn(4, 3, |i, j| dense[(map.free()[i], map.fixed()[j])])
    );
    // Eliminating fixed dofs: A_ff x_f = b_f − A_fc x_c reproduces the full solution.
    let lap = Chain { n, k: 1.0, m: 1.0 }.stiffness();
    let x_full: Vec<f64> = (0..n).map(|i| (i as f64 * 0.9).cos()).collect();
    let mut b = vec![0.0; n];
    lap.mul_vec(&x_full, &mut b);
    let x_fixed: Vec<f64> = map.fixed().iter().map(|&d| x_full[d]).collect();
    let mut rhs = map.restrict(&b);
    map.coupling_matrix(&lap)
        .mul_vec_add(-1.0, &x_fixed, &mut rhs);
    let x_free = SpdSolver::new(&map.restrict_matrix(&lap))
        .unwrap()
        .solve(&rhs);
    let mut fixed_only = vec![0.0; n];
    for &d in map.fixed() {
        fixed_only[d] = x_full[d];
    }
    assert!(max_abs_diff(&map.extend(&x_free, &fixed_only), &x_full) < tol::EXACT);
    let all = DofMap::all_free(n);
    assert_eq!(all.n_free(), n);
    assert!(all.fixed().is_empty());
}

#[test]
fn linear_model_energy_and_forces_are_consistent() {
    let c = chain();
    let model = loaded_chain_model(&c);
    model.validate().unwrap();
    let q = initial_positions(c.n);
    // f_int = ∇E by central differences (E quadratic: exact up to round-off).
    let mut f = vec![0.0; c.n];
    model.internal_force(&q, &mut f);
    let h = 1e-4;
    for i in 0..c.n {
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[i] += h;
        qm[i] -= h;
        let g = (model.potential_energy(&qp) - model.potential_energy(&qm)) / (2.0 * h);
        assert!((g - f[i]).abs() < 1e-9, "{i}: {g} vs {}", f[i]);
    }
    assert_eq!(model.potential_energy(&model.rest), 0.0);
    let m = SystemMatrix::Diagonal(vec![2.0; 3]);
    assert_eq!(m.quadratic_form(&[1.0, 2.0, 3.0]), 28.0);
    assert_eq!(m.to_sparse().diagonal(), vec![2.0; 3]);
}

/// Relative residual of `M a + D v + f_int(q) − f_ext` at one state, recomputed from the model.
fn equation_of_motion_residual(model: &dyn DynamicModel, q: &[f64], v: &[f64], a: &[f64]) -> f64 {
    let n = q.len();
    let (mut ma, mut fint, mut fext, mut dv) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    model.mass().mul_vec(a, &mut ma);
    model.internal_force(q, &mut fint);
    model.external_force(0.0, &mut fext);
    if let Some(d) = model.damping() {
        d.mul_vec(v, &mut dv);
    }
    let norm = |x: &[f64]| x.iter().map(|y| y * y).sum::<f64>().sqrt();
    let r: Vec<f64> = (0..n).map(|i| ma[i] + dv[i] + fint[i] - fext[i]).collect();
    let scale = norm(&ma).max(norm(&fint)).max(norm(&fext)).max(norm(&dv));
    norm(&r) / scale
}

/// The implicit schemes keep one factor of the Newton matrix across iterations and steps
/// (modified Newton) on a strongly nonlinear model, and every step still solves its own
/// equations: the residual of the equation of motion, recomputed here from the states alone
/// (backward Euler: `a = (v⁺ − v)/Δt` at `q⁺ = q + Δt v⁺`; Newmark: `a⁺` from the velocity update,
/// with the position update checked too), stays at the Newton tolerance.
#[test]
fn modified_newton_reuses_the_factor_and_solves_every_step() {
    use nurbspring_sim::integrators::{BackwardEuler, Newmark};
    let c = chain();
    let mut model = Duffing::new(&c, 40.0);
    model.damping = Some(SystemMatrix::Diagonal(vec![0.05; c.n]));
    model.force = (0..c.n).map(|i| 0.1 * (i as f64 - 3.5)).collect();
    let (dt, steps) = (0.05, 200);
    let newton = NewtonSettings::default();
    let start = State::new(initial_positions(c.n), initial_velocities(c.n));
    // The motion is nonlinear: the cubic term is comparable to the linear one.
    let cubic = start.q.iter().map(|x| 40.0 * x * x).fold(0.0, f64::max);
    assert!(
        cubic > 0.3 * c.k,
        "cubic stiffness {cubic} against k = {}",
        c.k
    );

    let mut be = BackwardEuler::new(&model, dt, newton).unwrap();
    let mut s = start.clone();
    for _ in 0..steps {
        let (q, v) = (s.q.clone(), s.v.clone());
        be.step(&model, &mut s, dt).unwrap();
        let a: Vec<f64> = (0..c.n).map(|i| (s.v[i] - v[i]) / dt).collect();
        for i in 0..c.n {
            assert!((s.q[i] - (q[i] + dt * s.v[i])).abs() < tol::EXACT);
        }
        let r = equation_of_motion_residual(&model, &s.q, &s.v, &a);
        assert!(r < 10.0 * newton.tolerance, "backward Euler residual {r:e}");
    }
    let counts = be.newton_counts();
    assert!(
        counts.factorizations * 4 < steps && counts.iterations >= steps,
        "backward Euler: {counts:?} over {steps} steps"
    );

    let mut nm = Newmark::new(&model, &start, dt, newton).unwrap();
    let mut s = start.clone();
    // a₀ from the equation of motion: M a₀ = f_ext − f_int(q₀) − D v₀ (M diagonal).
    let mut a = {
        let (mut f, mut fint, mut dv) = (vec![0.0; c.n], vec![0.0; c.n], vec![0.0; c.n]);
        model.external_force(0.0, &mut f);
        model.internal_force(&s.q, &mut fint);
        model.damping.as_ref().unwrap().mul_vec(&s.v, &mut dv);
        (0..c.n)
            .map(|i| (f[i] - fint[i] - dv[i]) / c.m)
            .collect::<Vec<f64>>()
    };
    for _ in 0..steps {
        let (q, v) = (s.q.clone(), s.v.clone());
        nm.step(&model, &mut s, dt).unwrap();
        let a_new: Vec<f64> = (0..c.n)
            .map(|i| 2.0 * (s.v[i] - v[i]) / dt - a[i])
            .collect();
        for i in 0..c.n {
            let q_new = q[i] + dt * v[i] + 0.25 * dt * dt * (a[i] + a_new[i]);
            assert!((s.q[i] - q_new).abs() < 1e-12, "{} vs {q_new}", s.q[i]);
        }
        let r = equation_of_motion_residual(&model, &s.q, &s.v, &a_new);
        assert!(r < 10.0 * newton.tolerance, "Newmark residual {r:e}");
        a = a_new;
    }
    let counts = nm.newton_counts();
    assert!(
        counts.factorizations * 4 < steps && counts.iterations >= steps,
        "Newmark: {counts:?} over {steps} steps"
    );
}

/// Every stepper advances the clock by Δt a step: `t_n = n Δt` (to the round-off of n sums),
/// the time at which the external force of the next step is taken.
#[test]
fn every_stepper_advances_time_by_dt() {
    let model = LinearModel::new(
        SystemMatrix::Diagonal(vec![1.0, 2.0]),
        SparseMatrix::from_diagonal(&[4.0, 9.0]),
    );
    let dt = 0.1;
    for kind in IntegratorKind::ALL {
        let mut state = State::new(vec![1.0, -0.5], vec![0.0, 0.3]);
        state.t = 2.0;
        let mut stepper = make_stepper(kind, &model, &state, dt).unwrap();
        for n in 1..=7 {
            stepper.step(&model, &mut state, dt).unwrap();
            let expected = 2.0 + n as f64 * dt;
            assert!(
                (state.t - expected).abs() <= 8.0 * f64::EPSILON * expected,
                "{kind:?} after {n} steps: t = {} (expected {expected})",
                state.t
            );
        }
    }
}

/// A damped linear model through the implicit schemes' one-solve path: every step satisfies
/// the equation of motion `M a + D v + K q = f` at its end, recomputed from the states
/// (backward Euler: `a = (v⁺ − v)/Δt`; Newmark: `a⁺` from its velocity update).
#[test]
fn linear_implicit_steps_solve_the_damped_equation_of_motion() {
    use nurbspring_sim::integrators::{BackwardEuler, Newmark};
    let mut model = LinearModel::new(
        SystemMatrix::Diagonal(vec![1.0, 2.0]),
        SparseMatrix::from_triplets(
            2,
            2,
            &[(0, 0, 5.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 3.0)],
        )
        .unwrap(),
    );
    model.damping = Some(SystemMatrix::Diagonal(vec![0.4, 0.7]));
    model.force = vec![0.3, -0.2];
    let dt = 0.05;
    let newton = NewtonSettings::default();
    let start = State::new(vec![0.5, -0.25], vec![0.1, 0.2]);

    let mut be = BackwardEuler::new(&model, dt, newton).unwrap();
    let mut s = start.clone();
    for _ in 0..20 {
        let v = s.v.clone();
        be.step(&model, &mut s, dt).unwrap();
        let a: Vec<f64> = (0..2).map(|i| (s.v[i] - v[i]) / dt).collect();
        let r = equation_of_motion_residual(&model, &s.q, &s.v, &a);
        // Measured: 2e-15 (backward Euler), 1e-14 (Newmark, whose a⁺ is a difference over Δt).
        assert!(r < 2e-14, "backward Euler residual {r:e}");
    }

    let mut nm = Newmark::new(&model, &start, dt, newton).unwrap();
    let mut s = start.clone();
    // a₀ = M⁻¹ (f − K q₀ − D v₀).
    let mut a = vec![
        (0.3 - (5.0 * 0.5 + 0.25) - 0.4 * 0.1) / 1.0,
        (-0.2 - (-0.5 - 0.75) - 0.7 * 0.2) / 2.0,
    ];
    for _ in 0..20 {
        let v = s.v.clone();
        nm.step(&model, &mut s, dt).unwrap();
        let a_new: Vec<f64> = (0..2).map(|i| 2.0 * (s.v[i] - v[i]) / dt - a[i]).collect();
        let r = equation_of_motion_residual(&model, &s.q, &s.v, &a_new);
        assert!(r < 1e-13, "Newmark residual {r:e}");
        a = a_new;
    }
}

// ------------------------------------------------------------------ damped explicit steps

/// One damped step of each explicit scheme on the oscillator `m = 2`, `k = 8`, `d = 0.6`,
/// against its update formula by hand (`a = (−k q − d v)/m`): symplectic Euler
/// `v₁ = v₀ + Δt a(q₀, v₀)`, `q₁ = q₀ + Δt v₁`; velocity Verlet with the damping of the second
/// half-kick taken at the new velocity, `v₁ = (m v½ − ½Δt k q₁)/(m + ½Δt d)`.
#[test]
fn explicit_schemes_take_one_damped_step_by_their_formulas() {
    let (m, k, d) = (2.0, 8.0, 0.6);
    let mut model = LinearModel::new(
        SystemMatrix::Diagonal(vec![m]),
        SparseMatrix::from_triplets(1, 1, &[(0, 0, k)]).unwrap(),
    );
    model.damping = Some(SystemMatrix::Diagonal(vec![d]));
    let (q0, v0, dt) = (0.3, -0.7, 0.1);
    let step = |kind| {
        let mut s = State::new(vec![q0], vec![v0]);
        let mut stepper = make_stepper(kind, &model, &s, dt).unwrap();
        stepper.step(&model, &mut s, dt).unwrap();
        (s.q[0], s.v[0], s.t)
    };
    let a = |q: f64, v: f64| (-k * q - d * v) / m;
    let v1 = v0 + dt * a(q0, v0);
    let (q, v, t) = step(IntegratorKind::SymplecticEuler);
    assert!((v - v1).abs() < tol::EXACT && (q - (q0 + dt * v1)).abs() < tol::EXACT);
    assert_eq!(t, dt);
    let h = 0.5 * dt;
    let v_half = v0 + h * a(q0, v0);
    let q1 = q0 + dt * v_half;
    let v1 = (m * v_half - h * k * q1) / (m + h * d);
    let (q, v, t) = step(IntegratorKind::VelocityVerlet);
    assert!(
        (q - q1).abs() < tol::EXACT && (v - v1).abs() < tol::EXACT,
        "{q} {v}"
    );
    assert_eq!(t, dt);
    // RK4 on y' = A y, A = [[0, 1], [−k/m, −d/m]]: the Taylor polynomial of exp(AΔt) to order 4.
    let apply = |y: [f64; 2]| [y[1], -k / m * y[0] - d / m * y[1]];
    let mut term = [q0, v0];
    let mut y = term;
    for p in 1..=4 {
        term = apply(term).map(|x| x * dt / p as f64);
        y = [y[0] + term[0], y[1] + term[1]];
    }
    let (q, v, _) = step(IntegratorKind::Rk4);
    assert!((q - y[0]).abs() < tol::EXACT && (v - y[1]).abs() < tol::EXACT);
}

/// A stepper is built for one Δt: another is refused.
#[test]
fn a_stepper_refuses_another_time_step() {
    let model = Chain {
        n: 3,
        k: 1.0,
        m: 1.0,
    }
    .model();
    let s = State::new(vec![0.1; 3], vec![0.0; 3]);
    for kind in [
        IntegratorKind::BackwardEuler,
        IntegratorKind::Newmark,
        IntegratorKind::Modal,
    ] {
        let mut stepper = make_stepper(kind, &model, &s, 0.1).unwrap();
        let mut state = s.clone();
        assert!(
            stepper
                .step(&model, &mut state, 0.1 * (1.0 + 1e-14))
                .is_ok(),
            "{kind}"
        );
        assert!(
            matches!(
                stepper.step(&model, &mut state, 0.2),
                Err(SimError::NotSupported { .. })
            ),
            "{kind}"
        );
    }
}

#[test]
fn representable_numbers_and_time_limits() {
    for x in [0.0, -1.0, 1e-300, MAX_MAGNITUDE, -MAX_MAGNITUDE] {
        assert!(representable(x), "{x}");
    }
    for x in [f64::NAN, f64::INFINITY, 1.0001 * MAX_MAGNITUDE, -1e31] {
        assert!(!representable(x), "{x}");
    }
    // ⌈(t_end − t0)/Δt⌉ steps at most MAX_STEPS.
    assert!(check_time(1e-3, 1e5, 0.0).is_ok());
    assert!(matches!(
        check_time(1e-4, 1e5, 0.0),
        Err(SimError::TooManySteps { steps, .. }) if steps == 1e9
    ));
    assert!(check_time(1e-4, 1e4 + 5.0, 5.0).is_ok());
}

/// A run given its stability limit reports that limit, not one of its own.
#[test]
fn a_scheduled_run_reports_the_limit_it_was_given() {
    let c = Chain {
        n: 4,
        k: 1.0,
        m: 1.0,
    };
    let model = c.model();
    let given = StabilityLimit {
        omega_max: 3.0,
        dt_critical: 2.0 / 3.0,
    };
    let (schedule, limit) = Schedule::below(IntegratorKind::SymplecticEuler, 0.1, given);
    assert_eq!(limit, Some(given));
    let opts = RunOptions::scheduled(0.1, 1.0, schedule, limit);
    let s = State::new(initial_positions(c.n), vec![0.0; c.n]);
    let summary = simulate(&model, s, &opts, &mut NullObserver).unwrap();
    assert_eq!(summary.omega_max, Some(3.0));
    assert_eq!(summary.dt_critical, Some(2.0 / 3.0));
    // A step above 0.9 of the limit is cut into substeps, which the options carry: Δt = 1
    // against 0.9 · 2/3 = 0.6 takes 2.
    let (schedule, limit) = Schedule::below(IntegratorKind::SymplecticEuler, 1.0, given);
    assert_eq!(schedule.substeps, 2);
    let opts = RunOptions::scheduled(1.0, 4.0, schedule, limit);
    assert_eq!((opts.substeps, opts.substep()), (2, 0.5));
}

/// Symplectic Euler's other two paths, from t = 0.25: a damping matrix that is not diagonal
/// (forces first, then the update) against the formula, and a model with its own fused step,
/// which the stepper calls and then advances the clock.
#[test]
fn symplectic_euler_with_full_damping_and_with_a_fused_step() {
    let mut model = LinearModel::new(
        SystemMatrix::Diagonal(vec![2.0, 1.0]),
        SparseMatrix::from_triplets(
            2,
            2,
            &[(0, 0, 8.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 3.0)],
        )
        .unwrap(),
    );
    model.damping = Some(SystemMatrix::Sparse(
        SparseMatrix::from_triplets(2, 2, &[(0, 0, 0.6), (0, 1, 0.1), (1, 0, 0.1), (1, 1, 0.4)])
            .unwrap(),
    ));
    let (q0, v0, dt) = ([0.3, -0.2], [-0.7, 0.5], 0.1);
    let mut s = State::new(q0.to_vec(), v0.to_vec());
    s.t = 0.25;
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &model, &s, dt).unwrap();
    stepper.step(&model, &mut s, dt).unwrap();
    let a = [
        (-(8.0 * q0[0] - q0[1]) - (0.6 * v0[0] + 0.1 * v0[1])) / 2.0,
        -(-q0[0] + 3.0 * q0[1]) - (0.1 * v0[0] + 0.4 * v0[1]),
    ];
    for i in 0..2 {
        let v1 = v0[i] + dt * a[i];
        assert!(
            (s.v[i] - v1).abs() < tol::EXACT && (s.q[i] - (q0[i] + dt * v1)).abs() < tol::EXACT
        );
    }
    assert!((s.t - 0.35).abs() < 4.0 * f64::EPSILON);

    /// A model whose fused step moves every coordinate by Δt and every velocity by 1.
    struct Fused(LinearModel);
    impl FusedStep for Fused {
        fn workspace_len(&self) -> usize {
            3
        }
        fn symplectic_euler(&self, _t: f64, dt: f64, q: &mut [f64], v: &mut [f64], w: &mut [f64]) {
            assert!(w.len() >= 3);
            q.iter_mut().for_each(|x| *x += dt);
            v.iter_mut().for_each(|x| *x += 1.0);
        }
    }
    impl DynamicModel for Fused {
        fn n_dofs(&self) -> usize {
            self.0.n_dofs()
        }
        fn mass(&self) -> &SystemMatrix {
            self.0.mass()
        }
        fn damping(&self) -> Option<&SystemMatrix> {
            None
        }
        fn internal_force(&self, q: &[f64], out: &mut [f64]) {
            self.0.internal_force(q, out)
        }
        fn external_force(&self, t: f64, out: &mut [f64]) {
            self.0.external_force(t, out)
        }
        fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
            self.0.tangent_stiffness(q)
        }
        fn potential_energy(&self, q: &[f64]) -> f64 {
            self.0.potential_energy(q)
        }
        fn fused_step(&self) -> Option<&dyn FusedStep> {
            Some(self)
        }
    }
    let fused = Fused(model.clone());
    let mut s = State::new(q0.to_vec(), v0.to_vec());
    s.t = 0.25;
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &fused, &s, dt).unwrap();
    stepper.step(&fused, &mut s, dt).unwrap();
    assert_eq!(s.q, vec![q0[0] + dt, q0[1] + dt]);
    assert_eq!(s.v, vec![v0[0] + 1.0, v0[1] + 1.0]);
    assert!((s.t - 0.35).abs() < 4.0 * f64::EPSILON);
}

/// One mass on a spring driven by `F cos Ωt`: `q̈ + ω² q = F cos Ωt`, whose solution is
/// `(q₀ − c) cos ωt + v₀/ω sin ωt + c cos Ωt` with `c = F/(ω² − Ω²)`.
struct Forced {
    mass: SystemMatrix,
    k: SparseMatrix,
    amplitude: f64,
    frequency: f64,
}

impl Forced {
    fn new(omega: f64, amplitude: f64, frequency: f64) -> Self {
        Self {
            mass: SystemMatrix::Diagonal(vec![1.0]),
            k: SparseMatrix::from_diagonal(&[omega * omega]),
            amplitude,
            frequency,
        }
    }

    fn exact(&self, q0: f64, v0: f64, t: f64) -> f64 {
        let w = self.k.diagonal()[0].sqrt();
        let c = self.amplitude / (w * w - self.frequency * self.frequency);
        (q0 - c) * (w * t).cos() + v0 / w * (w * t).sin() + c * (self.frequency * t).cos()
    }
}

impl DynamicModel for Forced {
    fn n_dofs(&self) -> usize {
        1
    }
    fn mass(&self) -> &SystemMatrix {
        &self.mass
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        None
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.k.mul_vec(q, out);
    }
    fn external_force(&self, t: f64, out: &mut [f64]) {
        out[0] = self.amplitude * (self.frequency * t).cos();
    }
    fn tangent_stiffness(&self, _q: &[f64]) -> SparseMatrix {
        self.k.clone()
    }
    fn potential_energy(&self, q: &[f64]) -> f64 {
        0.5 * self.k.quadratic_form(q)
    }
}

/// Under a load that varies in time, RK4 evaluates it at each stage's time and keeps its
/// fourth order against the closed form (a stage at the wrong time costs orders).
#[test]
fn rk4_keeps_fourth_order_under_a_time_dependent_load() {
    let model = Forced::new(3.0, 2.0, 5.0);
    let (q0, v0, t_end) = (0.1, -0.4, 1.0);
    let exact = model.exact(q0, v0, t_end);
    let err =
        |dt: f64| (run(&model, IntegratorKind::Rk4, &[q0], &[v0], dt, t_end).q[0] - exact).abs();
    let e: Vec<f64> = [0.02, 0.01, 0.005].iter().map(|&dt| err(dt)).collect();
    assert_order("rk4 forced", e[0] / e[1], 4);
    assert_order("rk4 forced", e[1] / e[2], 4);
}
