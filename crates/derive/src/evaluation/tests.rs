//! Unit tests of `evaluation`.

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};

use super::*;
use crate::scalar::EnergyOrigin;
use crate::test_scenes::setup;

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    a.map(|x| x / n)
}

/// The velocity of every control point of an impulse state, one triple per point.
fn point_velocities(setup: &Setup, state: &State) -> Vec<[f64; 3]> {
    let v = setup.model().full_velocity(&state.v);
    v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// On a doubly curved bicubic patch the impulse moves the one free control point whose
/// Greville point is nearest the point at fractions (0.3, 0.35) of the domain, along the unit normal of the
/// surface there (checked against the cross product of central-difference tangents), at
/// the given speed (1 without one).
#[test]
fn the_surface_impulse_pushes_the_nearest_free_point_along_the_normal() {
    // The domain [1, 3] × [−1, 1], so that the target (1.6, −0.3) is not at fractions of 1.
    let ku =
        KnotVector::try_new(vec![1., 1., 1., 1., 5. / 3., 7. / 3., 3., 3., 3., 3.], 3).unwrap();
    let kv = KnotVector::try_new(vec![-1., -1., -1., -1., 0., 1., 1., 1., 1.], 3).unwrap();
    let (gu, gv) = (ku.greville(), kv.greville());
    let pts = gu
        .iter()
        .flat_map(|&u| {
            gv.iter().map(move |&v| {
                let (u, v) = ((u - 1.0) / 2.0, (v + 1.0) / 2.0);
                [2.0 * u + 0.2 * v, 1.5 * v, 0.3 * u * u - 0.4 * v * u]
            })
        })
        .collect();
    let s = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 30]).unwrap();
    let setup = setup(Geometry::Surface(s.clone()));
    // The free points are the interior 4 × 3; by hand the nearest Greville point to
    // (1 + 0.3·2, −1 + 0.35·2) among them.
    let mut best = (usize::MAX, f64::INFINITY, (0.0, 0.0));
    for i in 1..5 {
        for j in 1..4 {
            let d = (gu[i] - 1.6).powi(2) + (gv[j] + 0.3).powi(2);
            if d < best.1 {
                best = (i * 5 + j, d, (gu[i], gv[j]));
            }
        }
    }
    let (k, _, (u, v)) = best;
    let h = 1e-5;
    let diff = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|x| (a[x] - b[x]) / (2.0 * h));
    let su = diff(s.point(u + h, v).unwrap(), s.point(u - h, v).unwrap());
    let sv = diff(s.point(u, v + h).unwrap(), s.point(u, v - h).unwrap());
    let normal = unit([
        su[1] * sv[2] - su[2] * sv[1],
        su[2] * sv[0] - su[0] * sv[2],
        su[0] * sv[1] - su[1] * sv[0],
    ]);
    // Every component non-zero, so that none can be dropped unseen.
    assert!(normal.iter().all(|c| c.abs() > 1e-3), "{normal:?}");
    for (speed, expected_speed) in [(0.3, 0.3), (0.0, 1.0)] {
        let state = impulse(&setup, speed).unwrap();
        let velocities = point_velocities(&setup, &state);
        for (a, vel) in velocities.iter().enumerate() {
            if a == k {
                for x in 0..3 {
                    assert!(
                        (vel[x] - expected_speed * normal[x]).abs() < 1e-8,
                        "{vel:?} vs {normal:?}"
                    );
                }
            } else {
                assert_eq!(*vel, [0.0; 3], "point {a}");
            }
        }
    }
}

