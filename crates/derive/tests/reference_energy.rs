//! The energies of the exact modal reference (closed form from the modal coordinates) against
//! those of the same D-NURBS stepped in time by Newmark, which counts them from its own state
//! (`DynamicModel` potentials): equal to the integrator's error, shrinking as Δt², and the
//! total conserved without damping.

use nurbspring_derive::{
    Config, DnurbsModes, FitOptions, InitialConditions, Judge, Method, ReferenceKind, Setup,
    TimeSettings, Trajectory,
};
use nurbspring_dnurbs::{Constraints, DnurbsOptions, Loads, Material, RestShape};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::LatticeOptions;
use nurbspring_sim::IntegratorKind;

/// The paper's patch under gravity with its initial velocity: the three energies all move.
fn config(gamma: f64, rest_shape: RestShape, dt: f64) -> Config {
    let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
    let px = [0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.];
    let py = [0., 0.83, 2.5, 4.16, 5.];
    let pts: Vec<[f64; 3]> = px
        .iter()
        .flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0]))
        .collect();
    let surface = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap();
    Config {
        method: Method::Modal,
        geometry: nurbspring_dnurbs::Geometry::Surface(surface),
        material: Material {
            mu: 25.0,
            gamma,
            alpha11: 0.5,
            alpha22: 0.5,
            beta11: 0.01,
            beta22: 0.01,
            ..Material::default()
        },
        loads: Loads {
            gravity: [0.0, 0.0, -0.5],
            ..Loads::default()
        },
        constraints: Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        dnurbs: DnurbsOptions {
            rest_shape,
            ..DnurbsOptions::default()
        },
        lattice: LatticeOptions::default(),
        initial: InitialConditions {
            velocities: vec![[0.1, 0.0, -0.2]],
            ..InitialConditions::default()
        },
        time: TimeSettings {
            dt,
            t_end: 4.0,
            dnurbs_integrator: IntegratorKind::Newmark,
            msm_integrator: IntegratorKind::Newmark,
        },
        fit: FitOptions::default(),
        probes: vec![(0.5, 0.5)],
        given: None,
        node_damping: None,
    }
}

/// The judge's reference (modal when undamped, Newmark when damped) and how it was made.
fn reference(c: &Config) -> (Trajectory, ReferenceKind, Setup) {
    let setup = Setup::new(c).unwrap();
    let modes = DnurbsModes::new(&setup, "modal").unwrap();
    let (traj, kind) = {
        let judge = Judge::new(&setup, c, Some(modes)).unwrap();
        judge.reference().unwrap()
    };
    (traj, kind, setup)
}

/// `max_t |a − b|` per energy, over the largest kinetic + elastic energy of `a`; `b` sampled
/// `every` times finer.
fn energy_error(a: &Trajectory, b: &Trajectory, every: usize) -> [f64; 3] {
    let scale = a.energy.iter().map(|e| e[0] + e[1]).fold(0.0, f64::max);
    let mut err = [0.0f64; 3];
    for (k, e) in a.energy.iter().enumerate() {
        let f = b.energy[k * every];
        assert!(
            (a.t[k] - b.t[k * every]).abs() < 1e-9,
            "{} vs {}",
            a.t[k],
            b.t[k * every]
        );
        for i in 0..3 {
            err[i] = err[i].max((e[i] - f[i]).abs() / scale);
        }
    }
    err
}

/// The largest change of the total energy over the run, relative to the energy scale.
fn total_drift(a: &Trajectory) -> f64 {
    let scale = a.energy.iter().map(|e| e[0] + e[1]).fold(0.0, f64::max);
    let total = |e: &[f64; 3]| e[0] + e[1] + e[2];
    let t0 = total(&a.energy[0]);
    a.energy
        .iter()
        .map(|e| (total(e) - t0).abs() / scale)
        .fold(0.0, f64::max)
}

#[test]
fn modal_reference_energies_match_a_time_stepped_dnurbs() {
    for rest_shape in [RestShape::Initial, RestShape::Zero] {
        let c = config(0.0, rest_shape, 0.08);
        let (exact, kind, setup) = reference(&c);
        assert_eq!(kind, ReferenceKind::Modal);
        assert_eq!(exact.energy.len(), exact.t.len());
        let horizon = *exact.t.last().unwrap();
        // Each energy moves (the comparison is not between constants).
        for i in 0..3 {
            let (lo, hi) = exact
                .energy
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), e| {
                    (l.min(e[i]), h.max(e[i]))
                });
            assert!(
                hi - lo > 1e-3 * (hi.abs() + lo.abs()),
                "{rest_shape:?} energy {i}: {lo}..{hi}"
            );
        }
        // Conserved to round-off.
        let drift = total_drift(&exact);
        assert!(drift < 1e-10, "{rest_shape:?}: total drifts by {drift:e}");
        // Newmark at Δt/8 and Δt/16: the error falls as Δt² (ratio ≈ 4).
        let mut errors = Vec::new();
        for every in [8, 16] {
            let stepped = setup
                .run_dnurbs(IntegratorKind::Newmark, 0.08 / every as f64, horizon, None)
                .unwrap();
            assert!(stepped.stopped.is_none());
            let e = energy_error(&exact, &stepped, every);
            errors.push(e.iter().copied().fold(0.0, f64::max));
            eprintln!("{rest_shape:?} Δt = 0.08/{every}: energy errors {e:?}");
        }
        // Measured 5.0e-5 (initial rest shape) and 6.9e-5 (zero rest shape) at Δt = 0.08/16.
        assert!(errors[1] < 2e-4, "{rest_shape:?}: {errors:?}");
        let ratio = errors[0] / errors[1];
        assert!(
            (3.0..5.0).contains(&ratio),
            "{rest_shape:?}: error ratio {ratio}"
        );
    }
}

/// Damped: the reference is Newmark on the scalar system; its energies, counted from the
/// scalar state, are the D-NURBS's own under the same integrator and step (to round-off), and
/// the total only falls.
#[test]
fn damped_reference_energies_are_the_dnurbs_energies() {
    let c = config(2.5, RestShape::Initial, 0.08);
    let (reference, kind, setup) = reference(&c);
    assert_eq!(kind, ReferenceKind::Newmark);
    let horizon = *reference.t.last().unwrap();
    let stepped = setup
        .run_dnurbs(IntegratorKind::Newmark, 0.08, horizon, None)
        .unwrap();
    let e = energy_error(&reference, &stepped, 1);
    assert!(e.iter().all(|&x| x < 1e-9), "{e:?}");
    let total: Vec<f64> = reference
        .energy
        .iter()
        .map(|e| e[0] + e[1] + e[2])
        .collect();
    assert!(
        total
            .windows(2)
            .all(|w| w[1] <= w[0] + 1e-12 * w[0].abs().max(1.0))
    );
    assert!(total.last().unwrap() < &total[0]);
}
