//! What the weights-as-unknowns model reports is that of the current shape (docs/math.md §3):
//! the nonlinear steady state against an independent Newton solve, energies against matrices
//! assembled independently at each sample's own `p` with the velocity at the sample's own
//! time, Newmark's energy on an undamped rational sheet, the weights of fixed points, and the
//! `loads.distributed` measure in both integration modes.

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, Integration, Loads, Material,
    SteadySettings, assemble,
};
use nurbspring_geom::NurbsSurface;
use nurbspring_linalg::{DenseMatrix, solve_dense};
use nurbspring_sim::{IntegratorKind, RunOptions, Sample};

use crate::support::{self, tol};

fn rational_model(gamma: f64, fixed_point_weights: bool) -> DnurbsModel {
    DnurbsModel::new(
        Geometry::Surface(support::wavy_rational_patch()),
        Material {
            gamma,
            alpha11: 0.5,
            alpha22: 0.5,
            ..support::paper_material()
        },
        Loads {
            gravity: [0.0, 0.0, -0.02],
            distributed: [0.02, 0.0, 0.0],
            ..Loads::default()
        },
        &Constraints {
            fixed_rings: 1,
            fixed_weights: false,
            fixed_point_weights,
            ..Constraints::default()
        },
        DnurbsOptions {
            weights_as_dofs: true,
            // A fixed rule keeps the finite-difference Newton reference cheap.
            quadrature_points: Some(4),
            ..DnurbsOptions::default()
        },
    )
    .unwrap()
}

/// `f(p) − K(p)(p − p_rest)` on the free dofs, assembled here from the shape `p` itself.
fn residual(model: &DnurbsModel, p: &[f64]) -> Vec<f64> {
    let geometry = model.geometry().with_coordinates(p, true).unwrap();
    let m = assemble(&geometry, model.material(), model.loads(), model.options()).unwrap();
    let d: Vec<f64> = p.iter().zip(model.p_rest()).map(|(a, b)| a - b).collect();
    let mut kd = vec![0.0; d.len()];
    m.stiffness.mul_vec(&d, &mut kd);
    model
        .dof_map()
        .free()
        .iter()
        .map(|&i| m.force[i] - kd[i])
        .collect()
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |a, b| a.max(b.abs()))
}

