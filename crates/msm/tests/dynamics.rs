//! The MSM as a `sim::DynamicModel`: a spring chain's frequencies, energy and momentum of the
//! symplectic schemes, implicit/explicit convergence, and the explicit stability limit.

mod support;

use std::f64::consts::PI;

use nurbspring_linalg::generalized_symmetric_eigen;
use nurbspring_msm::{MsmModel, Spring, SpringKind, SpringLattice};
use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Sample, SimError, State, simulate};
use support::tolerances::*;
use support::{Lcg, curved_lattice};

/// `n` free masses `m` between two fixed ends, springs `k` of rest length `l` at spacing `h`
/// along x.
fn chain(n: usize, k: f64, m: f64, h: f64, l: f64) -> SpringLattice {
    let positions: Vec<[f64; 3]> = (0..n + 2).map(|i| [h * i as f64, 0.0, 0.0]).collect();
    let springs = (0..n + 1)
        .map(|i| Spring {
            a: i,
            b: i + 1,
            kind: SpringKind::Structural,
            k,
            rest_length: l,
            weight: 1.0,
            damping: 0.0,
        })
        .collect();
    let mut fixed = vec![false; n + 2];
    fixed[0] = true;
    fixed[n + 1] = true;
    SpringLattice::from_parts(
        positions,
        vec![m; n + 2],
        vec![0.0; n + 2],
        fixed,
        springs,
        [0.0; 3],
    )
    .unwrap()
}

/// ω_j = 2 √(k/m) sin(jπ / (2(N+1))), j = 1..N.
fn chain_omegas(n: usize, k: f64, m: f64) -> Vec<f64> {
    (1..=n)
        .map(|j| 2.0 * (k / m).sqrt() * (j as f64 * PI / (2.0 * (n + 1) as f64)).sin())
        .collect()
}

fn frequencies(model: &MsmModel) -> Vec<f64> {
    let q0 = model.initial_positions();
    let k = model.tangent_stiffness(q0).to_dense();
    let m = model.mass().to_sparse().to_dense();
    let eig = generalized_symmetric_eigen(&k, &m).unwrap();
    eig.values.iter().map(|&l| l.max(0.0).sqrt()).collect()
}

#[test]
fn spring_chain_frequencies() {
    let (n, k, m) = (12, 3.0, 0.25);
    // At rest length: N longitudinal modes by the formula, 2N transverse modes at zero.
    let model = MsmModel::new(chain(n, k, m, 0.5, 0.5)).unwrap();
    let omega = frequencies(&model);
    assert_eq!(omega.len(), 3 * n);
    let expected = chain_omegas(n, k, m);
    let omega_max = expected[n - 1];
    let worst = omega[2 * n..]
        .iter()
        .zip(&expected)
        .map(|(w, e)| (w - e).abs() / e)
        .fold(0.0, f64::max);
    eprintln!("chain at rest: worst relative frequency error {worst:e}");
    for (w, e) in omega[2 * n..].iter().zip(&expected) {
        assert!((w - e).abs() < CHAIN_FREQUENCY * e, "ω = {w}, expected {e}");
    }
    assert!(omega[..2 * n].iter().all(|w| *w < 1e-6 * omega_max));
    // Under tension (rest length 0.4 at spacing 0.5): the geometric stiffness k (1 − l/h)
    // gives two transverse families with k_t = 0.2 k; the longitudinal ones keep k.
    let model = MsmModel::new(chain(n, k, m, 0.5, 0.4)).unwrap();
    let omega = frequencies(&model);
    let mut expected: Vec<f64> = chain_omegas(n, k, m);
    let transverse = chain_omegas(n, 0.2 * k, m);
    expected.extend(&transverse);
    expected.extend(&transverse);
    expected.sort_by(f64::total_cmp);
    for (w, e) in omega.iter().zip(&expected) {
        assert!((w - e).abs() < CHAIN_FREQUENCY * e, "ω = {w}, expected {e}");
    }
    // The stability limit is 2/ω_max.
    let limit = model.stability().unwrap();
    let w_max = chain_omegas(n, k, m)[n - 1];
    assert!(
        (limit.omega_max - w_max).abs() < 1e-8 * w_max,
        "{} vs {w_max}",
        limit.omega_max
    );
    assert!((limit.dt_critical - 2.0 / w_max).abs() < 1e-8 / w_max);
}

