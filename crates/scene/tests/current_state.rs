//! Outputs of a scene with weights as unknowns are those of the current state (docs/math.md §3):
//! trajectory probes and `steady`'s points against the surface evaluated here with the geom
//! crate from the state itself; the scale-fixing weight and the reduced dofs in `check`'s
//! summary; the `constraints.fixed_point_weights` key and its refusals.

use std::path::{Path, PathBuf};

use nurbspring_dnurbs::{DnurbsModel, Geometry, RationalStepper};
use nurbspring_geom::NurbsSurface;
use nurbspring_scene::run::{RunRequest, simulate_dnurbs, steady_state};
use nurbspring_scene::summary::summary;
use nurbspring_scene::{Scene, SceneErrorKind};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn sheet_text() -> String {
    std::fs::read_to_string(data("rational_sheet.toml")).unwrap()
}

/// The surface with control points and weights from `p` (4 dofs per point), built here.
fn surface_of(model: &DnurbsModel, p: &[f64]) -> NurbsSurface {
    let Geometry::Surface(s) = model.geometry() else {
        panic!("surface expected")
    };
    NurbsSurface::try_new(
        s.basis_u().knots().clone(),
        s.basis_v().knots().clone(),
        p.chunks(4).map(|c| [c[0], c[1], c[2]]).collect(),
        p.chunks(4).map(|c| c[3]).collect(),
    )
    .unwrap()
}

fn gap(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|x| (a[x] - b[x]).abs()).fold(0.0, f64::max)
}

#[test]
fn trajectory_probes_are_the_surface_of_the_current_state() {
    let scene = Scene::from_path(data("rational_sheet.toml")).unwrap();
    let (run, outcome) =
        simulate_dnurbs(&scene, &RunRequest::default(), None, &mut |_, _| {}).unwrap();
    outcome.unwrap();
    let traj = &run.trajectory;
    let params = scene.probe_params().unwrap();
    assert_eq!(traj.probes.len(), params.len());
    // The same states, stepped here.
    let model = scene.build_dnurbs().unwrap();
    let initial = scene.initial_conditions().state(&model);
    let mut stepper = RationalStepper::new(&model, initial, run.dt).unwrap();
    let mut first_order_gap: f64 = 0.0;
    let j0 = model.geometry().stacked_jacobian(&params, true).unwrap();
    for s in 0..traj.t.len() {
        if s > 0 {
            stepper.step().unwrap();
        }
        assert!((stepper.state().t - traj.t[s]).abs() < 1e-12);
        let p = stepper.full_coordinates();
        let surface = surface_of(&model, p);
        let mut frozen = vec![0.0; 3 * params.len()];
        j0.mul_vec(p, &mut frozen);
        for (a, &(u, v)) in params.iter().enumerate() {
            let want = surface.point(u, v).unwrap();
            let got = traj.probes[a][s];
            assert!(
                gap(got, want) < 1e-12,
                "sample {s} probe {a}: {got:?} vs {want:?}"
            );
            first_order_gap = first_order_gap.max(gap(
                [frozen[3 * a], frozen[3 * a + 1], frozen[3 * a + 2]],
                want,
            ));
        }
    }
    // J(p(0)) p(t) is measurably different: the test discriminates.
    assert!(first_order_gap > 1e-6, "{first_order_gap:e}");
    assert!(run.warnings.is_empty(), "{:?}", run.warnings);
}

#[test]
fn steady_points_are_the_surface_at_the_nonlinear_equilibrium() {
    let scene = Scene::from_path(data("rational_sheet.toml")).unwrap();
    let steady = steady_state(&scene, &Default::default(), &mut |_| {}).unwrap();
    assert!(
        steady.iterations > 1 && steady.residual <= 1e-13,
        "{}",
        steady.residual
    );
    let model = &steady.model;
    let (now, before) = (surface_of(model, &steady.p), surface_of(model, model.p0()));
    for probe in &steady.probes {
        let want = now.point(probe.u, probe.v).unwrap();
        let b = before.point(probe.u, probe.v).unwrap();
        assert!(gap(probe.point, want) < 1e-12, "{probe:?} vs {want:?}");
        let d = [want[0] - b[0], want[1] - b[1], want[2] - b[2]];
        assert!(gap(probe.displacement, d) < 1e-12);
    }
    assert!(steady.probes[0].displacement[2] < -1e-3);
}