/// Damped Newton on the free dofs with a central-difference Jacobian, from `p(0)`.
fn newton_steady_state(model: &DnurbsModel) -> Vec<f64> {
    let free = model.dof_map().free().to_vec();
    let mut p = model.p0().to_vec();
    for _ in 0..30 {
        let r = residual(model, &p);
        let n = free.len();
        let h = 1e-6;
        let mut jac = DenseMatrix::zeros(n, n);
        for (c, &dof) in free.iter().enumerate() {
            let (mut plus, mut minus) = (p.clone(), p.clone());
            plus[dof] += h;
            minus[dof] -= h;
            let (rp, rm) = (residual(model, &plus), residual(model, &minus));
            for i in 0..n {
                jac[(i, c)] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        let step = solve_dense(&jac, &r).unwrap();
        // Backtracking: keep the weights positive and the residual decreasing.
        let mut lambda = 1.0;
        loop {
            let mut trial = p.clone();
            for (c, &dof) in free.iter().enumerate() {
                trial[dof] -= lambda * step[c];
            }
            let positive = trial.iter().skip(3).step_by(4).all(|&w| w > 0.0);
            if positive && (lambda < 1e-3 || max_abs(&residual(model, &trial)) <= max_abs(&r)) {
                p = trial;
                break;
            }
            lambda *= 0.5;
        }
        if lambda == 1.0 && max_abs(&step) < 1e-15 * max_abs(&p) {
            break;
        }
    }
    p
}

#[test]
fn steady_state_with_free_weights_is_the_nonlinear_equilibrium() {
    let model = rational_model(0.0, false);
    let steady = model.steady_state_with(SteadySettings::default()).unwrap();
    let linear = model.linearized_steady_state().unwrap();
    let newton = newton_steady_state(&model);
    let scale = max_abs(&steady.p);
    let motion: Vec<f64> = steady
        .p
        .iter()
        .zip(model.p0())
        .map(|(a, b)| a - b)
        .collect();
    let lin_gap: Vec<f64> = linear.iter().zip(&steady.p).map(|(a, b)| a - b).collect();
    // The linearization at p(0) is measurably off: the test discriminates.
    assert!(
        max_abs(&lin_gap) > 1e-4 * max_abs(&motion),
        "linearized {:e} vs motion {:e}",
        max_abs(&lin_gap),
        max_abs(&motion)
    );
    let gap = support::max_abs_diff(&steady.p, &newton);
    assert!(gap < 1e-10 * scale, "fixed point vs Newton: {gap:e}");
    let r = max_abs(&residual(&model, &steady.p));
    let f = max_abs(&residual(&model, model.p0()));
    assert!(r < 1e-12 * f, "residual {r:e} of {f:e}");
    eprintln!(
        "steady: {} iterations, residual {:e}, |fixed point − Newton| {gap:e}, linearized off by {:e} of a motion {:e}",
        steady.iterations,
        steady.residual,
        max_abs(&lin_gap),
        max_abs(&motion)
    );
    assert!(steady.iterations > 1 && steady.residual <= 1e-12);
    // steady_state() is the nonlinear one with weights as unknowns.
    assert_eq!(model.steady_state().unwrap(), steady.p);
}

/// Six times the loads of `rational_model`: the plain fixed-point iteration `q ← G(q)` does not
/// converge within the default 200 iterations here (checked by emptying the Anderson history:
/// it stalls), Anderson mixing does, and what it returns is an equilibrium, its residual
/// recomputed from matrices assembled at that shape.
/// The rational sheet with free weights, undamped, under gravity `−g` along z and a
/// distributed load `g` along x.
fn loaded_model(g: f64) -> DnurbsModel {
    DnurbsModel::new(
        Geometry::Surface(support::wavy_rational_patch()),
        Material {
            gamma: 0.0,
            alpha11: 0.5,
            alpha22: 0.5,
            ..support::paper_material()
        },
        Loads {
            gravity: [0.0, 0.0, -g],
            distributed: [g, 0.0, 0.0],
            ..Loads::default()
        },
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions {
            weights_as_dofs: true,
            quadrature_points: Some(4),
            ..DnurbsOptions::default()
        },
    )
    .unwrap()
}

#[test]
fn anderson_mixing_reaches_the_equilibrium_under_larger_loads() {
    let model = loaded_model(0.12);
    let steady = model.steady_state_with(SteadySettings::default()).unwrap();
    let r = max_abs(&residual(&model, &steady.p));
    let f = max_abs(&residual(&model, model.p0()));
    assert!(r < 1e-12 * f, "residual {r:e} of {f:e}");
}

/// Stopped at a loose tolerance (far above round-off), the reported residual is the relative
/// equilibrium residual `|f − K(p)(p − p_rest)| / (|f| + |K(p)(p − p_rest)|)` on the free dofs
/// of the shape it returns, recomputed here from matrices assembled at that shape.
#[test]
fn steady_state_reports_the_relative_residual_of_its_shape() {
    let model = rational_model(0.0, false);
    let steady = model
        .steady_state_with(SteadySettings {
            tolerance: 1e-5,
            max_iterations: 50,
        })
        .unwrap();
    let geometry = model.geometry().with_coordinates(&steady.p, true).unwrap();
    let m = assemble(&geometry, model.material(), model.loads(), model.options()).unwrap();
    let d: Vec<f64> = steady
        .p
        .iter()
        .zip(model.p_rest())
        .map(|(a, b)| a - b)
        .collect();
    let mut kd = vec![0.0; d.len()];
    m.stiffness.mul_vec(&d, &mut kd);
    let free = model.dof_map().free();
    let norm = |x: &mut dyn Iterator<Item = f64>| x.map(|v| v * v).sum::<f64>().sqrt();
    let f = norm(&mut free.iter().map(|&i| m.force[i]));
    let e = norm(&mut free.iter().map(|&i| kd[i]));
    let r = norm(&mut free.iter().map(|&i| m.force[i] - kd[i]));
    let expected = r / (f + e);
    assert!(steady.residual <= 1e-5 && expected > 1e-9, "{expected:e}");
    assert!(
        (steady.residual - expected).abs() <= 1e-6 * expected,
        "reported {:e}, recomputed {expected:e}",
        steady.residual
    );
}

#[test]
fn steady_state_iteration_that_cannot_converge_is_an_error() {
    let model = rational_model(0.0, false);
    let err = model
        .steady_state_with(SteadySettings {
            tolerance: 1e-13,
            max_iterations: 2,
        })
        .unwrap_err();
    assert!(
        err.to_string().contains("did not converge in 2 iterations"),
        "{err}"
    );
}

/// Every sample of `model.simulate`.
struct Recorded {
    t: Vec<f64>,
    q: Vec<Vec<f64>>,
    v: Vec<Vec<f64>>,
    energy: Vec<[f64; 2]>,
}

fn run(model: &DnurbsModel, integrator: IntegratorKind, dt: f64, t_end: f64) -> Recorded {
    let mut rec = Recorded {
        t: Vec::new(),
        q: Vec::new(),
        v: Vec::new(),
        energy: Vec::new(),
    };
    let initial = model.initial_state(&[[0.1, -0.05, 0.3]], 0.2);
    let mut observer = |s: &Sample<'_>| {
        rec.t.push(s.t);
        rec.q.push(s.q.to_vec());
        rec.v.push(s.v.to_vec());
        // The elastic energy excludes the load; the potential adds the load's.
        assert_eq!(s.potential, s.elastic + s.external);
        rec.energy.push([s.kinetic, s.elastic]);
    };
    model
        .simulate(
            initial,
            &RunOptions::new(dt, t_end, integrator),
            &mut observer,
        )
        .unwrap();
    rec
}

/// `½ vᵀ M(p) v` and `½ (p − p_rest)ᵀ K(p) (p − p_rest)` with a surface built here from `p`.
fn independent_energies(model: &DnurbsModel, p: &[f64], v: &[f64]) -> [f64; 2] {
    let wad = model.options().weights_as_dofs;
    let m = if wad { 4 } else { 3 };
    let s0 = match model.geometry() {
        Geometry::Surface(s) => s,
        Geometry::Curve(_) => unreachable!(),
    };
    let points: Vec<[f64; 3]> = p.chunks(m).map(|c| [c[0], c[1], c[2]]).collect();
    let weights: Vec<f64> = if wad {
        p.chunks(4).map(|c| c[3]).collect()
    } else {
        s0.weights().to_vec()
    };
    let surface = NurbsSurface::try_new(
        s0.basis_u().knots().clone(),
        s0.basis_v().knots().clone(),
        points,
        weights,
    )
    .unwrap();
    let mats = assemble(
        &Geometry::Surface(surface),
        model.material(),
        model.loads(),
        model.options(),
    )
    .unwrap();
    let d: Vec<f64> = p.iter().zip(model.p_rest()).map(|(a, b)| a - b).collect();
    [
        0.5 * mats.mass.quadratic_form(v),
        0.5 * mats.stiffness.quadratic_form(&d),
    ]
}

/// The second-order backward difference `(3p_n − 4p_{n−1} + p_{n−2})/(2Δt)` with the start
/// `p_{−1} = p_0 − Δt v_0`.
fn backward_velocity(p: &[Vec<f64>], v0: &[f64], n: usize, dt: f64) -> Vec<f64> {
    let start: Vec<f64> = p[0].iter().zip(v0).map(|(a, b)| a - dt * b).collect();
    let older = if n >= 2 { &p[n - 2] } else { &start };
    (0..p[n].len())
        .map(|i| (3.0 * p[n][i] - 4.0 * p[n - 1][i] + older[i]) / (2.0 * dt))
        .collect()
}

#[test]
fn weights_as_unknowns_energies_are_those_of_the_current_shape() {
    let model = rational_model(0.3, false);
    let dt = 0.01;
    let rec = run(&model, IntegratorKind::TerzopoulosQin, dt, 0.3);
    let p: Vec<Vec<f64>> = rec.q.iter().map(|q| model.full_coordinates(q)).collect();
    let v0 = model.full_velocity(&rec.v[0]);
    let frozen = model.matrices();
    let mut frozen_gap: f64 = 0.0;
    for n in 0..rec.t.len() {
        let v = if n == 0 {
            v0.clone()
        } else {
            backward_velocity(&p, &v0, n, dt)
        };
        let reported = model.full_velocity(&rec.v[n]);
        let vgap = support::max_abs_diff(&reported, &v);
        assert!(
            vgap < tol::SAME * max_abs(&v).max(1e-3),
            "step {n}: velocity {vgap:e}"
        );
        let want = independent_energies(&model, &p[n], &v);
        for (c, name) in ["kinetic", "elastic"].iter().enumerate() {
            let got = rec.energy[n][c];
            assert!(
                (got - want[c]).abs() <= tol::SAME * want[0].max(want[1]),
                "step {n} {name}: {got:e} vs {:e}",
                want[c]
            );
        }
        frozen_gap = frozen_gap.max((0.5 * frozen.mass.quadratic_form(&v) - want[0]).abs());
    }
    // M(p(0)) would have been measurably different.
    assert!(frozen_gap > 1e-6, "frozen-mass gap {frozen_gap:e}");
}

#[test]
fn newmark_conserves_the_energy_of_an_undamped_rational_sheet() {
    let model = DnurbsModel::new(
        Geometry::Surface(support::wavy_rational_patch()),
        Material {
            alpha11: 0.5,
            alpha22: 0.5,
            ..support::paper_material()
        },
        Loads::default(),
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions::default(),
    )
    .unwrap();
    let rec = run(&model, IntegratorKind::Newmark, 0.02, 2.0);
    let e0 = rec.energy[0][0] + rec.energy[0][1];
    assert!(e0 > 0.0);
    for n in 0..rec.t.len() {
        let p = model.full_coordinates(&rec.q[n]);
        let v = model.full_velocity(&rec.v[n]);
        let want = independent_energies(&model, &p, &v);
        let (k, e) = (rec.energy[n][0], rec.energy[n][1]);
        assert!((k - want[0]).abs() <= tol::SAME * e0, "step {n}: kinetic");
        assert!((e - want[1]).abs() <= tol::SAME * e0, "step {n}: elastic");
        assert!(
            ((k + e) - e0).abs() <= tol::ENERGY * e0,
            "step {n}: drift {:e}",
            (k + e - e0) / e0
        );
    }
    // The energy is exchanged, not constant in each part.
    let kmin = rec
        .energy
        .iter()
        .map(|e| e[0])
        .fold(f64::INFINITY, f64::min);
    assert!(kmin < 0.5 * rec.energy[0][0]);
}

#[test]
fn terzopoulos_qin_reports_the_velocity_at_the_rows_own_time() {
    let model = DnurbsModel::new(
        Geometry::Surface(support::wavy_rational_patch()),
        support::paper_material(),
        Loads::default(),
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions::default(),
    )
    .unwrap();
    let dt = 0.02;
    let rec = run(&model, IntegratorKind::TerzopoulosQin, dt, 0.4);
    let p: Vec<Vec<f64>> = rec.q.iter().map(|q| model.full_coordinates(q)).collect();
    let v0 = model.full_velocity(&rec.v[0]);
    for n in 1..rec.t.len() {
        let v = backward_velocity(&p, &v0, n, dt);
        let gap = support::max_abs_diff(&model.full_velocity(&rec.v[n]), &v);
        assert!(gap < tol::SAME * max_abs(&v0), "step {n}: {gap:e}");
        let want = independent_energies(&model, &p[n], &v);
        assert!((rec.energy[n][0] - want[0]).abs() <= tol::SAME * want[0].max(want[1]));
    }
}

#[test]
fn weights_of_fixed_points_are_free_or_held_by_the_key() {
    let free = rational_model(0.0, false);
    let held = rational_model(0.0, true);
    let fixed = free.fixed_points().to_vec();
    assert_eq!(fixed, held.fixed_points());
    assert_eq!(free.gauge_weight(), Some(4 * fixed[0] + 3));
    assert_eq!(held.gauge_weight(), None);
    let n = free.geometry().n_control_points();
    for k in 0..n {
        let on_ring = fixed.contains(&k);
        assert_eq!(held.dof_map().is_fixed(4 * k + 3), on_ring, "point {k}");
        assert_eq!(
            free.dof_map().is_fixed(4 * k + 3),
            k == fixed[0],
            "point {k}"
        );
    }
    assert_eq!(free.n_free(), held.n_free() + fixed.len() - 1);
    // Held boundary weights: the boundary curve cannot move in the steady state.
    let p = held.steady_state().unwrap();
    for &k in &fixed {
        assert_eq!(&p[4 * k..4 * k + 4], &held.p0()[4 * k..4 * k + 4]);
    }
}

#[test]
fn distributed_load_is_per_unit_parameter_or_surface_area() {
    // A flat 2 × 3 sheet on the unit parameter square: parameter area 1, surface area 6.
    let sheet = support::flat_patch(2, 3, 2, 2.0, 3.0);
    let f_d = [0.7, -0.2, 0.4];
    for wad in [false, true] {
        for (integration, measure) in [(Integration::Parameter, 1.0), (Integration::Area, 6.0)] {
            let options = DnurbsOptions {
                weights_as_dofs: wad,
                integration,
                ..DnurbsOptions::default()
            };
            let loads = Loads {
                distributed: f_d,
                ..Loads::default()
            };
            let m = assemble(
                &Geometry::Surface(sheet.clone()),
                &support::paper_material(),
                &loads,
                &options,
            )
            .unwrap();
            let dpp = m.dofs_per_point;
            for x in 0..3 {
                let total: f64 = m.force.iter().skip(x).step_by(dpp).sum();
                let want = f_d[x] * measure;
                assert!(
                    (total - want).abs() < tol::SUM * want.abs(),
                    "wad {wad} {integration:?} {x}: {total} vs {want}"
                );
            }
        }
    }
}

/// Under loads fifty times those above, the first step of the iteration takes a free weight
/// below zero: the steady state is refused, naming a weight that is not positive, rather than
/// iterated on through a shape with a negative weight.
#[test]
fn a_steady_state_through_a_negative_weight_is_refused() {
    let model = loaded_model(1.0);
    let text = model
        .steady_state_with(SteadySettings::default())
        .unwrap_err()
        .to_string();
    let weight: f64 = text
        .split("reached weight ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(weight <= 0.0, "{text}");
}
