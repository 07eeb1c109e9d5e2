//! The Newton iteration of the implicit schemes (`integrators/implicit.rs`) on models built to
//! reach each of its exits and policies: the round-off floor of a residual whose terms cancel,
//! the step-size exit on coordinates far from the origin, the projected tangent, the energy
//! line search, the factor counts and the reported residual. Expected values come from the
//! update formulas by hand, closed-form roots and residuals recomputed from the models.

mod support;

use std::sync::atomic::Ordering;

use nurbspring_linalg::{SparseMatrix, SpdSolver};
use nurbspring_sim::integrators::{BackwardEuler, GeneralizedAlpha, Newmark, NewtonCounts};
use nurbspring_sim::*;
use support::{Chain, DoubleWell, Duffing, Opaque, Prestressed, initial_positions, max_abs_diff};

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// A chain with a prestress P = 1e8 ≫ its spring forces (k = 1, |q| ≈ 0.3): the force at a
/// mass is the difference of two tensions ≈ P, so it carries a round-off of about
/// `ε·P ≈ 2e-8` whatever q is, against forces `|K q| ≈ 0.3`: the relative residual of Newton
/// cannot fall below about 1e-7, far above the tolerance 1e-10 but below its square root
/// 1e-5. A Newton correction of that round-off, `c_q·|p| ≈ c_q/(m + c_q k λ)·6e-8 ≈ 1e-10`
/// (m = 1, c_q = Δt² or Δt²/4, Δt = 0.1), is larger than `tolerance·|q| ≈ 5e-11`, so the
/// step-size exit does not end the iteration either: only the
/// round-off-floor exit (a full Newton step that leaves the residual where it was) does.
/// Without it every step fails after 30 iterations. The result must still be the linear
/// chain's step: the same scheme on the [`LinearModel`] with the same K (one exact solve) agrees
/// to the propagated force round-off.
#[test]
fn newton_stops_at_the_round_off_floor_of_a_prestressed_chain() {
    let chain = Chain {
        n: 6,
        k: 1.0,
        m: 1.0,
    };
    let prestress = 1e8;
    let model = Prestressed {
        chain: Chain { ..chain },
        prestress,
        mass: SystemMatrix::Diagonal(vec![chain.m; chain.n]),
    };
    let exact = chain.model();
    let q0 = initial_positions(chain.n);
    let v0 = vec![0.0; chain.n];
    // The floor, by hand: one force entry is T_i − T_{i+1} with T ≈ P, each T rounded once
    // (P + k s) and the difference once: at most 3 ulps of P, i.e. 3·ε·P ≈ 6.7e-8 per entry.
    let force_roundoff = 3.0 * f64::EPSILON * prestress * (chain.n as f64).sqrt();
    let mut f = vec![0.0; chain.n];
    model.internal_force(&q0, &mut f);
    let relative_floor = force_roundoff / norm(&f);
    assert!(
        relative_floor > 1e-10 && relative_floor < 1e-5,
        "{relative_floor:e}"
    );
    let (dt, steps) = (0.1, 20);
    for kind in [IntegratorKind::BackwardEuler, IntegratorKind::Newmark] {
        let mut a = State::new(q0.clone(), v0.clone());
        let mut b = State::new(q0.clone(), v0.clone());
        let mut noisy = make_stepper(kind, &model, &a, dt).unwrap();
        let mut clean = make_stepper(kind, &exact, &b, dt).unwrap();
        for step in 1..=steps {
            noisy
                .step(&model, &mut a, dt)
                .unwrap_or_else(|e| panic!("{kind} step {step}: {e}"));
            clean.step(&exact, &mut b, dt).unwrap();
        }
        // Each step's solve is exact up to the force round-off: the residual left at the floor
        // plus the force's own error, 2·force_roundoff, times |J⁻¹| ≤ 1/m, moves q by at most
        // c_q/m·2·force_roundoff a step. These schemes do not amplify errors in the energy
        // norm (backward Euler contracts it, Newmark keeps it), which differs from the
        // Euclidean one by at most √(λ_max/λ_min(K)) ≈ 4.4 for n = 6: a factor 10 covers both.
        let cq = if kind == IntegratorKind::Newmark {
            0.25 * dt * dt
        } else {
            dt * dt
        };
        let bound = 10.0 * steps as f64 * cq / chain.m * force_roundoff;
        let err = max_abs_diff(&a.q, &b.q);
        assert!(
            err < bound,
            "{kind}: |q − q_exact| = {err:e} above {bound:e}"
        );
    }
}

