//! The explicit schemes with a consistent (sparse, non-diagonal) mass: the factored path
//! against the diagonal one, convergence orders on a nonlinear chain, and the stability limit
//! of the generalized eigenproblem `(K, M)` with the mass as it is.

mod support;

use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::integrators::{MassInverse, Rk4, SymplecticEuler, VelocityVerlet};
use nurbspring_sim::*;
use support::{
    Chain, Duffing, assert_rates, initial_positions, initial_velocities, max_abs_diff,
    observed_rates, sci, tol,
};

fn chain() -> Chain {
    Chain {
        n: 8,
        k: 3.0,
        m: 0.5,
    }
}

/// Runs `stepper` for `steps` steps of `dt` and returns every state.
fn steps(
    model: &dyn DynamicModel,
    stepper: &mut dyn Stepper,
    start: &State,
    dt: f64,
    steps: usize,
) -> Vec<State> {
    let mut s = start.clone();
    (0..steps)
        .map(|_| {
            stepper.step(model, &mut s, dt).unwrap();
            s.clone()
        })
        .collect()
}

fn worst(a: &[State], b: &[State]) -> f64 {
    a.iter().zip(b).fold(0.0_f64, |m, (x, y)| {
        m.max(max_abs_diff(&x.q, &y.q))
            .max(max_abs_diff(&x.v, &y.v))
    })
}

fn final_state(model: &dyn DynamicModel, start: &State, opts: &RunOptions) -> State {
    let mut last = start.clone();
    let mut obs = |s: &Sample<'_>| {
        last.t = s.t;
        last.q.copy_from_slice(s.q);
        last.v.copy_from_slice(s.v);
    };
    simulate(model, start.clone(), opts, &mut obs).unwrap();
    last
}

// ------------------------------------------------------------------ (d) factored = diagonal

/// (d) A diagonal mass run through the factored path (its Cholesky factor, two triangular
/// solves a force evaluation) gives the diagonal path's trajectory to round-off: 2000 steps of
/// each explicit scheme on the loaded chain, undamped and with diagonal damping (Verlet's
/// factored path then solves `(M + ½ΔtD) a⁺ = f − D v½`, the diagonal one divides by
/// `m + ½Δt d`). Measured: at most 2.3e-13 in q and v undamped, 1.7e-15 damped (the motion is
/// of order 1; [`tol::FACTORED_MASS`]). A `Sparse` mass that happens to be diagonal takes the
/// diagonal path itself, bit for bit.
#[test]
fn a_diagonal_mass_through_the_factor_gives_the_diagonal_path() {
    let c = chain();
    let mut model = c.model();
    model.rest = (0..c.n).map(|i| 0.1 * i as f64).collect();
    model.force = (0..c.n).map(|i| 0.4 - 0.1 * i as f64).collect();
    let start = State::new(initial_positions(c.n), initial_velocities(c.n));
    let dt = 0.5 * stability_limit(&model, &start.q).unwrap().dt_critical;
    let sparse_mass = model.mass.to_sparse();
    let factored = || MassInverse::factored(&sparse_mass).unwrap();
    assert!(!factored().is_diagonal());
    for damping in [None, Some(SystemMatrix::Diagonal(vec![0.3; c.n]))] {
        model.damping = damping;
        let damped = model.damping.is_some();
        let pairs: [(&str, Box<dyn Stepper>, Box<dyn Stepper>); 3] = [
            (
                "symplectic-euler",
                Box::new(SymplecticEuler::new(&model).unwrap()),
                Box::new(SymplecticEuler::with_mass_inverse(&model, factored()).unwrap()),
            ),
            (
                "verlet",
                Box::new(VelocityVerlet::new(&model, &start).unwrap()),
                Box::new(VelocityVerlet::with_mass_inverse(&model, &start, factored()).unwrap()),
            ),
            (
                "rk4",
                Box::new(Rk4::new(&model).unwrap()),
                Box::new(Rk4::with_mass_inverse(&model, factored()).unwrap()),
            ),
        ];
        for (name, mut diagonal, mut through_factor) in pairs {
            let a = steps(&model, diagonal.as_mut(), &start, dt, 2000);
            let b = steps(&model, through_factor.as_mut(), &start, dt, 2000);
            let w = worst(&a, &b);
            eprintln!("{name} (damped: {damped}): factored vs diagonal {w:e}");
            assert!(w < tol::FACTORED_MASS, "{name} (damped: {damped}): {w:e}");
        }
    }
    // The same mass stored as a sparse matrix is recognised as diagonal: the same run, bit for
    // bit, through `simulate`.
    let mut sparse = model.clone();
    sparse.mass = SystemMatrix::Sparse(sparse_mass.clone());
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
    ] {
        let opts = RunOptions::new(dt, 200.0 * dt, kind);
        let (a, b) = (
            final_state(&model, &start, &opts),
            final_state(&sparse, &start, &opts),
        );
        assert_eq!((&a.q, &a.v), (&b.q, &b.v), "{kind}");
    }
}