/// A pre-strained curved lattice with its u = 0 edge fixed and a random initial velocity.
fn tense_sheet(seed: u64, amplitude: f64) -> (MsmModel, State) {
    let mut lattice = curved_lattice(5, 4, 0.05);
    for a in 0..4 {
        lattice.fixed[a] = true;
    }
    let model = MsmModel::new(lattice).unwrap();
    let mut rng = Lcg(seed);
    let v: Vec<[f64; 3]> = (0..20)
        .map(|_| [0.0; 3].map(|_| amplitude * rng.next()))
        .collect();
    let state = model.initial_state(&v);
    (model, state)
}

/// Total energy at every sample.
fn energies(
    model: &MsmModel,
    initial: State,
    dt: f64,
    t_end: f64,
    kind: IntegratorKind,
) -> Vec<f64> {
    let mut e = Vec::new();
    let mut observer = |s: &Sample<'_>| e.push(s.kinetic + s.potential);
    simulate(
        model,
        initial,
        &RunOptions::new(dt, t_end, kind),
        &mut observer,
    )
    .unwrap();
    e
}

#[test]
fn symplectic_schemes_keep_energy_bounded() {
    let (model, state) = tense_sheet(11, 0.3);
    let dt_crit = model.stability().unwrap().dt_critical;
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
    ] {
        let dt = 0.1 * dt_crit;
        let e = energies(&model, state.clone(), dt, 20_000.0 * dt, kind);
        let e0 = e[0];
        let half = e.len() / 2;
        let dev = |s: &[f64]| s.iter().map(|x| (x - e0).abs()).fold(0.0, f64::max) / e0;
        let (first, second) = (dev(&e[..half]), dev(&e[half..]));
        // Bounded oscillation, O(Δt ω) for symplectic Euler, O((Δt ω)²) for Verlet; no drift.
        eprintln!("{kind:?}: max |E − E0|/E0 {first:e} (first half), {second:e} (second half)");
        assert!(
            first < 0.1 && second < 0.1,
            "{kind:?}: deviation {first:e}, {second:e}"
        );
        assert!(
            second < 1.5 * first,
            "{kind:?}: energy drifts: {first:e} then {second:e}"
        );
    }
}

#[test]
fn energy_with_gravity_includes_the_load_potential() {
    // The sheet falls and swings (kinetic energy ≫ initial energy): kinetic + elastic
    // − (q − q0)ᵀ m g must stay constant up to Verlet's O(Δt²) error.
    let (model, state) = tense_sheet(15, 0.1);
    let mut lattice = model.lattice().clone();
    lattice.gravity = [0.0, 0.0, -0.2];
    let model = MsmModel::new(lattice).unwrap();
    let dt = 0.05 * model.stability().unwrap().dt_critical;
    let mut samples = Vec::new();
    let mut observer = |s: &Sample<'_>| samples.push((s.kinetic, s.potential));
    let opts = RunOptions::new(dt, 10_000.0 * dt, IntegratorKind::VelocityVerlet);
    simulate(&model, state, &opts, &mut observer).unwrap();
    let e0 = samples[0].0 + samples[0].1;
    let scale = samples.iter().map(|s| s.0).fold(0.0, f64::max);
    let dev = samples
        .iter()
        .map(|s| (s.0 + s.1 - e0).abs())
        .fold(0.0, f64::max)
        / scale;
    eprintln!("Verlet with gravity: max |E − E0| / max kinetic = {dev:e}");
    assert!(scale > 10.0 * e0.abs(), "the sheet should fall");
    assert!(dev < 1e-2, "total energy with gravity drifts by {dev:e}");
}

