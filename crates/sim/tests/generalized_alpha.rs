//! Generalized-α (`integrators/generalized_alpha.rs`) and Newmark on nonlinear models:
//! convergence orders on a stiff Duffing chain against an RK4 reference, the spectral radius
//! of the generalized-α step against Chung & Hulbert's amplification matrix and its limit ρ∞,
//! the reduction to Newmark at ρ∞ = 1, energy conservation and decay, Newmark's energy error on
//! a nonlinear run.

mod support;

use nurbspring_linalg::{DenseMatrix, SparseMatrix, least_squares};
use nurbspring_sim::integrators::{GeneralizedAlpha, GeneralizedAlphaParameters};
use nurbspring_sim::*;
use support::{
    Chain, Duffing, assert_rates, initial_positions, initial_velocities, max_abs_diff,
    observed_rates, sci, tol,
};

/// Runs `simulate` and returns every sample's `(q, v, kinetic + potential)`.
fn trajectory(
    model: &dyn DynamicModel,
    start: &State,
    opts: &RunOptions,
) -> Vec<(Vec<f64>, Vec<f64>, f64)> {
    let mut out = Vec::new();
    let mut obs = |s: &Sample<'_>| out.push((s.q.to_vec(), s.v.to_vec(), s.kinetic + s.potential));
    simulate(model, start.clone(), opts, &mut obs).unwrap();
    out
}

fn final_state(model: &dyn DynamicModel, start: &State, opts: &RunOptions) -> (Vec<f64>, Vec<f64>) {
    let last = trajectory(model, start, opts).pop().unwrap();
    (last.0, last.1)
}

fn generalized_alpha(dt: f64, t_end: f64, rho_infinity: f64) -> RunOptions {
    RunOptions {
        rho_infinity,
        ..RunOptions::new(dt, t_end, IntegratorKind::GeneralizedAlpha)
    }
}

/// The stiff Duffing chain (4 masses, k = 2, ε = 50, m = 1) from rest far from equilibrium,
/// under a load: `ω` up to about 10 along the run.
fn stiff_duffing() -> (Duffing, State) {
    let c = Chain {
        n: 4,
        k: 2.0,
        m: 1.0,
    };
    let mut model = Duffing::new(&c, 50.0);
    model.force = vec![0.1, 0.0, -0.2, 0.05];
    (
        model,
        State::new(vec![0.8, -0.6, 0.7, 0.5], vec![0.0, 0.5, 0.0, -0.2]),
    )
}

/// RK4 at Δt = 1e-4 (ωΔt ≤ 1e-3, error ~ (ωΔt)⁴ relative: far below the errors measured).
fn reference(model: &dyn DynamicModel, start: &State, t_end: f64) -> Vec<f64> {
    final_state(
        model,
        start,
        &RunOptions::new(1e-4, t_end, IntegratorKind::Rk4),
    )
    .0
}

/// Position errors at t = 1 of a scheme at Δt = `dt`, `dt/2`, `dt/4`, `dt/8`.
fn errors_on_stiff_duffing(dt: f64, opts: impl Fn(f64) -> RunOptions) -> Vec<f64> {
    let (model, start) = stiff_duffing();
    let exact = reference(&model, &start, 1.0);
    (0..4)
        .map(|k| {
            let h = dt / f64::from(1 << k);
            max_abs_diff(&final_state(&model, &start, &opts(h)).0, &exact)
        })
        .collect()
}

// ------------------------------------------------------------------ parameters and errors