/// One mass far from the origin, `q = q_rest + u` with `q_rest = 10⁶` and a motion
/// `u ≈ 10⁻⁶`, behind the nonlinear interface: a whole step moves q by
/// `Δt²|a| ≈ 0.01·3e-6 ≈ 3e-8`, less than `tolerance·|q| = 10⁻⁴`, so the first full Newton
/// step ends the iteration by the step-size exit (the first step: after one iteration, with
/// the one factorization), and that last correction must be applied. The displacement must
/// follow backward Euler's step for `m ü + k u = 0`, by hand: `(m + Δt² k) a = −k (u + Δt v)`,
/// `v⁺ = v + Δt a`, `u⁺ = u + Δt v⁺`.
#[test]
fn newton_ends_by_the_step_size_on_coordinates_far_from_the_origin() {
    let (m, k, rest, dt) = (1.0, 3.0, 1e6, 0.1);
    let mut linear = LinearModel::new(
        SystemMatrix::Diagonal(vec![m]),
        SparseMatrix::from_diagonal(&[k]),
    );
    linear.rest = vec![rest];
    let model = Opaque(linear);
    let u0 = 1e-6;
    let mut state = State::new(vec![rest + u0], vec![0.0]);
    let (mut u, mut v) = (state.q[0] - rest, 0.0);
    let mut stepper = BackwardEuler::new(&model, dt, NewtonSettings::default()).unwrap();
    // Per step: q is rounded to a multiple of ulp(10⁶) = 1.2e-10 (half of it at most), and the
    // solve carries the force round-off 2·½ulp(k·10⁶) ≈ 4.7e-10 times Δt²/(m + Δt²k) ≈ 0.01.
    let per_step = 0.5 * 1.2e-10 + 0.01 * 4.7e-10;
    for step in 1..=10 {
        stepper
            .step(&model, &mut state, dt)
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        let a = -k * (u + dt * v) / (m + dt * dt * k);
        v += dt * a;
        u += dt * v;
        let err = (state.q[0] - rest - u).abs();
        assert!(
            err <= step as f64 * per_step,
            "step {step}: u = {:e}, by hand {u:e}",
            state.q[0] - rest
        );
        assert!((state.v[0] - v).abs() <= step as f64 * per_step / dt);
        if step == 1 {
            let one = NewtonCounts {
                factorizations: 1,
                iterations: 1,
                halved_steps: 0,
            };
            assert_eq!(stepper.newton_counts(), one);
        }
    }
}

/// A linear model behind the nonlinear interface: J is constant, so the first iteration ever
/// factors it and every later step solves with that factor in one iteration (the solve is
/// exact up to round-off, relative residual ≈ 1e-15 against the tolerance 1e-10, and the kept
/// factor contracts the residual by far more than `CONTRACTION`): exactly 1 factorization and
/// one iteration per step.
#[test]
fn a_linear_model_behind_newton_is_factored_once_and_solved_in_one_iteration_a_step() {
    let chain = Chain {
        n: 8,
        k: 3.0,
        m: 0.5,
    };
    let mut linear = chain.model();
    linear.force = (0..chain.n).map(|i| 0.4 - 0.1 * i as f64).collect();
    let model = Opaque(linear);
    let steps = 20;
    let start = State::new(
        initial_positions(chain.n),
        support::initial_velocities(chain.n),
    );
    let newton = NewtonSettings::default();
    let mut be = BackwardEuler::new(&model, 0.05, newton).unwrap();
    let mut nm = Newmark::new(&model, &start, 0.05, newton).unwrap();
    let (mut s, mut t) = (start.clone(), start.clone());
    for _ in 0..steps {
        be.step(&model, &mut s, 0.05).unwrap();
        nm.step(&model, &mut t, 0.05).unwrap();
    }
    let expected = NewtonCounts {
        factorizations: 1,
        iterations: steps,
        halved_steps: 0,
    };
    assert_eq!(be.newton_counts(), expected, "backward Euler");
    assert_eq!(nm.newton_counts(), expected, "Newmark");
}