#[test]
fn momentum_is_conserved_without_fixed_nodes_or_gravity() {
    let lattice = curved_lattice(5, 4, 0.05);
    let masses = lattice.masses.clone();
    let model = MsmModel::new(lattice).unwrap();
    let mut rng = Lcg(12);
    let v: Vec<[f64; 3]> = (0..20)
        .map(|_| [0.0; 3].map(|_| 0.5 * rng.next()))
        .collect();
    let dt = 0.2 * model.stability().unwrap().dt_critical;
    for kind in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
    ] {
        let mut momenta: Vec<[f64; 3]> = Vec::new();
        let mut scale = 0.0f64;
        let mut observer = |s: &Sample<'_>| {
            let mut p = [0.0; 3];
            let mut sum_abs = 0.0;
            for (a, v) in s.v.chunks(3).enumerate() {
                for c in 0..3 {
                    p[c] += masses[a] * v[c];
                    sum_abs += masses[a] * v[c].abs();
                }
            }
            scale = scale.max(sum_abs);
            momenta.push(p);
        };
        simulate(
            &model,
            model.initial_state(&v),
            &RunOptions::new(dt, 2000.0 * dt, kind),
            &mut observer,
        )
        .unwrap();
        let p0 = momenta[0];
        let drift = momenta
            .iter()
            .flat_map(|p| (0..3).map(move |c| (p[c] - p0[c]).abs()))
            .fold(0.0, f64::max);
        eprintln!("{kind:?}: momentum drift {drift:e} (scale Σ m|v| = {scale})");
        assert!(
            drift < MOMENTUM * scale,
            "{kind:?}: momentum drift {drift:e} (scale {scale})"
        );
    }
}

/// Free positions at t_end.
fn final_positions(
    model: &MsmModel,
    initial: &State,
    dt: f64,
    t_end: f64,
    kind: IntegratorKind,
) -> Vec<f64> {
    let mut last = Vec::new();
    let mut observer = |s: &Sample<'_>| {
        last.clear();
        last.extend_from_slice(s.q);
    };
    simulate(
        model,
        initial.clone(),
        &RunOptions::new(dt, t_end, kind),
        &mut observer,
    )
    .unwrap();
    last
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn implicit_and_explicit_runs_converge_to_the_same_trajectory() {
    let (model, state) = tense_sheet(13, 0.3);
    let dt_crit = model.stability().unwrap().dt_critical;
    // Short enough that backward Euler's damping of the stiffest modes, ≈ exp(−t ω² Δt / 2),
    // is in its asymptotic regime for every Δt below.
    let t_end = 4.0 * dt_crit;
    let reference = final_positions(&model, &state, dt_crit / 512.0, t_end, IntegratorKind::Rk4);
    let mut gaps = Vec::new();
    for refine in [32.0, 64.0, 128.0] {
        let dt = dt_crit / refine;
        let implicit = final_positions(&model, &state, dt, t_end, IntegratorKind::BackwardEuler);
        let explicit = final_positions(&model, &state, dt, t_end, IntegratorKind::VelocityVerlet);
        let (e_impl, e_expl) = (
            distance(&implicit, &reference),
            distance(&explicit, &reference),
        );
        gaps.push((distance(&implicit, &explicit), e_impl, e_expl));
    }
    eprintln!("(gap, backward Euler error, Verlet error): {gaps:?}");
    for w in gaps.windows(2) {
        let (g0, i0, x0) = w[0];
        let (g1, i1, x1) = w[1];
        // Backward Euler is first order, Verlet second order: halving Δt halves the gap.
        assert!(
            (1.6..2.5).contains(&(i0 / i1)),
            "backward Euler error ratio {}",
            i0 / i1
        );
        assert!(
            (3.0..5.0).contains(&(x0 / x1)),
            "Verlet error ratio {}",
            x0 / x1
        );
        assert!(g1 < 0.65 * g0, "gap {g0:e} → {g1:e}");
    }
}

/// Largest |q − q0| over the last half of a symplectic-Euler run at `factor × Δt_crit`,
/// relative to the largest over its first 300 steps; `None` when the run reported divergence.
fn growth(model: &MsmModel, state: &State, factor: f64, steps: usize) -> Option<f64> {
    let dt = factor * model.stability().unwrap().dt_critical;
    let q0 = state.q.clone();
    let mut amplitude = Vec::new();
    let mut observer = |s: &Sample<'_>| {
        amplitude.push(
            s.q.iter()
                .zip(&q0)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max),
        );
    };
    let mut opts = RunOptions::new(dt, steps as f64 * dt, IntegratorKind::SymplecticEuler);
    opts.force_unstable = true;
    match simulate(model, state.clone(), &opts, &mut observer) {
        Ok(_) => {
            let early = amplitude[..300].iter().copied().fold(0.0, f64::max);
            let late = amplitude[steps / 2..].iter().copied().fold(0.0, f64::max);
            Some(late / early)
        }
        Err(SimError::Diverged { .. }) => None,
        Err(e) => panic!("unexpected error {e}"),
    }
}