#[test]
fn parameters_follow_chung_and_hulbert_and_a_bad_rho_is_refused() {
    for rho in [0.0, 0.3, 0.8, 1.0] {
        let p = GeneralizedAlphaParameters::from_rho_infinity(rho).unwrap();
        assert_eq!(p.rho_infinity, rho);
        // Chung & Hulbert: α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1); second order
        // needs γ = ½ − α_m + α_f, and β = ¼(1 − α_m + α_f)².
        assert!((p.alpha_m - (2.0 * rho - 1.0) / (rho + 1.0)).abs() < tol::EXACT);
        assert!((p.alpha_f - rho / (rho + 1.0)).abs() < tol::EXACT);
        assert!((p.gamma - (0.5 - p.alpha_m + p.alpha_f)).abs() < tol::EXACT);
        assert!((p.beta - 0.25 * (1.0 - p.alpha_m + p.alpha_f).powi(2)).abs() < tol::EXACT);
        // Unconditional stability (Chung & Hulbert): α_m ≤ α_f ≤ ½, β ≥ ¼ + ½(α_f − α_m).
        assert!(p.alpha_m <= p.alpha_f && p.alpha_f <= 0.5);
        assert!(p.beta >= 0.25 + 0.5 * (p.alpha_f - p.alpha_m) - tol::EXACT);
    }
    assert_eq!(
        RunOptions::new(0.1, 1.0, IntegratorKind::Newmark).rho_infinity,
        0.8
    );
    let c = Chain {
        n: 3,
        k: 1.0,
        m: 1.0,
    };
    let model = c.model();
    let start = State::new(initial_positions(3), vec![0.0; 3]);
    for bad in [-0.1, 1.5, f64::NAN, f64::INFINITY] {
        let e = simulate(
            &model,
            start.clone(),
            &generalized_alpha(0.1, 1.0, bad),
            &mut NullObserver,
        )
        .unwrap_err();
        assert!(
            matches!(e, SimError::InvalidSpectralRadius { rho_infinity } if rho_infinity.to_bits() == bad.to_bits()),
            "{e:?}"
        );
        assert_eq!(e.kind(), ErrorKind::Input);
        assert!(e.to_string().contains(&format!("ρ∞ = {bad}")), "{e}");
        assert!(
            GeneralizedAlpha::new(&model, &start, 0.1, bad, NewtonSettings::default()).is_err()
        );
    }
    // The other schemes ignore ρ∞.
    let mut opts = RunOptions::new(0.1, 1.0, IntegratorKind::Newmark);
    opts.rho_infinity = 2.0;
    assert!(simulate(&model, start, &opts, &mut NullObserver).is_ok());
}

// ------------------------------------------------------------------ (a) order, nonlinear

/// (a) Second order on the stiff Duffing chain for ρ∞ = 0, 0.5, 0.8 over three halvings of Δt
/// from 0.005 (ωΔt ≤ 0.05). Measured orders: ρ∞ = 0: 2.14, 2.08, 2.04; ρ∞ = 0.5: 2.02, 2.01,
/// 2.00; ρ∞ = 0.8: 2.00, 2.00, 2.00. ρ∞ = 0 nears its order from above: from Δt = 0.02 its
/// orders are 2.29, 2.23, 2.14.
#[test]
fn generalized_alpha_converges_at_second_order_on_a_stiff_duffing_chain() {
    for rho in [0.0, 0.5, 0.8] {
        let e = errors_on_stiff_duffing(0.005, |dt| generalized_alpha(dt, 1.0, rho));
        eprintln!(
            "generalized-alpha ρ∞ = {rho}: errors {}, orders {:.3?}",
            sci(&e),
            observed_rates(&e)
        );
        assert_rates(&format!("generalized-alpha ρ∞ = {rho}"), &e, 2.0);
    }
}

/// (g) Newmark's average acceleration at second order on the same nonlinear run, Δt = 0.02 to
/// 0.0025 (measured orders 2.007, 2.002, 2.000).
#[test]
fn newmark_converges_at_second_order_on_a_stiff_duffing_chain() {
    let e = errors_on_stiff_duffing(0.02, |dt| RunOptions::new(dt, 1.0, IntegratorKind::Newmark));
    eprintln!(
        "newmark: errors {}, orders {:.3?}",
        sci(&e),
        observed_rates(&e)
    );
    assert_rates("newmark", &e, 2.0);
}