/// On a curve the impulse is across it: the z axis made orthogonal to the tangent (the y
/// axis where the tangent is nearly along z), at the free point nearest 0.3 of the domain.
#[test]
fn the_curve_impulse_pushes_across_the_tangent() {
    let k = KnotVector::clamped_uniform(2, 4).unwrap();
    let g = k.greville();
    let pts: Vec<[f64; 3]> = g.iter().map(|&u| [3.0 * u, u * u, 0.8 * u]).collect();
    let n = pts.len();
    let c = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
    let curve_setup = setup(Geometry::Curve(c.clone()));
    let (point, &u) = g[1..n - 1]
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - 0.3).abs().total_cmp(&(b.1 - 0.3).abs()))
        .map(|(i, u)| (i + 1, u))
        .unwrap();
    let h = 1e-5;
    let (a, b) = (c.point(u + h).unwrap(), c.point(u - h).unwrap());
    let t = unit([0, 1, 2].map(|x| a[x] - b[x]));
    let expected = unit([-t[2] * t[0], -t[2] * t[1], 1.0 - t[2] * t[2]]);
    let velocities = point_velocities(&curve_setup, &impulse(&curve_setup, 2.0).unwrap());
    for x in 0..3 {
        assert!((velocities[point][x] - 2.0 * expected[x]).abs() < 1e-8);
    }
    assert_eq!(velocities.iter().filter(|v| **v != [0.0; 3]).count(), 1);

    // A curve in the y–z plane (tangent without x component): across it is still z made
    // orthogonal to the tangent, in that plane.
    let k = KnotVector::clamped_uniform(2, 4).unwrap();
    let pts: Vec<[f64; 3]> = g.iter().map(|&u| [0.0, 3.0 * u, 0.5 * u * u]).collect();
    let c = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
    let plane_setup = setup(Geometry::Curve(c.clone()));
    let (a, b) = (c.point(u + h).unwrap(), c.point(u - h).unwrap());
    let t = unit([0, 1, 2].map(|x| a[x] - b[x]));
    let expected = unit([0.0, -t[2] * t[1], 1.0 - t[2] * t[2]]);
    let velocities = point_velocities(&plane_setup, &impulse(&plane_setup, 1.0).unwrap());
    for x in 0..3 {
        assert!(
            (velocities[point][x] - expected[x]).abs() < 1e-8,
            "{:?}",
            velocities[point]
        );
    }

    // A curve nearly along z (|t_z| > 0.9): across it is the y axis made orthogonal to
    // the tangent, `y − (y·t) t`.
    let k = KnotVector::clamped_uniform(2, 4).unwrap();
    let pts: Vec<[f64; 3]> = g
        .iter()
        .map(|&u| [0.1 * u, 0.3 * u + 0.2 * u * u, 3.0 * u])
        .collect();
    let c = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
    let steep_setup = setup(Geometry::Curve(c.clone()));
    let (a, b) = (c.point(u + h).unwrap(), c.point(u - h).unwrap());
    let t = unit([0, 1, 2].map(|x| a[x] - b[x]));
    assert!(t[2] > 0.9 && t[0] != 0.0 && t[1] != 0.0, "{t:?}");
    let expected = unit([-t[1] * t[0], 1.0 - t[1] * t[1], -t[1] * t[2]]);
    let velocities = point_velocities(&steep_setup, &impulse(&steep_setup, 1.0).unwrap());
    for x in 0..3 {
        assert!(
            (velocities[point][x] - expected[x]).abs() < 1e-8,
            "{:?} vs {expected:?}",
            velocities[point]
        );
    }
}

/// The impulse's target is at 0.3 (and 0.35) of the domain, whatever the domain: on
/// [2, 10] (× [−3, 1]) with 12 spans the free point moved is the one whose Greville point is
/// nearest (4.4, −1.6), for a surface and for a curve.
#[test]
fn the_impulse_target_is_a_fraction_of_any_domain() {
    let knots = |a: f64, b: f64| {
        let mut k = vec![a; 3];
        k.extend((1..12).map(|i| a + (b - a) * i as f64 / 12.0));
        k.extend([b; 3]);
        KnotVector::try_new(k, 2).unwrap()
    };
    let (ku, kv) = (knots(2.0, 10.0), knots(-3.0, 1.0));
    let (gu, gv) = (ku.greville(), kv.greville());
    let n = gu.len();
    let nearest = |g: &[f64], x: f64| {
        (1..n - 1)
            .min_by(|&a, &b| (g[a] - x).abs().total_cmp(&(g[b] - x).abs()))
            .unwrap()
    };
    let (i, j) = (nearest(&gu, 4.4), nearest(&gv, -1.6));
    let pts = gu
        .iter()
        .flat_map(|&u| gv.iter().map(move |&v| [u, v, 0.05 * u * v]))
        .collect();
    let s = NurbsSurface::try_new(ku.clone(), kv, pts, vec![1.0; n * n]).unwrap();
    let surface = setup(Geometry::Surface(s.clone()));
    let moved: Vec<usize> = point_velocities(&surface, &impulse(&surface, 1.0).unwrap())
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != [0.0; 3])
        .map(|(a, _)| a)
        .collect();
    assert_eq!(moved, vec![s.index(i, j)]);
    let pts: Vec<[f64; 3]> = gu.iter().map(|&u| [u, 0.1 * u * u, 0.0]).collect();
    let c = NurbsCurve::try_new(ku, pts, vec![1.0; n]).unwrap();
    let curve = setup(Geometry::Curve(c));
    let moved: Vec<usize> = point_velocities(&curve, &impulse(&curve, 1.0).unwrap())
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != [0.0; 3])
        .map(|(a, _)| a)
        .collect();
    assert_eq!(moved, vec![i]);
}