/// The projected tangent is for Newton matrices that Cholesky cannot factor: on the buckling
/// chain with a step so short that `J = M + c_v D + c_q K_T ⪰ (m − c_q κ) I` is positive
/// definite everywhere (K ⪰ 0, D ⪰ 0, 3εq² ≥ 0; m = 1e-4 > c_q κ = 2.5e-5 for Δt = 5e-3),
/// the model's projection is never asked for and every step solves its own equation (the
/// residual recomputed from the states, backward Euler: `a = (v⁺ − v)/Δt`).
#[test]
fn the_projected_tangent_is_not_used_while_the_newton_matrix_is_positive_definite() {
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
        project: true,
        projections: Default::default(),
        energies: Default::default(),
    };
    let dt = 5e-3;
    assert!(c.m > dt * dt * model.kappa);
    let q0: Vec<f64> = (1..=c.n).map(|i| 0.3 * (i as f64 * 0.7).sin()).collect();
    let mut s = State::new(q0, vec![0.0; c.n]);
    let newton = NewtonSettings::default();
    let mut be = BackwardEuler::new(&model, dt, newton).unwrap();
    for step in 1..=50 {
        let v = s.v.clone();
        be.step(&model, &mut s, dt).unwrap();
        let a: Vec<f64> = (0..c.n).map(|i| (s.v[i] - v[i]) / dt).collect();
        let (mut ma, mut dv, mut f) = (vec![0.0; c.n], vec![0.0; c.n], vec![0.0; c.n]);
        model.mass.mul_vec(&a, &mut ma);
        model.damping.as_ref().unwrap().mul_vec(&s.v, &mut dv);
        model.internal_force(&s.q, &mut f);
        let r: Vec<f64> = (0..c.n).map(|i| ma[i] + dv[i] + f[i]).collect();
        let scale = norm(&ma).max(norm(&dv)).max(norm(&f));
        assert!(
            norm(&r) <= 10.0 * newton.tolerance * scale,
            "step {step}: residual {:e}",
            norm(&r) / scale
        );
    }
    assert!(be.newton_counts().factorizations > 0);
    assert_eq!(model.projections.load(Ordering::Relaxed), 0);
}

/// Two masses on a Duffing chain (k = 1, ε = 1, m = 1) with loads (0.1, 0.3), and Newton
/// settings that allow no iteration (tolerance 1e-10): every implicit step fails.
fn loaded_pair_without_iterations() -> (Duffing, NewtonSettings) {
    let c = Chain {
        n: 2,
        k: 1.0,
        m: 1.0,
    };
    let mut model = Duffing::new(&c, 1.0);
    model.force = vec![0.1, 0.3];
    let newton = NewtonSettings {
        tolerance: 1e-10,
        max_iterations: 0,
    };
    (model, newton)
}

/// A stiff Duffing chain (4 masses, k = 2, ε = 50, m = 1) at rest far from equilibrium.
fn stiff_duffing_chain() -> (Duffing, State) {
    let c = Chain {
        n: 4,
        k: 2.0,
        m: 1.0,
    };
    let start = State::new(vec![0.8, -0.6, 0.7, 0.5], vec![0.0; 4]);
    (Duffing::new(&c, 50.0), start)
}

/// When Newton gives up, the error reports the relative residual `|R| / max(|M a|, |f_int|,
/// |f_ext|)` of its last iterate. With no iteration allowed that is the starting point of the
/// first backward Euler step from rest, a = 0 (the guess and the acceleration that keeps q
/// coincide), where `R = f_int(q₀) − f`, by hand on a two-mass Duffing chain
/// (k = 1, ε = 1): `f_int(0.5, −0.25) = (1.375, −1.015625)`, `f = (0.1, 0.3)`.
#[test]
fn a_newton_failure_reports_the_relative_residual_of_the_last_iterate() {
    let (model, newton) = loaded_pair_without_iterations();
    let mut be = BackwardEuler::new(&model, 0.1, newton).unwrap();
    let mut s = State::new(vec![0.5, -0.25], vec![0.0, 0.0]);
    let r2 = 1.275f64.powi(2) + 1.315625f64.powi(2);
    let f2 = 1.375f64.powi(2) + 1.015625f64.powi(2);
    let expected = (r2 / f2).sqrt();
    match be.step(&model, &mut s, 0.1) {
        Err(SimError::NewtonFailed {
            step,
            iterations,
            residual,
            ..
        }) => {
            assert_eq!((step, iterations), (1, 0));
            assert!(
                (residual - expected).abs() <= 4.0 * f64::EPSILON * expected,
                "reported {residual}, by hand {expected}"
            );
        }
        other => panic!("expected NewtonFailed, got {other:?}"),
    }
}