// ------------------------------------------------------------------ (b) spectral radius

/// Chung & Hulbert's amplification matrix of the undamped oscillator `q̈ + ω²q = 0` for
/// `Ω = ωΔt` (Δt = 1), in the state `(q, v, a)` with their balance
/// `(1 − α_m) a₁ + α_m a₀ + Ω²((1 − α_f) q₁ + α_f q₀) = 0` and Newmark's updates, column by
/// column (independent of the stepper's code, which solves for `q̈₁`).
fn chung_hulbert_amplification(omega_dt: f64, rho: f64) -> [[f64; 3]; 3] {
    let p = GeneralizedAlphaParameters::from_rho_infinity(rho).unwrap();
    let w2 = omega_dt * omega_dt;
    let mut a = [[0.0; 3]; 3];
    for (j, x) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .iter()
        .enumerate()
    {
        let [q, v, acc] = *x;
        let predictor = q + v + (0.5 - p.beta) * acc;
        let a1 = -(p.alpha_m * acc + w2 * (1.0 - p.alpha_f) * predictor + w2 * p.alpha_f * q)
            / ((1.0 - p.alpha_m) + w2 * (1.0 - p.alpha_f) * p.beta);
        let column = [
            predictor + p.beta * a1,
            v + (1.0 - p.gamma) * acc + p.gamma * a1,
            a1,
        ];
        for i in 0..3 {
            a[i][j] = column[i];
        }
    }
    a
}

/// `(c₂, c₁, c₀)` of the characteristic polynomial `λ³ − c₂λ² + c₁λ − c₀` of a 3 × 3 matrix:
/// trace, sum of the principal 2 × 2 minors, determinant.
fn characteristic(a: &[[f64; 3]; 3]) -> [f64; 3] {
    let minor = |i: usize, j: usize| a[i][i] * a[j][j] - a[i][j] * a[j][i];
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    [
        a[0][0] + a[1][1] + a[2][2],
        minor(0, 1) + minor(0, 2) + minor(1, 2),
        det,
    ]
}

/// The largest root modulus of `λ³ − c₂λ² + c₁λ − c₀` (Cardano; trigonometric form for three
/// real roots, otherwise one real root r and a complex pair of modulus `√(c₀/r)`).
fn spectral_radius([c2, c1, c0]: [f64; 3]) -> f64 {
    // λ = t + c₂/3: t³ + p t + q = 0.
    let shift = c2 / 3.0;
    let p = c1 - c2 * c2 / 3.0;
    let q = -2.0 * c2.powi(3) / 27.0 + c2 * c1 / 3.0 - c0;
    let disc = (q / 2.0).powi(2) + (p / 3.0).powi(3);
    if disc <= 0.0 {
        let r = (-p / 3.0).sqrt();
        let phi = (-q / (2.0 * r.powi(3))).clamp(-1.0, 1.0).acos();
        (0..3)
            .map(|k| {
                (2.0 * r * ((phi + 2.0 * std::f64::consts::PI * k as f64) / 3.0).cos() + shift)
                    .abs()
            })
            .fold(0.0, f64::max)
    } else {
        let s = disc.sqrt();
        let real = (-q / 2.0 + s).cbrt() + (-q / 2.0 - s).cbrt() + shift;
        real.abs().max((c0 / real).abs().sqrt())
    }
}