/// The non-zeros of a row of a CSC matrix, by hand; stored zeros are left out.
#[test]
fn rows_of_a_sparse_matrix_by_hand() {
    let a = SparseMatrix::from_triplets(
        3,
        4,
        &[
            (0, 1, 2.0),
            (1, 0, -1.0),
            (1, 3, 4.0),
            (2, 2, 0.0),
            (1, 2, 0.5),
        ],
    )
    .unwrap();
    assert_eq!(row(&a, 0), vec![(1, 2.0)]);
    assert_eq!(row(&a, 1), vec![(0, -1.0), (2, 0.5), (3, 4.0)]);
    assert!(row(&a, 2).is_empty());
}

/// With no point fixed the D-NURBS has rigid modes (ω = 0); the lowest non-zero frequency
/// is the first positive one, not a zero.
#[test]
fn omega1_skips_the_rigid_modes() {
    let ku = KnotVector::clamped_uniform(2, 2).unwrap();
    let g = ku.greville();
    let pts = g
        .iter()
        .flat_map(|&u| g.iter().map(move |&v| [u, v, 0.1 * u * v]))
        .collect();
    let s = NurbsSurface::try_new(ku.clone(), ku, pts, vec![1.0; 16]).unwrap();
    let mut config = crate::test_scenes::config(Geometry::Surface(s));
    config.constraints.fixed_rings = 0;
    let setup = Setup::new(&config).unwrap();
    let modes = DnurbsModes::new(&setup, "test").unwrap();
    let zeros = modes.basis.omega.iter().filter(|&&w| w == 0.0).count();
    assert!(zeros >= 1, "{:?}", modes.basis.omega);
    let first = modes
        .basis
        .omega
        .iter()
        .copied()
        .find(|&w| w > 0.0)
        .unwrap();
    assert_eq!(modes.omega1(), first);
    assert!(first > 0.0);
}

/// The second excitation's system keeps M and K and replaces the state: no load, the
/// given displacement and velocity, and the energy origin of no load.
#[test]
fn the_unloaded_system_keeps_the_matrices_and_replaces_the_state() {
    use crate::scalar::ScalarSystem;
    let sys = ScalarSystem {
        free: vec![1, 2],
        mass: SparseMatrix::from_diagonal(&[2.0, 3.0]),
        stiffness: SparseMatrix::from_diagonal(&[5.0, 7.0]),
        damping_ratio: 0.1,
        load: vec![[0.0, 0.0, -1.0]; 2],
        displacement: vec![[0.5; 3]; 2],
        velocity: vec![[1.0; 3]; 2],
        energy: EnergyOrigin::of_load(&[[0.0, 0.0, -1.0]; 2], &[[0.5; 3]; 2]),
    };
    let (u0, v0) = (
        vec![[0.0, 0.1, 0.0], [0.2, 0.0, 0.0]],
        vec![[0.0, 0.0, 3.0], [0.0; 3]],
    );
    let out = unloaded(&sys, u0.clone(), v0.clone());
    assert_eq!(
        (out.free.clone(), out.damping_ratio),
        (sys.free.clone(), 0.1)
    );
    assert_eq!(out.mass.to_dense().data(), sys.mass.to_dense().data());
    assert_eq!(
        out.stiffness.to_dense().data(),
        sys.stiffness.to_dense().data()
    );
    assert_eq!(out.load, vec![[0.0; 3]; 2]);
    assert_eq!((out.displacement, out.velocity), (u0, v0));
    assert_eq!((out.energy.elastic, out.energy.external), (0.0, 0.0));
    assert_eq!(out.energy.force, vec![[0.0; 3]; 2]);
}