// ------------------------------------------------------------------ (e) orders, nonlinear

/// The Duffing chain (k = 2, ε = 8, m = 1) with the consistent mass `(m/6)·tridiag(1, 4, 1)`,
/// loaded, optionally with the sparse damping `D = 0.05 M + 0.01 K`.
fn consistent_duffing(damped: bool) -> (Duffing, State) {
    let c = Chain {
        n: 4,
        k: 2.0,
        m: 1.0,
    };
    let mut model = Duffing::new(&c, 8.0);
    model.mass = SystemMatrix::Sparse(c.consistent_mass());
    model.force = vec![0.1, 0.0, -0.2, 0.05];
    if damped {
        model.damping = Some(SystemMatrix::Sparse(
            SparseMatrix::linear_combination(0.05, &c.consistent_mass(), 0.01, &c.stiffness())
                .unwrap(),
        ));
    }
    (
        model,
        State::new(vec![0.5, -0.3, 0.4, 0.2], vec![0.0, 0.5, 0.0, -0.2]),
    )
}

/// (e) Velocity Verlet (the central difference) at second order and symplectic Euler at first
/// order with the consistent mass on the nonlinear Duffing chain, undamped and with the sparse
/// damping (Verlet's last half step implicit in D through the factor of `M + ½ΔtD`), against
/// RK4 with the same mass at Δt = 1e-4; three halvings of Δt below a quarter of the stability
/// limit at the start. Measured orders: Verlet 2.001, 2.000, 2.000 (undamped and damped),
/// symplectic Euler 1.008, 1.004, 1.002 (damped 1.007, 1.004, 1.002).
#[test]
fn explicit_schemes_keep_their_order_with_a_consistent_mass_on_a_nonlinear_chain() {
    for damped in [false, true] {
        let (model, start) = consistent_duffing(damped);
        let t_end = 1.0;
        let reference = final_state(
            &model,
            &start,
            &RunOptions::new(1e-4, t_end, IntegratorKind::Rk4),
        );
        let limit = stability_limit(&model, &start.q).unwrap().dt_critical;
        for (kind, order, dt0) in [
            (IntegratorKind::VelocityVerlet, 2.0, 0.02),
            (IntegratorKind::SymplecticEuler, 1.0, 0.004),
        ] {
            assert!(dt0 < 0.25 * limit, "{dt0} vs the limit {limit}");
            let e: Vec<f64> = (0..4)
                .map(|k| {
                    let dt = dt0 / f64::from(1 << k);
                    max_abs_diff(
                        &final_state(&model, &start, &RunOptions::new(dt, t_end, kind)).q,
                        &reference.q,
                    )
                })
                .collect();
            eprintln!(
                "{kind} consistent mass (damped: {damped}): errors {}, orders {:.3?} (limit {limit:.4})",
                sci(&e),
                observed_rates(&e)
            );
            assert_rates(
                &format!("{kind} (consistent mass, damped: {damped})"),
                &e,
                order,
            );
        }
    }
}

// ------------------------------------------------------------------ (f) the limit of (K, M)