/// The characteristic polynomial of the stepper itself, identified from its output: on the
/// linear oscillator the state `(q, v, a)` evolves by one 3 × 3 matrix, so `q_k` and `v_k` obey
/// `x_{k+3} = c₂x_{k+2} − c₁x_{k+1} + c₀x_k`; the 16 equations from `k = 0, …, 7` of both are
/// solved in the least-squares sense (Householder QR).
fn measured_characteristic(omega_dt: f64, rho: f64) -> [f64; 3] {
    let model = LinearModel::new(
        SystemMatrix::Diagonal(vec![1.0]),
        SparseMatrix::from_diagonal(&[1.0]),
    );
    let dt = omega_dt;
    let samples = trajectory(
        &model,
        &State::new(vec![1.0], vec![0.3]),
        &generalized_alpha(dt, 10.0 * dt, rho),
    );
    let q: Vec<f64> = samples.iter().map(|s| s.0[0]).collect();
    let v: Vec<f64> = samples.iter().map(|s| s.1[0]).collect();
    let (mut rows, mut rhs) = (Vec::new(), Vec::new());
    for x in [&q, &v] {
        for k in 0..8 {
            rows.extend([x[k + 2], -x[k + 1], x[k]]);
            rhs.push(x[k + 3]);
        }
    }
    let c = least_squares(&DenseMatrix::from_row_major(rhs.len(), 3, rows), &rhs).unwrap();
    [c[0], c[1], c[2]]
}

/// (b) The spectral radius of the step tends to ρ∞ as ωΔt → ∞. At ωΔt = 1000 the stepper's
/// characteristic polynomial, identified from its output, is Chung & Hulbert's (measured:
/// coefficients within 7.5e-11 (ρ∞ = 0.5) and 4.6e-10 (ρ∞ = 0.8), radii within 8e-11), so
/// its spectral radius is theirs: 0.507847 for ρ∞ = 0.5 and 0.807721 for ρ∞ = 0.8, 7.8e-3 and
/// 7.7e-3 above ρ∞ — not within 1e-3: the three roots meet at −ρ∞ at infinity, so the gap
/// closes only as (ωΔt)^{−2/3}, by 10^{2/3} = 4.64 a decade (measured on the stepper 4.66, 4.65
/// and 4.61, 4.63 from ωΔt = 10³ to 10⁵), and falls below 1e-4 only past ωΔt ≈ 10⁶. At
/// ωΔt = 10⁴ and 10⁵ the identification itself loses digits as the roots cluster
/// ([`tol::IDENTIFIED_RADIUS`]).
#[test]
fn the_spectral_radius_is_chung_and_hulberts_and_tends_to_rho_infinity() {
    for rho in [0.5, 0.8] {
        let mut gaps = Vec::new();
        for omega_dt in [1e3, 1e4, 1e5] {
            let expected = characteristic(&chung_hulbert_amplification(omega_dt, rho));
            let measured = measured_characteristic(omega_dt, rho);
            let worst = (0..3).fold(0.0_f64, |m, i| m.max((measured[i] - expected[i]).abs()));
            let (r_measured, r_expected) = (spectral_radius(measured), spectral_radius(expected));
            eprintln!(
                "ρ∞ = {rho}, ωΔt = {omega_dt:e}: polynomial {measured:?} vs {expected:?} (worst {worst:.1e}); radius {r_measured:.6} vs {r_expected:.6}, gap to ρ∞ {:.3e}",
                r_expected - rho
            );
            if omega_dt == 1e3 {
                assert!(
                    worst < tol::AMPLIFICATION,
                    "ωΔt = {omega_dt}: {measured:?} vs {expected:?}"
                );
            }
            assert!(
                (r_measured - r_expected).abs() < tol::IDENTIFIED_RADIUS,
                "ωΔt = {omega_dt}: radius {r_measured} vs {r_expected}"
            );
            gaps.push(r_measured - rho);
        }
        assert!(gaps.iter().all(|&g| g > 0.0), "{gaps:?}");
        // Within 1e-4 of ρ∞ from about ωΔt = 10⁶ (closed form: 7.8e-5 and 8.4e-5 there).
        let far = spectral_radius(characteristic(&chung_hulbert_amplification(1e6, rho)));
        assert!(
            far > rho && far - rho < 1e-4,
            "ρ∞ = {rho}: radius {far} at ωΔt = 1e6"
        );
        for w in gaps.windows(2) {
            let ratio = w[0] / w[1];
            eprintln!("ρ∞ = {rho}: the gap fell by {ratio:.3} a decade");
            assert!(
                (ratio / 10f64.powf(2.0 / 3.0) - 1.0).abs() < tol::ORDER_RATIO,
                "ρ∞ = {rho}: the gap to ρ∞ fell by {ratio} a decade, expected 10^(2/3): {gaps:?}"
            );
        }
    }
    // ρ∞ = 1 keeps every mode: radius 1 at any ωΔt.
    let r = spectral_radius(characteristic(&chung_hulbert_amplification(1e3, 1.0)));
    assert!((r - 1.0).abs() < tol::AMPLIFICATION, "{r}");
}