/// With weights as unknowns (4 dofs a point) the totals count the x, y, z rows only:
/// `Σ_ij M_ij / 3` over them is `μ` times the parameter measure (1) by the partition of
/// unity; the lattice's totals are its masses, all and free.
#[test]
fn mass_totals_skip_the_weight_rows() {
    use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Loads, Material};
    let (ku, kv) = (
        KnotVector::clamped_uniform(2, 2).unwrap(),
        KnotVector::clamped_uniform(2, 2).unwrap(),
    );
    let (gu, gv) = (ku.greville(), kv.greville());
    let pts = gu
        .iter()
        .flat_map(|&u| gv.iter().map(move |&v| [u, v, 0.1 * u * v]))
        .collect();
    let w = (0..16).map(|k| 1.0 + 0.1 * (k % 3) as f64).collect();
    let s = NurbsSurface::try_new(ku, kv, pts, w).unwrap();
    let model = DnurbsModel::new(
        Geometry::Surface(s),
        Material {
            mu: 2.5,
            alpha11: 1.0,
            alpha22: 1.0,
            ..Material::default()
        },
        Loads::default(),
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions {
            weights_as_dofs: true,
            ..DnurbsOptions::default()
        },
    )
    .unwrap();
    assert_eq!(model.matrices().dofs_per_point, 4);
    let report = with_totals(
        MassReport::default(),
        &model,
        &[1.0, 2.0, 3.0],
        &[true, false, false],
    );
    assert!(
        (report.total_dnurbs - 2.5).abs() < 1e-12,
        "{}",
        report.total_dnurbs
    );
    assert!(report.free_dnurbs > 0.0 && report.free_dnurbs < report.total_dnurbs);
    assert_eq!((report.total_msm, report.free_msm), (6.0, 5.0));
}

#[test]
fn horizon_and_initial_speed_by_hand() {
    let two_pi = 2.0 * std::f64::consts::PI;
    assert_eq!(horizon(1.0, two_pi), PERIODS);
    assert_eq!(horizon(10.0, two_pi), 10.0);
    assert_eq!(horizon(3.0, 0.0), 3.0);
    let state = State::new(vec![0.0; 6], vec![3.0, -4.0, 0.0, 0.0, 0.0, 1.0]);
    assert_eq!(initial_speed(&state), 5.0);
}

#[test]
fn triplicate_repeats_each_value_for_x_y_z() {
    assert_eq!(triplicate(&[1.0, 2.5]), vec![1.0, 1.0, 1.0, 2.5, 2.5, 2.5]);
    assert!(triplicate(&[]).is_empty());
}

fn validation_with(relative_rms: f64) -> Validation {
    Validation {
        integrator: "newmark".into(),
        substeps: 1,
        reference: ReferenceKind::Modal,
        horizon: 1.0,
        dt: 0.01,
        rms: relative_rms,
        max_abs: relative_rms,
        relative_rms,
        relative_rms_z: relative_rms,
        dnurbs_amplitude: 1.0,
        dnurbs_period: None,
        msm_period: None,
        samples: 101,
        dnurbs_energy_drift: None,
        msm_energy_drift: None,
        msm_stopped: None,
        msm_halved_steps: 0,
        dnurbs_truncation: None,
        msm_truncation: None,
        probes: Vec::new(),
    }
}

/// A truncated modal run is reported when its left-out modes carry more than
/// [`WARN_TRUNCATION`] of the motion (1.5% does, 0.5% does not) or an unknown share, naming
/// the run, the model and the counts.
#[test]
fn a_truncated_run_is_reported_above_its_threshold() {
    let rows: [crate::outcome::FrequencyRow; 0] = [];
    let mass = MassReport {
        free_msm: 1.0,
        free_dnurbs: 1.0,
        ..MassReport::default()
    };
    let truncated = |left_out| {
        Some(crate::validation::ModalTruncation {
            modes: 200,
            unknowns: 3721,
            left_out,
        })
    };
    let quiet = validation_with(0.0);
    let with = |dnurbs, msm| Validation {
        dnurbs_truncation: dnurbs,
        msm_truncation: msm,
        ..validation_with(0.0)
    };
    let w = warnings(
        Method::Modal,
        &with(
            truncated(Some(0.005)),
            truncated(Some(0.5 * WARN_TRUNCATION)),
        ),
        &quiet,
        &rows,
        &mass,
        &[],
        &Regime::default(),
    );
    assert!(w.is_empty(), "{w:?}");
    let w = warnings(
        Method::Modal,
        &quiet,
        &with(truncated(Some(1.5 * WARN_TRUNCATION)), truncated(None)),
        &rows,
        &mass,
        &[],
        &Regime::default(),
    );
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].starts_with(
            "the second excitation followed the lowest 200 of the D-NURBS's 3721 modes"
        ) && w[0].contains("carry 1.5% of its motion (above 1%)"),
        "{w:?}"
    );
    assert!(
        w[1].contains("of the MSM's 3721 modes") && w[1].contains("an unknown share"),
        "{w:?}"
    );
}