/// (f) With the consistent mass the chain's frequencies are
/// `ω_j² = k(2 − 2cos θ_j)/((m/6)(4 + 2cos θ_j))` (the modes of K and M coincide), so the
/// highest is about √3 above the lumped mass's `2√(k/m) sin(nπ/(2(n+1)))`. Both stability
/// limits solve the generalized eigenproblem `(K, M)` with the mass as given (Lanczos on
/// `M⁻¹K` with the factor of M): the limit at a state, the uniform one from the stiffness
/// bound, and the uniform one of the same chain in 3-D (`K ⊗ I₃`, `M ⊗ I₃`, solved on the
/// factors) all give the analytic ω_max. `simulate` refuses every explicit scheme above
/// `2/ω_max`, including at steps below the lumped-mass limit; run anyway, Verlet and
/// symplectic Euler diverge; just below the limit they stay bounded.
#[test]
fn the_stability_limit_is_that_of_the_consistent_mass() {
    let c = chain();
    let mut model = c.model();
    model.mass = SystemMatrix::Sparse(c.consistent_mass());
    let w = c.consistent_omega(c.n);
    let lumped = c.omega(c.n);
    assert!(w > 1.6 * lumped, "{w} vs {lumped}");
    let (q0, v0) = (initial_positions(c.n), initial_velocities(c.n));
    let at_q = stability_limit(&model, &q0).unwrap();
    let uniform = uniform_stability_limit(&model).unwrap().unwrap();
    let spatial = LinearModel::new(
        SystemMatrix::Sparse(c.consistent_mass().kron_identity(3)),
        c.stiffness().kron_identity(3),
    );
    let uniform_3d = uniform_stability_limit(&spatial).unwrap().unwrap();
    let at_q_3d = stability_limit(&spatial, &vec![0.0; 3 * c.n]).unwrap();
    for (name, limit) in [
        ("at q₀", at_q),
        ("uniform", uniform),
        ("uniform, 3-D", uniform_3d),
        ("at q₀, 3-D", at_q_3d),
    ] {
        assert!(
            (limit.omega_max - w).abs() < tol::OMEGA * w,
            "{name}: {} vs {w}",
            limit.omega_max
        );
        assert!(
            (limit.dt_critical - 2.0 / w).abs() < tol::OMEGA * 2.0 / w,
            "{name}"
        );
    }
    let dt_crit = at_q.dt_critical;
    let start = State::new(q0.clone(), v0.clone());
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
    ] {
        // Refused just above the limit and well below the lumped mass's limit 2/ω_lumped.
        for dt in [1.01 * dt_crit, 0.9 * 2.0 / lumped] {
            assert!(dt > dt_crit);
            match simulate(
                &model,
                start.clone(),
                &RunOptions::new(dt, 100.0 * dt, kind),
                &mut NullObserver,
            ) {
                Err(SimError::Unstable {
                    dt: refused,
                    dt_critical,
                    integrator,
                }) => {
                    assert_eq!((refused, integrator), (dt, kind.name()));
                    assert!((dt_critical - 2.0 / w).abs() < tol::OMEGA * dt_critical);
                }
                other => panic!("{kind} at Δt = {dt}: expected Unstable, got {other:?}"),
            }
        }
        if kind == IntegratorKind::Rk4 {
            continue; // its own limit is 2√2/ω_max: 1.01 Δt_crit is stable for it
        }
        // Forced above the limit: diverges (the highest mode grows every step).
        let mut forced = RunOptions::new(1.01 * dt_crit, 5000.0 * 1.01 * dt_crit, kind);
        forced.force_unstable = true;
        match simulate(&model, start.clone(), &forced, &mut NullObserver) {
            Err(SimError::Diverged { step, .. }) => {
                assert!(step > 1 && step < 5000, "{kind}: {step}")
            }
            other => panic!("{kind}: expected Diverged, got {other:?}"),
        }
        // Just below: bounded over 20 000 steps.
        let below = 0.99 * dt_crit;
        let mut peak = 0.0_f64;
        let mut obs =
            |s: &Sample<'_>| peak = peak.max(s.q.iter().fold(0.0_f64, |m, x| m.max(x.abs())));
        let summary = simulate(
            &model,
            start.clone(),
            &RunOptions::new(below, 20_000.0 * below, kind),
            &mut obs,
        )
        .unwrap();
        assert_eq!(summary.dt_critical, Some(dt_crit));
        let amplitude = q0.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        eprintln!("{kind}: peak {peak} just below the limit (start {amplitude})");
        assert!(peak < 50.0 * (amplitude + 1.0), "{kind}: peak {peak}");
    }
}

/// A mass that is not positive definite is refused when the stepper is built, naming the
/// scheme and the failure; a diagonal one naming the entry.
#[test]
fn a_mass_that_is_not_positive_definite_is_refused() {
    let c = chain();
    let start = State::new(initial_positions(c.n), vec![0.0; c.n]);
    let mut model = c.model();
    // (m/6)·tridiag(1, 4, 1) + ½·tridiag(1, 0, 1): eigenvalues 4m/6 + 2(m/6 + ½) cos θ_j, negative
    // near θ = π for m = 0.5 (0.33 − 1.17 cos-weighted).
    model.mass = SystemMatrix::Sparse(
        SparseMatrix::linear_combination(1.0, &c.consistent_mass(), 0.5, &{
            let mut t = Vec::new();
            for i in 0..c.n - 1 {
                t.push((i, i + 1, 1.0));
                t.push((i + 1, i, 1.0));
            }
            SparseMatrix::from_triplets(c.n, c.n, &t).unwrap()
        })
        .unwrap(),
    );
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
    ] {
        match make_stepper(kind, &model, &start, 0.01) {
            Err(e @ SimError::NotSupported { integrator, .. }) => {
                assert_eq!(integrator, kind.name());
                assert!(e.to_string().contains("positive definite"), "{e}");
                assert_eq!(e.kind(), ErrorKind::Input);
            }
            Err(other) => panic!("{kind}: {other:?}"),
            Ok(_) => panic!("{kind}: accepted an indefinite mass"),
        }
    }
    model.mass = SystemMatrix::Diagonal(vec![0.5, 0.5, 0.0, 0.5, 0.5, 0.5, 0.5, 0.5]);
    match make_stepper(IntegratorKind::VelocityVerlet, &model, &start, 0.01) {
        Err(e) => assert!(e.to_string().contains("mass entry 2 is 0"), "{e}"),
        Ok(_) => panic!("accepted a zero mass"),
    }
}