/// The closed form of the test above checked where it is known by hand. At ρ∞ = 1 (α_m = α_f
/// = ½) the balance is the mean of the equations of motion at both ends, so the residual
/// `r = a + Ω²q` of the state alternates (`r₁ = −r₀`: a root −1) and the other two roots are
/// Newmark's average acceleration, `λ² − 2cλ + 1` with `c = (1 − Ω²/4)/(1 + Ω²/4)`: the
/// polynomial is `(λ + 1)(λ² − 2cλ + 1)`. (The stepper never excites the root −1: it solves the
/// equation of motion, r = 0, at every step.)
#[test]
fn the_closed_form_amplification_at_rho_one_is_newmarks() {
    for omega_dt in [0.5, 3.0, 1e3] {
        let [c2, c1, c0] = characteristic(&chung_hulbert_amplification(omega_dt, 1.0));
        let x = omega_dt * omega_dt / 4.0;
        let c = (1.0 - x) / (1.0 + x);
        // λ³ − c₂λ² + c₁λ − c₀ = λ³ + (1 − 2c)λ² + (1 − 2c)λ + 1.
        assert!(
            (c2 - (2.0 * c - 1.0)).abs() < tol::EXACT,
            "{c2} vs {}",
            2.0 * c - 1.0
        );
        assert!(
            (c1 - (1.0 - 2.0 * c)).abs() < tol::EXACT,
            "{c1} vs {}",
            1.0 - 2.0 * c
        );
        assert!((c0 + 1.0).abs() < tol::EXACT, "{c0}");
    }
}

// ------------------------------------------------------------------ ρ∞ = 1 is Newmark

/// With ρ∞ = 1 (α_m = α_f = ½, β = ¼, γ = ½) the scheme is Newmark's average acceleration:
/// the same trajectory on a loaded linear chain and on the nonlinear Duffing chain (measured:
/// identical, bit for bit: the same predictor, coefficients and Newton guess).
#[test]
fn generalized_alpha_with_rho_one_is_newmark() {
    let c = Chain {
        n: 8,
        k: 3.0,
        m: 0.5,
    };
    let mut linear = c.model();
    linear.force = (0..c.n).map(|i| 0.4 - 0.1 * i as f64).collect();
    let linear_start = State::new(initial_positions(c.n), initial_velocities(c.n));
    let (duffing, duffing_start) = stiff_duffing();
    for (name, model, start, dt) in [
        (
            "linear chain",
            &linear as &dyn DynamicModel,
            &linear_start,
            0.05,
        ),
        ("Duffing chain", &duffing, &duffing_start, 0.01),
    ] {
        let a = trajectory(model, start, &generalized_alpha(dt, 2.0, 1.0));
        let b = trajectory(
            model,
            start,
            &RunOptions::new(dt, 2.0, IntegratorKind::Newmark),
        );
        assert_eq!(a.len(), b.len());
        let worst = a.iter().zip(&b).fold(0.0_f64, |m, (x, y)| {
            m.max(max_abs_diff(&x.0, &y.0))
                .max(max_abs_diff(&x.1, &y.1))
        });
        eprintln!("{name}: generalized-alpha(1) vs newmark: {worst:e}");
        assert!(worst <= tol::EXACT, "{name}: {worst:e}");
        // ρ∞ < 1 is another scheme: the trajectories part.
        let d = trajectory(model, start, &generalized_alpha(dt, 2.0, 0.8));
        let apart = max_abs_diff(&d.last().unwrap().0, &b.last().unwrap().0);
        assert!(
            apart > 1e3 * tol::EXACT,
            "{name}: ρ∞ = 0.8 vs Newmark {apart:e}"
        );
    }
}