fn candidate(m: f64) -> crate::outcome::MassCandidate {
    crate::outcome::MassCandidate {
        m,
        rms: 0.0,
        max_abs: 0.0,
        integrator: nurbspring_sim::IntegratorKind::Newmark,
        substeps: 1,
        stopped: None,
        pruned: None,
    }
}

/// Each warning exactly when its number crosses its threshold: the free mass ratio
/// `free_msm / free_dnurbs` outside [1/2, 2] (2.5 and 0.45 warn, 1.5 and 0.75 do not), a selected mass at
/// either edge of the paper's scan (not inside it), a class clamped to zero (paper only).
#[test]
fn warnings_against_their_thresholds() {
    let quiet = validation_with(0.5 * WARN_RELATIVE_RMS);
    let rows = [crate::outcome::FrequencyRow {
        mode: 1,
        dnurbs: 1.0,
        msm_mode: 1,
        msm: 1.0,
        relative_difference: 0.0,
        mac: None,
    }];
    let masses = |free_msm: f64, free_dnurbs: f64, selected: f64| MassReport {
        candidates: vec![candidate(1.0), candidate(2.0), candidate(3.0)],
        selected,
        free_msm,
        free_dnurbs,
        ..MassReport::default()
    };
    let warn = |method, mass: &MassReport, clamped: &[String]| {
        warnings(
            method,
            &quiet,
            &quiet,
            &rows,
            mass,
            clamped,
            &Regime::default(),
        )
    };
    assert!(warn(Method::Modal, &masses(3.0, 2.0, 2.0), &[]).is_empty());
    assert!(warn(Method::Modal, &masses(1.5, 2.0, 2.0), &[]).is_empty());
    let w = warn(Method::Modal, &masses(5.0, 2.0, 2.0), &[]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("(2.500×)"), "{w:?}");
    assert!(warn(Method::Modal, &masses(0.9, 2.0, 2.0), &[])[0].contains("(0.450×)"));
    // The scan's edges, for the paper's derivation only.
    for (selected, edge) in [(1.0, true), (2.0, false), (3.0, true)] {
        let w = warn(Method::Paper, &masses(2.0, 2.0, selected), &[]);
        assert_eq!(w.len(), usize::from(edge), "{selected}: {w:?}");
        assert!(
            !edge || w[0].contains("at the edge of the scan [1, 3]"),
            "{w:?}"
        );
        assert!(warn(Method::Modal, &masses(2.0, 2.0, selected), &[]).is_empty());
    }
    let clamped = ["k_bend".to_string()];
    let w = warn(Method::Paper, &masses(2.0, 2.0, 2.0), &clamped);
    assert_eq!(w, vec!["k_bend was clamped to 0 by k >= 0".to_string()]);
}

/// A validation run that stopped says so, with its reason, instead of an infinite RMS
/// ("inf%"), for the scene's excitation and for the second one.
#[test]
fn a_stopped_run_is_named_with_its_reason() {
    let rows: [crate::outcome::FrequencyRow; 0] = [];
    let mass = MassReport {
        free_msm: 1.0,
        free_dnurbs: 1.0,
        ..MassReport::default()
    };
    let stopped = Validation {
        msm_stopped: Some("Newton iteration failed at step 7".into()),
        ..validation_with(f64::INFINITY)
    };
    let quiet = validation_with(0.0);
    let w = warnings(
        Method::Modal,
        &stopped,
        &quiet,
        &rows,
        &mass,
        &[],
        &Regime::default(),
    );
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with(
            "the MSM's validation run stopped before 1.000 s (Newton iteration failed at step 7)"
        ),
        "{w:?}"
    );
    assert!(!w[0].contains("inf%"), "{w:?}");
    let w = warnings(
        Method::Modal,
        &quiet,
        &stopped,
        &rows,
        &mass,
        &[],
        &Regime::default(),
    );
    assert_eq!(
        w,
        vec![
            "under the second excitation the MSM's run stopped before 1.000 s (Newton iteration failed at step 7)"
                .to_string()
        ]
    );
}