/// The energy line search on one buckling element, `E = ¼q⁴ − ½q²` (κ = ε = 1, no spring),
/// m = 0.01, one backward Euler step of Δt = 1 from rest at q = 0.1 (`q̂ = 0.1`, `c_q = 1`),
/// so the step minimizes `Ψ(a) = E(0.1 + a) + ½ m a²`. At a = 0 the Newton matrix
/// `m + K_T = 0.01 + 3·0.01 − 1` is negative, so the projected one (`K_T` clipped at 0) is
/// factored, `J = m = 0.01`, and the step `p = −R/J = 0.099/0.01 = 9.9` overshoots to q = 10,
/// where the relative residual is `(0.099 + 990)/990 > 1 = |R(0)|/|f_int(0.1)|`: the line
/// search must backtrack on Ψ (slope `R·p = −0.98`, Ψ(0) = −0.004975). By hand,
/// `Ψ(9.9) = 2450.5`, `Ψ(4.95) = 150.0`, `Ψ(2.475) = 7.71` fail the Armijo bound and
/// `Ψ(1.2375) = −0.0867` (q = 1.3375) passes: the energy is evaluated at least 2 times to
/// choose the start, once at a = 0 and 4 times along the step. The step ends in the right
/// well at the root of `m(q − 0.1) + q³ − q = 0` above `1/√3` (bisection here).
#[test]
fn an_overshooting_projected_newton_step_is_backtracked_on_the_step_energy() {
    let m = 0.01;
    let model = DoubleWell {
        k: SparseMatrix::from_diagonal(&[0.0]),
        kappa: 1.0,
        epsilon: 1.0,
        mass: SystemMatrix::Diagonal(vec![m]),
        damping: None,
        project: true,
        projections: Default::default(),
        energies: Default::default(),
    };
    let mut be = BackwardEuler::new(&model, 1.0, NewtonSettings::default()).unwrap();
    let mut s = State::new(vec![0.1], vec![0.0]);
    be.step(&model, &mut s, 1.0).unwrap();
    assert_eq!(model.projections.load(Ordering::Relaxed), 1);
    let energies = model.energies.load(Ordering::Relaxed);
    assert!(energies >= 7, "{energies} evaluations of the energy");
    let g = |q: f64| m * (q - 0.1) + q * q * q - q;
    let (mut lo, mut hi) = (1.0 / 3f64.sqrt(), 2.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 { hi = mid } else { lo = mid }
    }
    assert!((s.q[0] - lo).abs() < 1e-9, "q = {}, root {lo}", s.q[0]);
    assert!((s.v[0] - (s.q[0] - 0.1)).abs() < 1e-15);
    // A minimum of Ψ, not a stationary point of another kind.
    assert!(SpdSolver::new(&model.tangent_stiffness(&s.q)).is_ok());

    // Stopped after that first iteration, Newton reports the relative residual where the line
    // search left it: a = 9.9/8 = 1.2375, q = 1.3375, by hand `f_int = q³ − q = 1.055162109375`,
    // `m a = 0.012375`, so `|R| / max(|m a|, |f_int|) = 1.067537109375 / 1.055162109375`.
    let newton = NewtonSettings {
        tolerance: 1e-10,
        max_iterations: 1,
    };
    let mut be = BackwardEuler::new(&model, 1.0, newton).unwrap();
    let mut s = State::new(vec![0.1], vec![0.0]);
    let expected = 1.067537109375 / 1.055162109375;
    match be.step(&model, &mut s, 1.0) {
        Err(SimError::NewtonFailed {
            iterations,
            residual,
            ..
        }) => {
            assert_eq!(iterations, 1);
            // The iterate carries the round-off of p = 0.099/0.01 and of the halvings.
            assert!(
                (residual - expected).abs() < 1e-13,
                "reported {residual}, by hand {expected}"
            );
        }
        other => panic!("expected NewtonFailed, got {other:?}"),
    }
}