#[test]
fn check_names_the_scale_fixing_weight_and_counts_reduced_dofs() {
    let scene = Scene::from_path(data("rational_sheet.toml")).unwrap();
    let s = summary(&scene).unwrap();
    assert_eq!(
        s.dnurbs.scale_fixing_weight.as_deref(),
        Some("weight of control point [0, 0] (dof 3) held at w = 1")
    );
    assert_eq!(s.dnurbs.fixed_point_weights, Some("free"));
    // 25 points × 4 dofs; the 16 ring points fix x, y, z; one weight fixes the scale.
    assert_eq!((s.dnurbs.dofs, s.dnurbs.free_dofs), (100, 100 - 48 - 1));
    assert_eq!(s.dnurbs.reduced_dofs, s.dnurbs.free_dofs);
    assert!(s.dnurbs.quadrature.automatic && !s.dnurbs.quadrature.polynomial);
    assert!(s.dnurbs.quadrature.estimated_error <= nurbspring_dnurbs::QUADRATURE_TOLERANCE);

    let held = sheet_text().replace(
        "fixed_weights = false",
        "fixed_weights = false\nfixed_point_weights = \"held\"",
    );
    let s = summary(&Scene::from_str(&held, "held.toml").unwrap()).unwrap();
    assert_eq!(s.dnurbs.scale_fixing_weight, None);
    assert_eq!(s.dnurbs.fixed_point_weights, Some("held"));
    assert_eq!(s.dnurbs.free_dofs, 100 - 64);

    // Two independent linear constraints: two fewer unknowns than free dofs.
    let linear = sheet_text().replace(
        "fixed_weights = false",
        "fixed_weights = false\n\
         [[constraints.linear]]\nterms = [{ point = [1, 1], component = \"z\" }, { point = [3, 3], component = \"z\", coefficient = -1.0 }]\n\
         [[constraints.linear]]\nterms = [{ point = [2, 2], component = \"x\" }]\nrhs = 1.0",
    );
    let s = summary(&Scene::from_str(&linear, "linear.toml").unwrap()).unwrap();
    assert_eq!(s.dnurbs.reduced_dofs, s.dnurbs.free_dofs - 2);
}

#[test]
fn a_coarse_rule_on_a_rational_sheet_is_warned_about() {
    let coarse = sheet_text().replace(
        "weights_as_dofs = true",
        "weights_as_dofs = true\nquadrature_points = 2",
    );
    let s = summary(&Scene::from_str(&coarse, "coarse.toml").unwrap()).unwrap();
    assert_eq!(s.warnings.len(), 1);
    assert!(
        s.warnings[0].contains("dnurbs.quadrature_points = 2")
            && s.warnings[0].contains("raise dnurbs.quadrature_points"),
        "{}",
        s.warnings[0]
    );
}

#[test]
fn fixed_point_weights_is_refused_where_it_cannot_apply() {
    for (old, new, why, kind) in [
        (
            "fixed_weights = false",
            "fixed_weights = true\nfixed_point_weights = \"held\"",
            "applies only to free weights",
            SceneErrorKind::Invalid,
        ),
        (
            "fixed_weights = false",
            "fixed_weights = false\nfixed_point_weights = \"sometimes\"",
            "sometimes",
            SceneErrorKind::Parse,
        ),
    ] {
        let text = sheet_text().replace(old, new);
        let err = Scene::from_str(&text, "bad.toml").unwrap_err();
        let msg = err.to_string();
        assert_eq!(err.kind(), kind, "{msg}");
        assert!(
            msg.starts_with("bad.toml") && msg.contains("fixed_point_weights"),
            "{msg}"
        );
        assert!(msg.contains(why), "{msg}");
    }
}

#[test]
fn weights_as_unknowns_refuse_newmark_naming_the_key() {
    let text = sheet_text().replace("dt = 0.02", "dt = 0.02\ndnurbs_integrator = \"newmark\"");
    // Refused when the scene is read, or at the latest when it is run.
    let msg = match Scene::from_str(&text, "newmark.toml") {
        Err(e) => e.to_string(),
        Ok(scene) => simulate_dnurbs(&scene, &RunRequest::default(), None, &mut |_, _| {})
            .unwrap_err()
            .to_string(),
    };
    assert!(
        msg.contains("simulation.dnurbs_integrator") && msg.contains("weights as unknowns"),
        "{msg}"
    );
}