// ------------------------------------------------------------------ (c) energy

/// (c) Undamped linear chain under a constant load, 2000 steps of Δt = 0.1: with ρ∞ = 1 the
/// energy is conserved to round-off (measured 7.4e-15 relative); with ρ∞ = 0.5 the scheme
/// damps the modes (ωΔt from 0.07 to 0.49) and the run loses a measured 58 % of its energy
/// (not monotonically: the energy of `(q, v)` leaves out the algorithmic acceleration).
#[test]
fn generalized_alpha_conserves_energy_at_rho_one_and_dissipates_below() {
    let c = Chain {
        n: 8,
        k: 3.0,
        m: 0.5,
    };
    let mut model = c.model();
    model.rest = (0..c.n).map(|i| 0.1 * i as f64).collect();
    model.force = (0..c.n).map(|i| 0.4 - 0.1 * i as f64).collect();
    let start = State::new(initial_positions(c.n), initial_velocities(c.n));
    let energies = |rho: f64| -> Vec<f64> {
        trajectory(&model, &start, &generalized_alpha(0.1, 200.0, rho))
            .into_iter()
            .map(|s| s.2)
            .collect()
    };
    let e = energies(1.0);
    assert_eq!(e.len(), 2001);
    let drift = e.iter().fold(0.0_f64, |m, x| m.max((x - e[0]).abs())) / e[0].abs();
    eprintln!("energy drift ρ∞ = 1: {drift:e}");
    assert!(
        drift < tol::ENERGY_ROUNDOFF,
        "ρ∞ = 1: energy drift {drift:e}"
    );
    let e = energies(0.5);
    let loss = (e[0] - e[e.len() - 1]) / e[0].abs();
    eprintln!("energy loss ρ∞ = 0.5: {loss:e}");
    assert!(loss > 0.5, "ρ∞ = 0.5: energy loss {loss:e}");
}

// ------------------------------------------------------------------ (h) Newmark energy, nonlinear

/// (h) Newmark's average acceleration is the trapezoidal rule, which conserves a linear
/// model's energy exactly but not a nonlinear one's: on the undamped, unloaded stiff Duffing
/// chain over 20 time units (≈ 30 periods of its fastest motion) the relative energy error
/// stays bounded — no drift: the last quarter of the run is no worse than the first — and
/// falls as Δt² (measured errors and orders printed).
#[test]
fn newmark_energy_error_on_a_nonlinear_run_is_bounded_and_falls_as_dt_squared() {
    let (mut model, start) = stiff_duffing();
    model.force = vec![0.0; 4];
    let mut errors = Vec::new();
    for dt in [0.02, 0.01, 0.005, 0.0025] {
        let e: Vec<f64> = trajectory(
            &model,
            &start,
            &RunOptions::new(dt, 20.0, IntegratorKind::Newmark),
        )
        .into_iter()
        .map(|s| s.2)
        .collect();
        let dev = |part: &[f64]| part.iter().fold(0.0_f64, |m, x| m.max((x - e[0]).abs())) / e[0];
        let quarter = e.len() / 4;
        let (first, last, all) = (dev(&e[..quarter]), dev(&e[e.len() - quarter..]), dev(&e));
        eprintln!(
            "newmark Δt = {dt}: energy error first quarter {first:.3e}, last {last:.3e}, all {all:.3e}"
        );
        assert!(
            last <= 1.5 * first,
            "Δt = {dt}: energy error grew from {first:e} to {last:e}"
        );
        errors.push(all);
    }
    eprintln!(
        "newmark energy error orders {:.3?}",
        observed_rates(&errors)
    );
    assert_rates("newmark energy error", &errors, 2.0);
}