/// The line search costs nothing where Newton converges: on a mildly hardening chain
/// (`f_int = K q + ε q³`, the DoubleWell without the well, κ = 0, ε = 0.1, |q| < 0.7, m = 1,
/// Δt = 0.05) the Newton matrix changes by at most `c_q·3ε|q|²/m < 4e-4` of itself over the
/// run, so every iteration with a kept factor contracts the residual by about that much and
/// no step raises it: no step is backtracked, and the energy is evaluated only twice a step
/// (the guess and the acceleration that keeps q, to choose the start).
#[test]
fn newton_steps_that_lower_the_residual_are_taken_whole() {
    let c = Chain {
        n: 8,
        k: 3.0,
        m: 1.0,
    };
    let steps = 40;
    for kind in [IntegratorKind::BackwardEuler, IntegratorKind::Newmark] {
        let model = DoubleWell {
            k: c.stiffness(),
            kappa: 0.0,
            epsilon: 0.1,
            mass: SystemMatrix::Diagonal(vec![c.m; c.n]),
            damping: Some(SystemMatrix::Diagonal(vec![0.1; c.n])),
            project: false,
            projections: Default::default(),
            energies: Default::default(),
        };
        let mut s = State::new(initial_positions(c.n), support::initial_velocities(c.n));
        let mut stepper = make_stepper(kind, &model, &s, 0.05).unwrap();
        for _ in 0..steps {
            stepper.step(&model, &mut s, 0.05).unwrap();
        }
        assert!(s.q.iter().all(|x| x.abs() < 0.7), "{kind}: {:?}", s.q);
        assert_eq!(
            model.energies.load(Ordering::Relaxed),
            2 * steps,
            "{kind}: evaluations of the energy"
        );
        assert_eq!(model.projections.load(Ordering::Relaxed), 0, "{kind}");
    }
}

/// A stiff Duffing chain (ε = 50, far from rest) where Newton with a small iteration limit
/// fails on the whole step but converges on its halves: the step is taken as two steps of
/// `Δt/2`, and those are, bit for bit, the two steps of the same scheme built for `Δt/2` (the
/// same operations from the same state and guess), while the time lands exactly on `Δt`.
#[test]
fn a_step_on_which_newton_fails_is_two_steps_of_half_the_size() {
    let (model, start) = stiff_duffing_chain();
    let newton = NewtonSettings {
        tolerance: 1e-10,
        max_iterations: 5,
    };
    let whole_and_halves =
        |stepper: &mut dyn Stepper, halves: &mut dyn Stepper, dt: f64| -> (State, State) {
            let (mut s, mut h) = (start.clone(), start.clone());
            stepper.step(&model, &mut s, dt).unwrap();
            halves.step(&model, &mut h, dt / 2.0).unwrap();
            halves.step(&model, &mut h, dt / 2.0).unwrap();
            (s, h)
        };
    // Backward Euler at Δt = 0.05, Newmark at Δt = 0.2.
    let dt = 0.05;
    let mut be = BackwardEuler::new(&model, dt, newton).unwrap();
    let mut be_half = BackwardEuler::new(&model, dt / 2.0, newton).unwrap();
    let (s, h) = whole_and_halves(&mut be, &mut be_half, dt);
    assert_eq!(be.newton_counts().halved_steps, 1);
    assert_eq!(be_half.newton_counts().halved_steps, 0);
    assert_eq!((&s.q, &s.v), (&h.q, &h.v), "backward Euler");
    assert_eq!(s.t, dt);
    // The whole step used its 5 iterations, the halves as many as the half-step scheme.
    assert_eq!(
        be.newton_counts().iterations,
        5 + be_half.newton_counts().iterations
    );

    let dt = 0.2;
    let mut nm = Newmark::new(&model, &start, dt, newton).unwrap();
    let mut nm_half = Newmark::new(&model, &start, dt / 2.0, newton).unwrap();
    let (s, h) = whole_and_halves(&mut nm, &mut nm_half, dt);
    assert_eq!(nm.newton_counts().halved_steps, 1);
    assert_eq!(nm_half.newton_counts().halved_steps, 0);
    assert_eq!((&s.q, &s.v), (&h.q, &h.v), "Newmark");
    assert_eq!(s.t, dt);
    // Newmark carries the end-of-step acceleration: the next step (halved again, the whole
    // step failing from this state too) goes on exactly as the half-step scheme's third and
    // fourth steps, so the halves left the acceleration of their end.
    let (mut s2, mut h2) = (s.clone(), h.clone());
    nm.step(&model, &mut s2, dt).unwrap();
    nm_half.step(&model, &mut h2, dt / 2.0).unwrap();
    nm_half.step(&model, &mut h2, dt / 2.0).unwrap();
    assert_eq!(nm.newton_counts().halved_steps, 2);
    assert_eq!((&s2.q, &s2.v), (&h2.q, &h2.v), "Newmark, second step");

    // Generalized-α (ρ∞ = 0.8) carries two accelerations, a_n and q̈_n: after the halves both
    // are those of the half-step scheme, so its next two steps are the same too.
    let mut ga = GeneralizedAlpha::new(&model, &start, dt, 0.8, newton).unwrap();
    let mut ga_half = GeneralizedAlpha::new(&model, &start, dt / 2.0, 0.8, newton).unwrap();
    let (mut s, mut h) = whole_and_halves(&mut ga, &mut ga_half, dt);
    assert_eq!(ga.newton_counts().halved_steps, 1);
    assert_eq!(ga_half.newton_counts().halved_steps, 0);
    assert_eq!((&s.q, &s.v), (&h.q, &h.v), "generalized-α");
    assert_eq!(
        (ga.acceleration(), ga.algorithmic_acceleration()),
        (ga_half.acceleration(), ga_half.algorithmic_acceleration())
    );
    ga.step(&model, &mut s, dt).unwrap();
    ga_half.step(&model, &mut h, dt / 2.0).unwrap();
    ga_half.step(&model, &mut h, dt / 2.0).unwrap();
    assert_eq!(ga.newton_counts().halved_steps, 2);
    assert_eq!((&s.q, &s.v), (&h.q, &h.v), "generalized-α, second step");
}