#[test]
fn explicit_runs_diverge_just_above_the_stability_limit() {
    // A flat sheet at rest, tiny in-plane velocities: the linearized model holds.
    let mut lattice = curved_lattice(6, 5, 0.0);
    for p in &mut lattice.positions {
        p[2] = 0.0;
    }
    let x0 = lattice.flat_positions();
    for s in &mut lattice.springs {
        s.rest_length = s.length(&x0);
    }
    for a in [0, 4, 25, 29] {
        lattice.fixed[a] = true;
    }
    let model = MsmModel::new(lattice).unwrap();
    let mut rng = Lcg(14);
    let v: Vec<[f64; 3]> = (0..30)
        .map(|_| [1e-6 * rng.next(), 1e-6 * rng.next(), 0.0])
        .collect();
    let state = model.initial_state(&v);
    let below = growth(&model, &state, 0.98, 3000).expect("stable below the limit");
    let above = growth(&model, &state, 1.02, 3000);
    eprintln!("growth at 0.98 Δt_crit: {below}; at 1.02 Δt_crit: {above:?} (None = diverged)");
    assert!(below < 2.0, "amplitude grew {below}× below the limit");
    match above {
        None => {}
        Some(above) => assert!(above > 1e6, "amplitude grew only {above}× above the limit"),
    }
    // Without force_unstable the simulator refuses to start above the limit.
    let dt = 1.02 * model.stability().unwrap().dt_critical;
    let opts = RunOptions::new(dt, 10.0 * dt, IntegratorKind::SymplecticEuler);
    let r = simulate(&model, state, &opts, &mut |_: &Sample<'_>| {});
    assert!(
        matches!(r, Err(SimError::Unstable { .. })),
        "expected Unstable"
    );
}

#[test]
fn damping_and_gravity_settle_a_sagging_membrane() {
    // Damping −γ ẋ (docs/math.md §5) removes energy: a pre-strained sheet under gravity, held at its
    // u = 0 and u = 1 edges, comes to rest where f_elastic + m g = 0.
    let mut lattice = curved_lattice(4, 4, 0.05);
    for a in (0..4).chain(12..16) {
        lattice.fixed[a] = true;
    }
    lattice.set_damping(2.0);
    lattice.gravity = [0.0, 0.0, -0.5];
    let model = MsmModel::new(lattice).unwrap();
    assert!(model.damping().is_some());
    let last = final_positions(
        &model,
        &model.initial_state(&[]),
        1.0,
        1500.0,
        IntegratorKind::BackwardEuler,
    );
    let mut f_int = vec![0.0; last.len()];
    let mut f_ext = vec![0.0; last.len()];
    model.internal_force(&last, &mut f_int);
    model.external_force(0.0, &mut f_ext);
    let residual: f64 = f_int
        .iter()
        .zip(&f_ext)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    let load: f64 = f_ext.iter().map(|b| b * b).sum::<f64>().sqrt();
    assert!(
        residual < 1e-6 * load,
        "static residual {residual:e} vs load {load:e}"
    );
    // It sagged.
    let sag = last
        .iter()
        .skip(2)
        .step_by(3)
        .zip(model.initial_positions().iter().skip(2).step_by(3));
    assert!(sag.map(|(z, z0)| z - z0).sum::<f64>() < 0.0);
}

/// `integrator_problem` accepts exactly the listed integrators and names them when it refuses.
#[test]
fn integrator_problem_lists_the_integrators_of_the_mass_spring_model() {
    for kind in IntegratorKind::ALL {
        let problem = MsmModel::integrator_problem(kind);
        assert_eq!(
            problem.is_none(),
            MsmModel::INTEGRATORS.contains(&kind),
            "{kind}"
        );
        if let Some(text) = problem {
            for ok in MsmModel::INTEGRATORS {
                assert!(text.contains(ok.name()), "{text}");
            }
        }
    }
    assert!(MsmModel::integrator_problem(IntegratorKind::TerzopoulosQin).is_some());
}