/// A matched mode above the lowest is reported beyond 5% (not at 4.9%), and a motion
/// beyond 10% of the surface's size (not at 9%), each with its numbers.
#[test]
fn mode_and_linear_range_warnings_at_their_thresholds() {
    let quiet = validation_with(0.0);
    let mass = MassReport {
        free_msm: 1.0,
        free_dnurbs: 1.0,
        ..MassReport::default()
    };
    let row = |mode: usize, off: f64| crate::outcome::FrequencyRow {
        mode,
        dnurbs: 2.0,
        msm_mode: mode + 1,
        msm: 2.0 * (1.0 + off),
        relative_difference: off,
        mac: Some(0.98),
    };
    let regime = |motion: f64| Regime {
        frequency: 1.0,
        modes: 1,
        size: 2.0,
        amplitude: LINEAR_RANGE * 2.0,
        motion,
    };
    let warn = |rows: &[crate::outcome::FrequencyRow], r: &Regime| {
        warnings(Method::Modal, &quiet, &quiet, rows, &mass, &[], r)
    };
    let fine = [row(1, 0.0), row(2, 0.049), row(3, -0.049)];
    assert!(warn(&fine, &regime(0.18)).is_empty());
    let off = [row(1, 0.0), row(2, 0.051), row(3, -0.06)];
    let w = warn(&off, &regime(0.0));
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].starts_with("D-NURBS mode 2 (2.000000 rad/s) is matched by MAC (0.980) to MSM mode 3")
            && w[0].contains("+5.1% off"),
        "{w:?}"
    );
    assert!(w[1].contains("-6.0% off"), "{w:?}");
    let w = warn(&fine, &regime(0.8));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with(
            "the scene's own motion reaches 0.8000 at the probes, 40% of the surface's size 2.0000"
        ),
        "{w:?}"
    );
}

/// The regime by hand: the rows up to the first beyond 1% set the frequency bound, the
/// size is the lattice's bounding-box diagonal, the motion the largest displacement of
/// any probe.
#[test]
fn regime_by_hand() {
    let k = KnotVector::clamped_uniform(2, 2).unwrap();
    let pts: Vec<[f64; 3]> = (0..16)
        .map(|i| {
            [
                0.5 * (i / 4) as f64,
                0.3 * (i % 4) as f64,
                0.1 * (i % 3) as f64,
            ]
        })
        .collect();
    let s = setup(Geometry::Surface(
        NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 16]).unwrap(),
    ));
    let row = |mode: usize, dnurbs: f64, off: f64| crate::outcome::FrequencyRow {
        mode,
        dnurbs,
        msm_mode: mode,
        msm: dnurbs * (1.0 + off),
        relative_difference: off,
        mac: Some(1.0),
    };
    let rows = [
        row(1, 1.0, 0.0),
        row(2, 2.0, 0.009),
        row(3, 3.0, -0.011),
        row(4, 4.0, 0.0),
    ];
    let mut trajectory = Trajectory::new(2);
    trajectory.t = vec![0.0, 1.0, 2.0];
    trajectory.probes = vec![
        vec![[0.0, 0.0, 1.0], [0.0, 0.3, 1.4], [0.0, 0.0, 1.0]],
        vec![[1.0, 1.0, 0.0], [1.0, 1.0, 0.2], [1.0, 1.0, -0.1]],
    ];
    let r = regime(&s, &trajectory, &rows);
    assert_eq!((r.frequency, r.modes), (2.0, 2));
    let positions = &s.lattice().positions;
    let extent = |x: usize| {
        let v = positions.iter().map(|p| p[x]);
        v.clone().fold(f64::NEG_INFINITY, f64::max) - v.fold(f64::INFINITY, f64::min)
    };
    let size = (extent(0).powi(2) + extent(1).powi(2) + extent(2).powi(2)).sqrt();
    assert!((r.size - size).abs() < 1e-15 * size);
    assert!((r.amplitude - LINEAR_RANGE * size).abs() < 1e-15 * size);
    assert!((r.motion - 0.5).abs() < 1e-15, "{}", r.motion);
    assert_eq!(regime(&s, &trajectory, &[row(1, 1.0, 0.02)]).modes, 0);
}