/// When the halves fail too (no Newton iteration allowed: nothing converges), the error is
/// the whole step's, names the halvings tried (down to Δt/64), and the state is left as it
/// was, bit for bit, for both schemes.
#[test]
fn a_step_whose_halves_fail_too_reports_the_whole_step_and_leaves_the_state() {
    let (model, newton) = loaded_pair_without_iterations();
    let start = State::new(vec![0.5, -0.25], vec![0.1, 0.0]);
    let mut be = BackwardEuler::new(&model, 0.1, newton).unwrap();
    let mut nm = Newmark::new(&model, &start, 0.1, newton).unwrap();
    for (name, stepper) in [
        ("backward Euler", &mut be as &mut dyn Stepper),
        ("Newmark", &mut nm),
    ] {
        let mut s = start.clone();
        let err = stepper.step(&model, &mut s, 0.1).unwrap_err();
        match &err {
            SimError::NewtonFailed {
                step,
                iterations,
                halvings,
                time,
                ..
            } => {
                assert_eq!((*step, *iterations, *halvings), (1, 0, 6), "{name}");
                assert_eq!(*time, 0.1, "{name}");
            }
            other => panic!("{name}: expected NewtonFailed, got {other:?}"),
        }
        assert!(
            err.to_string()
                .ends_with("the step tried again in halves down to Δt/64 did not converge either"),
            "{name}: {err}"
        );
        assert_eq!((&s.q, &s.v, s.t), (&start.q, &start.v, start.t), "{name}");
    }
}

/// A step whose halves fail after the first of them succeeded leaves the carried state too as
/// it was: a Duffing chain at rest under a small load that jumps to a large one after
/// `t = 0.05`, one Newton iteration allowed, Δt = 0.1. The whole step fails (the large load),
/// its first half (the small load) converges and moves Newmark's acceleration, generalized-α's
/// two accelerations and backward Euler's guess, its second half fails at every halving.
/// Stepped on after the error with the load kept small, each scheme must go on as a fresh one
/// from the start, up to the Newton factor the failed attempts left behind (a kept factor is
/// only an approximation of the Jacobian, by design): measured 1.0e-12 of the motion in q and
/// 3.6e-12 in v, checked at 2e-11. An acceleration left at the first half's end would move
/// Newmark's predictor by `Δt²/4 Δa`, about 1e-3 of the motion here (generalized-α with only
/// `a_n` restored and `q̈_n` left: 9.7e-4); backward Euler's guess only moves Newton's start,
/// within its tolerance.
#[test]
fn a_failed_step_leaves_no_trace_in_what_the_scheme_carries() {
    let c = Chain {
        n: 3,
        k: 1.0,
        m: 1.0,
    };
    let mut jump = Duffing::new(&c, 50.0);
    jump.force = vec![1e-3, -2e-3, 1.5e-3];
    jump.force_after = Some((0.05, vec![4e3, -3e3, 5e3]));
    let mut small = Duffing::new(&c, 50.0);
    small.force = jump.force.clone();
    let newton = NewtonSettings {
        tolerance: 1e-10,
        max_iterations: 1,
    };
    let start = State::new(vec![0.0; 3], vec![0.0; 3]);
    let dt = 0.1;
    let schemes = |_: ()| -> [(&str, Box<dyn Stepper>); 3] {
        [
            (
                "backward Euler",
                Box::new(BackwardEuler::new(&jump, dt, newton).unwrap()),
            ),
            (
                "Newmark",
                Box::new(Newmark::new(&jump, &start, dt, newton).unwrap()),
            ),
            (
                "generalized-α",
                Box::new(GeneralizedAlpha::new(&jump, &start, dt, 0.8, newton).unwrap()),
            ),
        ]
    };
    for ((name, mut failed), (_, mut fresh)) in schemes(()).into_iter().zip(schemes(())) {
        let mut s = start.clone();
        match failed.step(&jump, &mut s, dt) {
            Err(SimError::NewtonFailed { halvings, .. }) => assert_eq!(halvings, 6, "{name}"),
            other => panic!("{name}: expected NewtonFailed, got {other:?}"),
        }
        assert_eq!((&s.q, &s.v, s.t), (&start.q, &start.v, start.t), "{name}");
        let mut t = start.clone();
        for _ in 0..3 {
            failed.step(&small, &mut s, dt).unwrap();
            fresh.step(&small, &mut t, dt).unwrap();
        }
        let scale = t.q.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let vscale = t.v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        assert!(
            max_abs_diff(&s.q, &t.q) <= 2e-11 * scale && max_abs_diff(&s.v, &t.v) <= 2e-11 * vscale,
            "{name}: q {:?} against {:?}",
            s.q,
            t.q
        );
    }
}

/// A run reports its halved steps: the stiff Duffing chain of the halving test under Newmark
/// with a 5-iteration Newton limit halves some of its steps and still reaches `t_end` on the
/// grid of Δt, with the count the stepper keeps; the default limit of 30 halves none; an
/// explicit run reports none either.
#[test]
fn a_run_reports_how_many_of_its_steps_were_halved() {
    let (model, start) = stiff_duffing_chain();
    let run = |kind: IntegratorKind, dt: f64, iterations: usize| {
        let mut opts = RunOptions::new(dt, 2.0, kind);
        opts.max_newton_iterations = iterations;
        let mut times = Vec::new();
        let summary = simulate(&model, start.clone(), &opts, &mut |s: &Sample<'_>| {
            times.push(s.t)
        })
        .unwrap();
        (summary, times)
    };
    let (summary, times) = run(IntegratorKind::Newmark, 0.2, 5);
    assert!(summary.halved_steps >= 1, "{summary:?}");
    assert_eq!(summary.steps, 10);
    assert_eq!(times.len(), 11);
    for (k, t) in times.iter().enumerate() {
        assert_eq!(*t, k as f64 * 0.2);
    }
    // The count is the stepper's: the same steps one by one.
    let newton = NewtonSettings {
        tolerance: RunOptions::new(0.2, 2.0, IntegratorKind::Newmark).newton_tolerance,
        max_iterations: 5,
    };
    let mut nm = Newmark::new(&model, &start, 0.2, newton).unwrap();
    let mut s = start.clone();
    for _ in 0..10 {
        nm.step(&model, &mut s, 0.2).unwrap();
    }
    assert_eq!(nm.newton_counts().halved_steps, summary.halved_steps);
    assert_eq!(run(IntegratorKind::Newmark, 0.2, 30).0.halved_steps, 0);
    assert_eq!(
        run(IntegratorKind::SymplecticEuler, 0.01, 30)
            .0
            .halved_steps,
        0
    );
}
