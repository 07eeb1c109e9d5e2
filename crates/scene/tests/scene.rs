//! Scene files: the paper's scene, every kind of bad input (with the key, value, line and
//! suggestion in the message), and property tests (parsing never panics, valid scenes round-trip).

use std::path::{Path, PathBuf};

use nurbspring_derive::{FitDofs, FitMethod, MassScan, Method};
use nurbspring_dnurbs::{DnurbsOptions, Integration, Material, RestShape};
use nurbspring_scene::*;
use nurbspring_sim::IntegratorKind;
use proptest::prelude::*;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn paper_text() -> String {
    std::fs::read_to_string(data("paper.toml")).unwrap()
}

/// The paper's scene with `old` replaced by `new` (which must occur).
fn edited(old: &str, new: &str) -> String {
    let t = paper_text();
    assert!(t.contains(old), "`{old}` not in paper.toml");
    t.replacen(old, new, 1)
}

/// Parses `text` expecting failure of `kind`; returns the message.
fn fails(text: &str, kind: SceneErrorKind) -> String {
    let err = Scene::from_str(text, "bad.toml").expect_err("scene should be refused");
    let msg = err.to_string();
    assert_eq!(err.kind(), kind, "{msg}");
    assert!(msg.starts_with("bad.toml: "), "{msg}");
    msg
}

fn assert_contains(msg: &str, needles: &[&str]) {
    for n in needles {
        assert!(msg.contains(n), "message lacks `{n}`:\n{msg}");
    }
}

#[test]
fn paper_scene_is_read_as_in_spec() {
    let scene = Scene::from_path(data("paper.toml")).unwrap();
    let GeometrySpec::Surface(s) = &scene.geometry else {
        panic!("surface expected")
    };
    assert_eq!((s.degree_u, s.degree_v), (3, 3));
    assert_eq!(
        s.knots_u,
        vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.]
    );
    assert_eq!(s.knots_v, vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.]);
    assert_eq!((s.n_u(), s.n_v()), (7, 5));
    let px = [0.0, 0.25, 0.75, 1.52, 2.5, 2.75, 3.0];
    let py = [0.0, 0.83, 2.5, 4.16, 5.0];
    for i in 0..7 {
        for j in 0..5 {
            assert_eq!(s.control_points[i][j], [px[i], py[j], 2.0]);
        }
    }
    assert_eq!(s.flat_control_points()[7], [0.25, 2.5, 2.0]); // k = i * n_v + j = 1 * 5 + 2
    assert_eq!(s.flat_weights(), vec![1.0; 35]);
    let material = scene.material.tension_plate().unwrap();
    assert_eq!(material.mu, 25.0);
    assert_eq!((material.beta11, material.beta22), (0.01, 0.01));
    assert_eq!(material.alpha11 + material.gamma + material.beta12, 0.0);
    assert_eq!(scene.constraints.fixed_rings, 2);
    assert_eq!(scene.initial.velocity, [0.0, 0.0, -0.2]);
    assert_eq!((scene.simulation.dt, scene.simulation.t_end), (0.08, 4.0));
    assert_eq!(
        scene.simulation.dnurbs_integrator,
        IntegratorKind::TerzopoulosQin
    );
    assert_eq!(
        scene.simulation.msm_integrator,
        nurbspring_sim::IntegratorKind::SymplecticEuler
    );
    assert_eq!(
        (scene.msm.k_edge, scene.msm.k_diag, scene.msm.mass),
        (Some(2.7225), Some(0.8661), Some(0.005))
    );
    assert_eq!(scene.msm.fixed, MsmFixed::Auto);
    assert_eq!(scene.dnurbs.quadrature_points, Some(4));
    assert!(scene.path.ends_with("paper.toml"));
    let surface = scene.to_surface().unwrap();
    assert_eq!(surface.point(0.5, 0.5).unwrap()[2], 2.0);
    assert!(scene.to_curve().is_err());
}

#[test]
fn examples_copy_matches_and_all_examples_parse() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    assert_eq!(
        std::fs::read_to_string(examples.join("paper.toml")).unwrap(),
        paper_text(),
        "examples/paper.toml must equal crates/scene/tests/data/paper.toml"
    );
    for entry in std::fs::read_dir(&examples).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::from_path(&p).unwrap_or_else(|e| panic!("{e}"));
            match &scene.geometry {
                GeometrySpec::Surface(_) => drop(scene.to_surface().unwrap()),
                GeometrySpec::Curve(_) => drop(scene.to_curve().unwrap()),
            }
        }
    }
}

#[test]
fn paper_scene_round_trips_through_to_toml() {
    let scene = Scene::from_path(data("paper.toml")).unwrap();
    let text = scene.to_toml();
    let back = Scene::from_str(&text, &scene.path).unwrap();
    assert_eq!(back, scene);
}

#[test]
fn defaults_apply_to_missing_sections() {
    let text =
        "[curve]\ndegree = 1\nknots = [0, 0, 1, 1]\ncontrol_points = [[0, 0, 0], [1, 0, 0]]\n";
    let scene = Scene::from_str(text, "c.toml").unwrap();
    assert_eq!(
        scene.material,
        nurbspring_dnurbs::MaterialModel::TensionPlate(Material::default())
    );
    assert_eq!(scene.material.tension_plate().unwrap().mu, 1.0);
    assert!(scene.constraints.fixed_weights);
    assert_eq!(
        scene.constraints.fixed_point_weights,
        FixedPointWeights::Free
    );
    // Omitted: chosen from the geometry (degree 1, equal weights: 2 points, exact).
    assert_eq!(scene.dnurbs.quadrature_points, None);
    let model = scene.build_dnurbs().unwrap();
    assert_eq!(model.quadrature().points, 2);
    assert_eq!(model.quadrature().estimated_error, 0.0);
    assert_eq!(scene.dnurbs.integration, Integration::Parameter);
    assert_eq!(scene.dnurbs.rest_shape, RestShape::Initial);
    assert_eq!(scene.simulation, SimulationSpec::default());
    assert_eq!(scene.msm, MsmSpec::default());
    assert_eq!(scene.fit.method, FitMethod::ClosedForm);
    assert_eq!(scene.fit.mass, MassMethod::EigenvalueScan);
    assert_eq!(scene.output.vtk_every, None); // at most DEFAULT_MAX_FRAMES frames
    let curve = scene.to_curve().unwrap();
    assert_eq!(curve.point(0.5).unwrap(), [0.5, 0.0, 0.0]);
}

#[test]
fn decreasing_knots() {
    let msg = fails(
        &edited("0.25, 0.5, 0.75", "0.5, 0.25, 0.75"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["surface.knots_u[5] = 0.25", "non-decreasing"]);
}

#[test]
fn wrong_number_of_control_points() {
    // Drop the last row: 6 rows along u but 11 knots of degree 3 need 7.
    let text = paper_text();
    let last = "    [[3.0, 0.0, 2.0], [3.0, 0.83, 2.0], [3.0, 2.5, 2.0], [3.0, 4.16, 2.0], [3.0, 5.0, 2.0]],\n";
    let msg = fails(&text.replace(last, ""), SceneErrorKind::Invalid);
    assert_contains(
        &msg,
        &[
            "surface.knots_u = [0, 0, 0, 0, 0.25",
            "11 knots given",
            "6 control points along u",
            "need 10",
        ],
    );
    // A ragged row.
    let msg = fails(&edited("[0.25, 5.0, 2.0]],", "],"), SceneErrorKind::Invalid);
    assert_contains(
        &msg,
        &[
            "surface.control_points[1] = 4 points",
            "every row must have 5 points",
        ],
    );
    // A point with 2 coordinates.
    let msg = fails(
        &edited("[0.75, 2.5, 2.0]", "[0.75, 2.5]"),
        SceneErrorKind::Invalid,
    );
    assert_contains(
        &msg,
        &[
            "surface.control_points[2][2] = [0.75, 2.5]",
            "3 coordinates",
        ],
    );
}

fn weights(rows: usize, cols: usize, special: Option<(usize, usize, &str)>) -> String {
    let mut s = String::from("weights = [\n");
    for i in 0..rows {
        let row: Vec<String> = (0..cols)
            .map(|j| match special {
                Some((a, b, v)) if (a, b) == (i, j) => v.to_string(),
                _ => "1.0".to_string(),
            })
            .collect();
        s.push_str(&format!("  [{}],\n", row.join(", ")));
    }
    s + "]\n"
}

#[test]
fn wrong_number_of_weights() {
    let msg = fails(
        &edited(
            "# weights: omitted, all 1 (held constant)",
            &weights(6, 5, None),
        ),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["surface.weights = 6 rows", "7 rows of 5"]);
    let msg = fails(
        &edited(
            "# weights: omitted, all 1 (held constant)",
            &weights(7, 4, None),
        ),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["surface.weights[0] = 4 values", "5 values"]);
}

#[test]
fn zero_and_negative_weights() {
    for (v, shown) in [("-1", "-1"), ("0", "0"), ("-0.5", "-0.5")] {
        let msg = fails(
            &edited(
                "# weights: omitted, all 1 (held constant)",
                &weights(7, 5, Some((2, 1, v))),
            ),
            SceneErrorKind::Invalid,
        );
        assert_contains(
            &msg,
            &[&format!(
                "bad.toml: surface.weights[2][1] = {shown}: weights must be positive"
            )],
        );
    }
}

#[test]
fn degree_zero() {
    let msg = fails(
        &edited("degree_u = 3", "degree_u = 0"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["surface.degree_u = 0", "at least 1"]);
    let msg = fails(
        &edited("degree_v = 3", "degree_v = -1"),
        SceneErrorKind::Parse,
    );
    assert_contains(&msg, &["-1", "line 7"]);
}

#[test]
fn nan_and_inf_anywhere() {
    let cases = [
        ("mu = 25.0", "mu = nan", "material.mu = NaN"),
        ("beta11 = 0.01", "beta11 = inf", "material.beta11 = inf"),
        (
            "velocity = [0.0, 0.0, -0.2]",
            "velocity = [0.0, 0.0, -inf]",
            "initial.velocity[2] = -inf",
        ),
        ("dt = 0.08", "dt = nan", "simulation.dt = NaN"),
        ("k_edge = 2.7225", "k_edge = inf", "msm.k_edge = inf"),
        (
            "[0.75, 2.5, 2.0]",
            "[0.75, nan, 2.0]",
            "surface.control_points[2][2][1] = NaN",
        ),
        (
            "0.25, 0.5, 0.75",
            "0.25, inf, 0.75",
            "surface.knots_u[5] = inf",
        ),
    ];
    for (old, new, needle) in cases {
        let msg = fails(&edited(old, new), SceneErrorKind::Invalid);
        assert_contains(&msg, &[needle]);
    }
    let msg = fails(
        &edited(
            "[output]",
            "[loads]\ngravity = [0.0, nan, -9.81]\n\n[output]",
        ),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["loads.gravity[1] = NaN: must be a finite number"]);
}

#[test]
fn unknown_key_with_suggestion() {
    let msg = fails(
        &edited("beta11 = 0.01", "bta11 = 0.01"),
        SceneErrorKind::Parse,
    );
    let line = paper_text()
        .lines()
        .position(|l| l.starts_with("beta11"))
        .unwrap()
        + 1;
    assert_eq!(
        msg,
        format!(
            "bad.toml: unknown key `bta11` in [material] at line {line}, column 1; did you mean `beta11`?"
        )
    );
    let msg = fails(
        &edited("k_diag = 0.8661", "kdiag = 0.8661"),
        SceneErrorKind::Parse,
    );
    assert_contains(
        &msg,
        &["unknown key `kdiag` in [msm]", "did you mean `k_diag`?"],
    );
    let msg = fails(&edited("[material]", "[materal]"), SceneErrorKind::Parse);
    assert_contains(
        &msg,
        &[
            "unknown key `materal` at the top level",
            "did you mean `material`?",
        ],
    );
    let msg = fails(
        &edited("vtk_every = 1", "something_else = 1"),
        SceneErrorKind::Parse,
    );
    assert_contains(&msg, &["unknown key `something_else` in [output]"]);
    assert!(!msg.contains("did you mean"), "{msg}");
    let msg = fails(
        &edited(
            "[output]",
            "[[loads.point]]\nu = 0.5\nv = 0.5\nforce = [0, 0, 1]\nforse = 1\n\n[output]",
        ),
        SceneErrorKind::Parse,
    );
    assert_contains(
        &msg,
        &[
            "unknown key `forse` in [loads.point]",
            "did you mean `force`?",
        ],
    );
}

#[test]
fn unknown_value_with_suggestion() {
    let msg = fails(
        &edited(
            "msm_integrator = \"symplectic-euler\"",
            "msm_integrator = \"sympletic-euler\"",
        ),
        SceneErrorKind::Parse,
    );
    assert_contains(
        &msg,
        &[
            "unknown value `sympletic-euler` for key `msm_integrator`",
            "did you mean `symplectic-euler`?",
        ],
    );
    let msg = fails(
        &edited("fixed = \"auto\"", "fixed = \"automatic\""),
        SceneErrorKind::Parse,
    );
    assert_contains(&msg, &["automatic"]);
    // The alias is accepted.
    let s = Scene::from_str(
        &edited(
            "msm_integrator = \"symplectic-euler\"",
            "msm_integrator = \"velocity-verlet\"",
        ),
        "ok.toml",
    )
    .unwrap();
    assert_eq!(s.simulation.msm_integrator, IntegratorKind::VelocityVerlet);
}

#[test]
fn truncated_toml() {
    let text = paper_text();
    let cut = &text[..text.find("[1.52, 0.83").unwrap()];
    let msg = fails(cut, SceneErrorKind::Parse);
    assert!(msg.contains(" at line "), "{msg}");
    let msg = fails("[surface\ndegree_u = 3\n", SceneErrorKind::Parse);
    assert_contains(&msg, &["at line 1"]);
}

#[test]
fn wrong_type() {
    let msg = fails(&edited("dt = 0.08", "dt = \"fast\""), SceneErrorKind::Parse);
    let line = paper_text()
        .lines()
        .position(|l| l.starts_with("dt ="))
        .unwrap()
        + 1;
    assert_contains(
        &msg,
        &[
            "invalid type",
            "fast",
            "(key `dt`)",
            &format!("at line {line}, column 6"),
        ],
    );
    let msg = fails(
        &edited("fixed_rings = 2", "fixed_rings = 2.5"),
        SceneErrorKind::Parse,
    );
    assert_contains(&msg, &["2.5", "fixed_rings"]);
    let msg = fails(
        &edited("structural = true", "structural = 1"),
        SceneErrorKind::Parse,
    );
    assert_contains(&msg, &["structural"]);
    let msg = fails(&edited("degree_u = 3\n", ""), SceneErrorKind::Parse);
    assert_contains(
        &msg,
        &["missing key `degree_u` in [surface] at line 5, column 1"],
    );
}

#[test]
fn empty_arrays() {
    let msg = fails(
        &edited(
            "knots_u = [0.0, 0.0, 0.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.0, 1.0, 1.0]",
            "knots_u = []",
        ),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["surface.knots_u = []: the knot vector is empty"]);
    let text = paper_text();
    let start = text.find("control_points = [").unwrap();
    let end = start + text[start..].find("\n]\n").unwrap() + 3;
    let empty = format!("{}control_points = []\n{}", &text[..start], &text[end..]);
    let msg = fails(&empty, SceneErrorKind::Invalid);
    assert_contains(
        &msg,
        &["surface.control_points = []: no control points given"],
    );
    let msg = fails(
        &edited("[output]", "[[constraints.linear]]\nterms = []\n\n[output]"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["constraints.linear[0].terms = []"]);
}

#[test]
fn huge_sizes_are_refused() {
    let msg = fails(
        &edited(
            "fixed = \"auto\"",
            "fixed = \"auto\"\ngrid = \"uniform\"\nnodes_u = 100000\nnodes_v = 100001",
        ),
        SceneErrorKind::Invalid,
    );
    assert_contains(
        &msg,
        &[
            "msm.nodes_u = 100000 x 100001 nodes",
            "more than 10000000 nodes",
        ],
    );
    let msg = fails(
        &edited(
            "fixed = \"auto\"",
            "fixed = \"auto\"\ngrid = \"uniform\"\nnodes_u = 18446744073709551615\nnodes_v = 3",
        ),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["more than 10000000 nodes"]);
    let msg = fails(
        &edited("t_end = 4.0", "t_end = 1e12"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["simulation.t_end = 1000000000000", "steps"]);
    let msg = fails(
        &edited("quadrature_points = 4", "quadrature_points = 1000000"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["dnurbs.quadrature_points = 1000000", "1..=32"]);
    let msg = fails(
        &edited("fixed_rings = 2", "fixed_rings = 18446744073709551615"),
        SceneErrorKind::Invalid,
    );
    assert_contains(
        &msg,
        &[
            "constraints.fixed_rings = 18446744073709551615",
            "every control point",
        ],
    );
    let msg = fails(
        &edited("fixed = \"auto\"", "fixed = [[18446744073709551615, 0]]"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["msm.fixed[0] = [18446744073709551615, 0]: outside"]);
    // A huge degree: the knot count check refuses it without allocating.
    let msg = fails(
        &edited("degree_u = 3", "degree_u = 18446744073709551615"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["surface.knots_u", "more than can be stored"]);
}

#[test]
fn values_out_of_range() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "dt = 0.08",
            "dt = 0.0",
            &["simulation.dt = 0: the time step must be positive"],
        ),
        ("dt = 0.08", "dt = -0.08", &["simulation.dt = -0.08"]),
        ("t_end = 4.0", "t_end = 0", &["simulation.t_end = 0"]),
        (
            "save_every = 1",
            "save_every = 0",
            &["simulation.save_every = 0"],
        ),
        (
            "mu = 25.0",
            "mu = 0.0",
            &["material.mu = 0: the mass density must be positive"],
        ),
        (
            "beta22 = 0.01",
            "beta22 = -0.01",
            &["material.beta22 = -0.01: material constants must not be negative"],
        ),
        ("mass = 0.005", "mass = 0", &["msm.mass = 0"]),
        ("damping = 0.0", "damping = -1", &["msm.damping = -1"]),
        (
            "k_diag = 0.8661",
            "k_diag = -0.8661",
            &["msm.k_diag = -0.8661"],
        ),
        (
            "fixed = \"auto\"",
            "fixed = \"auto\"\npre_strain = 1.0",
            &["msm.pre_strain = 1: must lie in (-1, 1)"],
        ),
        ("vtk_every = 1", "vtk_every = 0", &["output.vtk_every = 0"]),
        (
            "fixed_rings = 2",
            "fixed_rings = 3",
            &["constraints.fixed_rings = 3", "every control point"],
        ),
        (
            "fixed = \"auto\"",
            "grid = \"knots\"\nfixed = [[0, 0], [5, 1]]",
            &["msm.fixed[1] = [5, 1]: outside the 5 x 3 lattice"],
        ),
        (
            "fixed_rings = 2",
            "fixed_rings = 2\nfixed = [[7, 0]]",
            &["constraints.fixed[0] = [7, 0]: outside the 7 x 5 control net"],
        ),
        (
            "fixed_rings = 2",
            "fixed_rings = 2\nfixed = [[1]]",
            &["constraints.fixed[0] = [1]", "[i, j]"],
        ),
        (
            "save_every = 1",
            "save_every = 1\nprobes = [[1.5, 0.5]]",
            &["simulation.probes[0][0] = 1.5: outside the parameter domain [0, 1]"],
        ),
        (
            "save_every = 1",
            "save_every = 1\nprobes = [[0.5, -0.1]]",
            &["simulation.probes[0][1] = -0.1"],
        ),
        (
            "save_every = 1",
            "save_every = 1\nprobes = [[0.5]]",
            &["simulation.probes[0] = [0.5]", "[u, v]"],
        ),
        (
            "velocity = [0.0, 0.0, -0.2]",
            "velocity = [0.0, 0.0, -0.2]\nweight_velocity = 1.0",
            &["initial.weight_velocity = 1", "weights_as_dofs"],
        ),
        (
            "dnurbs_integrator = \"terzopoulos-qin\"",
            "dnurbs_integrator = \"modal\"",
            &[],
        ),
        ("gamma = 0.0", "gamma = 0.5", &[]),
        (
            "bending = false",
            "bending = false\nstructural = false\nshear = false",
            &["no springs"],
        ),
    ];
    for (old, new, needles) in cases {
        let text = if needles.is_empty() {
            // Fine on its own.
            Scene::from_str(&edited(old, new), "ok.toml").unwrap();
            continue;
        } else if new.starts_with("bending") {
            edited(old, new).replacen("structural = true\nshear = true\n", "", 1)
        } else {
            edited(old, new)
        };
        let msg = fails(&text, SceneErrorKind::Invalid);
        assert_contains(&msg, needles);
    }
    // The modal integrator with damping is refused.
    let msg = fails(
        &edited(
            "dnurbs_integrator = \"terzopoulos-qin\"",
            "dnurbs_integrator = \"modal\"",
        )
        .replacen("gamma = 0.0", "gamma = 0.5", 1),
        SceneErrorKind::Invalid,
    );
    assert_contains(
        &msg,
        &["simulation.dnurbs_integrator = \"modal\"", "undamped"],
    );
}

#[test]
fn point_loads_and_linear_constraints() {
    let ok = edited(
        "[output]",
        "[[loads.point]]\nu = 0.5\nv = 0.5\nforce = [0, 0, -1]\n\n[[constraints.linear]]\nterms = [{ point = [3, 2], component = \"z\", coefficient = 1.0 }, { point = [2, 2], component = \"z\" }]\nrhs = 0.0\n\n[output]",
    );
    let s = Scene::from_str(&ok, "ok.toml").unwrap();
    assert_eq!(s.loads.point[0].v, Some(0.5));
    assert_eq!(s.constraints.linear[0].terms[1].coefficient, 1.0);
    assert_eq!(s.constraints.linear[0].terms[0].component, Component::Z);
    assert_eq!(Scene::from_str(&s.to_toml(), "ok.toml").unwrap(), s);
    let msg = fails(
        &ok.replace("u = 0.5\nv = 0.5", "u = 0.5"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["loads.point[0].v: missing"]);
    let msg = fails(
        &ok.replace("u = 0.5\nv = 0.5", "u = 2\nv = 0.5"),
        SceneErrorKind::Invalid,
    );
    assert_contains(
        &msg,
        &["loads.point[0].u = 2: outside the parameter domain"],
    );
    let msg = fails(
        &ok.replace("component = \"z\" }]", "component = \"w\" }]"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["constraints.linear[0].terms[1].component = \"w\""]);
    let msg = fails(
        &ok.replace("point = [3, 2]", "point = [3, 9]"),
        SceneErrorKind::Invalid,
    );
    assert_contains(
        &msg,
        &["constraints.linear[0].terms[0].point = [3, 9]: outside the 7 x 5 control net"],
    );
}

#[test]
fn per_point_velocities() {
    let rows: Vec<String> = (0..7)
        .map(|i| {
            let row: Vec<String> = (0..5)
                .map(|j| format!("[0, 0, {}]", -(i * 5 + j) as f64 / 100.0))
                .collect();
            format!("[{}]", row.join(", "))
        })
        .collect();
    let text = edited(
        "velocity = [0.0, 0.0, -0.2]",
        &format!("velocities = [{}]", rows.join(",\n ")),
    );
    let s = Scene::from_str(&text, "v.toml").unwrap();
    let v = s.initial.velocities.as_ref().unwrap();
    assert_eq!(v.len(), 35);
    assert_eq!(v[7], [0.0, 0.0, -0.07]);
    assert_eq!(Scene::from_str(&s.to_toml(), "v.toml").unwrap(), s);
    let msg = fails(
        &text.replacen("[0, 0, -0.07]", "[0, 0]", 1),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["initial.velocities[1][2] = [0, 0]"]);
    let msg = fails(
        &text.replacen("velocities", "velocity = [0.0, 0.0, 1.0]\nvelocities", 1),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["either initial.velocity or initial.velocities"]);
}

#[test]
fn geometry_presence() {
    let text = paper_text();
    let no_surface = text.replacen("[surface]", "[other]", 1);
    fails(&no_surface, SceneErrorKind::Parse);
    let msg = fails("[material]\nmu = 1.0\n", SceneErrorKind::Invalid);
    assert_contains(&msg, &["missing geometry"]);
    let both = format!(
        "{text}\n[curve]\ndegree = 1\nknots = [0, 0, 1, 1]\ncontrol_points = [[0, 0, 0], [1, 0, 0]]\n"
    );
    let msg = fails(&both, SceneErrorKind::Invalid);
    assert_contains(&msg, &["exactly one of [surface] or [curve]"]);
}

#[test]
fn curve_specific_checks() {
    let base = "[curve]\ndegree = 2\nknots = [0, 0, 0, 0.5, 1, 1, 1]\ncontrol_points = [[0, 0, 0], [1, 1, 0], [2, 1, 0], [3, 0, 0]]\n";
    let s = Scene::from_str(base, "c.toml").unwrap();
    assert_eq!(s.geometry.net_dims(), (4, 1));
    let msg = fails(
        &format!("{base}weights = [1, 1, -2, 1]\n"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["curve.weights[2] = -2: weights must be positive"]);
    let msg = fails(
        &format!("{base}weights = [1, 1, 1]\n"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["curve.weights = 3 values"]);
    let msg = fails(
        &base.replace("0, 0.5, 1", "0, 1.5, 1"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["curve.knots[4] = 1", "non-decreasing"]);
    let msg = fails(
        &format!("{base}[material]\nbeta22 = 1.0\n"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["material.beta22 = 1: applies to surfaces only"]);
    let msg = fails(
        &format!("{base}[simulation]\nprobes = [[0.5, 0.5]]\n"),
        SceneErrorKind::Invalid,
    );
    assert_contains(&msg, &["simulation.probes[0] = [0.5, 0.5]", "[u]"]);
    let ok = Scene::from_str(
        &format!("{base}[constraints]\nfixed = [[0], [3]]\n"),
        "c.toml",
    )
    .unwrap();
    assert_eq!(ok.constraints.fixed, vec![vec![0], vec![3]]);
}

#[test]
fn all_problems_are_reported_together() {
    let text = edited("mu = 25.0", "mu = -1.0").replacen("dt = 0.08", "dt = 0", 1);
    let err = Scene::from_str(&text, "bad.toml").unwrap_err();
    assert_eq!(err.problems().len(), 2);
    let msg = err.to_string();
    assert_eq!(msg.lines().count(), 2);
    assert_contains(
        &msg,
        &["bad.toml: material.mu = -1", "bad.toml: simulation.dt = 0"],
    );
}

#[test]
fn io_errors() {
    let err = Scene::from_path("/definitely/not/here.toml").unwrap_err();
    assert_eq!(err.kind(), SceneErrorKind::Io);
    assert!(err.to_string().contains("here.toml"));
}

#[test]
fn spec_level_geometry_errors_name_keys() {
    let scene = Scene::from_path(data("paper.toml")).unwrap();
    let GeometrySpec::Surface(mut s) = scene.geometry else {
        panic!()
    };
    s.knots_v = vec![0., 0., 0., 0., 1., 0.5, 1., 1., 1.];
    let e = s.to_surface().unwrap_err();
    assert_eq!(e.kind(), SceneErrorKind::Invalid);
    assert!(
        e.to_string().starts_with("surface.knots_v[5] = 0.5: "),
        "{e}"
    );
    s.knots_v = vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.];
    s.weights = Some(vec![vec![1.0; 5]; 7]);
    s.weights.as_mut().unwrap()[4][3] = 0.0;
    let e = s.to_surface().unwrap_err();
    assert!(
        e.to_string().starts_with("surface.weights[4][3] = 0: "),
        "{e}"
    );
    s.weights = None;
    s.control_points[6][4][0] = f64::NAN;
    let e = s.to_surface().unwrap_err();
    assert!(
        e.to_string()
            .starts_with("surface.control_points[6][4] = NaN"),
        "{e}"
    );
}

// ---------------------------------------------------------------- property tests

/// A clamped knot vector of `degree` with `n` basis functions and random interior knots.
fn knots(degree: usize, n: usize) -> impl Strategy<Value = Vec<f64>> {
    let interior = n - degree - 1;
    proptest::collection::vec(0.001f64..0.999, interior).prop_map(move |mut inner| {
        inner.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut k = vec![0.0; degree + 1];
        k.extend(inner);
        k.extend(vec![1.0; degree + 1]);
        k
    })
}

fn coord() -> impl Strategy<Value = f64> {
    -100.0f64..100.0
}

fn surface() -> impl Strategy<Value = SurfaceSpec> {
    (1usize..=3, 1usize..=3, 0usize..4, 0usize..4)
        .prop_flat_map(|(p, q, eu, ev)| {
            let (nu, nv) = (p + 1 + eu, q + 1 + ev);
            (
                Just((p, q)),
                knots(p, nu),
                knots(q, nv),
                proptest::collection::vec(
                    proptest::collection::vec([coord(), coord(), coord()], nv),
                    nu,
                ),
                proptest::option::of(proptest::collection::vec(
                    proptest::collection::vec(0.1f64..10.0, nv),
                    nu,
                )),
            )
        })
        .prop_map(|((p, q), ku, kv, cp, w)| SurfaceSpec {
            degree_u: p,
            degree_v: q,
            knots_u: ku,
            knots_v: kv,
            control_points: cp,
            weights: w,
        })
}

fn curve() -> impl Strategy<Value = CurveSpec> {
    (1usize..=4, 0usize..5)
        .prop_flat_map(|(p, e)| {
            let n = p + 1 + e;
            (
                Just(p),
                knots(p, n),
                proptest::collection::vec([coord(), coord(), coord()], n),
                proptest::option::of(proptest::collection::vec(0.1f64..10.0, n)),
            )
        })
        .prop_map(|(p, k, cp, w)| CurveSpec {
            degree: p,
            knots: k,
            control_points: cp,
            weights: w,
        })
}

fn material() -> impl Strategy<Value = Material> {
    (
        0.01f64..100.0,
        proptest::collection::vec(prop_oneof![Just(0.0), 0.0f64..10.0], 6),
    )
        .prop_map(|(mu, v)| Material {
            mu,
            gamma: v[0],
            alpha11: v[1],
            alpha22: v[2],
            beta11: v[3],
            beta12: v[4],
            beta22: v[5],
        })
}

fn scene() -> impl Strategy<Value = Scene> {
    let geometry = prop_oneof![
        surface().prop_map(GeometrySpec::Surface),
        curve().prop_map(GeometrySpec::Curve)
    ];
    (
        geometry,
        material(),
        (
            1e-4f64..1.0,
            0.01f64..10.0,
            1usize..10,
            0usize..3,
            0usize..3,
        ),
        (
            0usize..3,
            2usize..8,
            2usize..8,
            any::<[bool; 3]>(),
            0.0f64..10.0,
            1e-4f64..1.0,
            -0.5f64..0.5,
        ),
        (
            [coord(), coord(), coord()],
            any::<bool>(),
            1usize..=8,
            0usize..3,
        ),
    )
        .prop_map(|(geometry, mut material, sim, lattice, rest)| {
            let (dt, t_end, save_every, dn, mi) = sim;
            let (grid, nodes_u, nodes_v, springs, k, mass, pre_strain) = lattice;
            let (velocity, nonneg, quadrature, fit) = rest;
            let surface = geometry.is_surface();
            if !surface {
                material.alpha22 = 0.0;
                material.beta12 = 0.0;
                material.beta22 = 0.0;
            }
            let dnurbs_integrator = [
                IntegratorKind::TerzopoulosQin,
                IntegratorKind::Newmark,
                IntegratorKind::Modal,
            ][dn];
            if dnurbs_integrator == IntegratorKind::Modal {
                material.gamma = 0.0;
            }
            let (n_u, n_v) = geometry.net_dims();
            let fixed_rings = usize::from(n_u >= 3 && (!surface || n_v >= 3));
            let probes = if surface {
                vec![vec![0.25, 0.75]]
            } else {
                vec![vec![0.3]]
            };
            Scene {
                path: PathBuf::from("random.toml"),
                geometry,
                material: nurbspring_dnurbs::MaterialModel::TensionPlate(material),
                loads: LoadsSpec {
                    gravity: [0.0, 0.0, -9.81],
                    distributed: velocity,
                    point: vec![PointLoadSpec {
                        u: 0.5,
                        v: surface.then_some(0.5),
                        force: velocity,
                    }],
                    edge: Vec::new(),
                },
                constraints: ConstraintsSpec {
                    fixed_rings,
                    ..ConstraintsSpec::default()
                },
                dnurbs: DnurbsOptions {
                    quadrature_points: Some(quadrature),
                    integration: if nonneg {
                        Integration::Area
                    } else {
                        Integration::Parameter
                    },
                    ..DnurbsOptions::default()
                },
                initial: InitialSpec {
                    velocity,
                    ..InitialSpec::default()
                },
                simulation: SimulationSpec {
                    dt,
                    t_end,
                    dnurbs_integrator,
                    msm_integrator: [
                        IntegratorKind::SymplecticEuler,
                        IntegratorKind::Rk4,
                        IntegratorKind::BackwardEuler,
                    ][mi],
                    save_every,
                    probes,
                    rho_infinity: 0.8,
                },
                msm: MsmSpec {
                    grid: Some(
                        [
                            LatticeGrid::Knots,
                            LatticeGrid::Uniform,
                            LatticeGrid::Greville,
                        ][grid],
                    ),
                    nodes_u,
                    nodes_v,
                    structural: springs[0] || !(springs[1] || springs[2]),
                    shear: springs[1],
                    bending: springs[2],
                    k_edge: Some(k),
                    k_diag: Some(k / 3.0),
                    k_bend: Some(0.0),
                    mass: Some(mass),
                    damping: Some(0.0),
                    pre_strain,
                    fixed: if nonneg {
                        MsmFixed::Auto
                    } else {
                        MsmFixed::Nodes(vec![if surface { vec![0, 0] } else { vec![0] }])
                    },
                    elements: None,
                },
                fit: FitSpec {
                    derivation: match fit {
                        1 => Some(Method::Paper),
                        2 => Some(Method::Modal),
                        _ => None,
                    },
                    dofs: if nonneg { FitDofs::Free } else { FitDofs::All },
                    nonnegative: nonneg,
                    method: if fit == 1 {
                        FitMethod::TrustRegion
                    } else {
                        FitMethod::ClosedForm
                    },
                    mass: if fit == 2 {
                        MassMethod::Fixed
                    } else {
                        MassMethod::EigenvalueScan
                    },
                    max_candidates: fit,
                    mass_scan: if nonneg {
                        MassScan::Complete
                    } else {
                        MassScan::Pruned
                    },
                },
                output: OutputSpec {
                    vtk_every: Some(save_every),
                },
            }
        })
}

/// A random edit of a scene text: cut, delete, duplicate or insert TOML-ish characters.
fn mutate(text: &str, op: usize, a: usize, b: usize, insert: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    let (i, j) = ((a % n).min(b % n), (a % n).max(b % n));
    let s = |r: std::ops::Range<usize>| chars[r].iter().collect::<String>();
    match op % 4 {
        0 => s(0..i),
        1 => format!("{}{}", s(0..i), s(j.min(i + 40)..chars.len())),
        2 => format!("{}{}{}", s(0..j), s(i..j), s(j..chars.len())),
        _ => format!("{}{insert}{}", s(0..i), s(i..chars.len())),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn valid_scenes_round_trip(scene in scene()) {
        let text = scene.to_toml();
        let back = Scene::from_str(&text, "random.toml");
        prop_assert!(back.is_ok(), "{}\n{}", back.unwrap_err(), text);
        prop_assert_eq!(back.unwrap(), scene);
    }

    #[test]
    fn mutated_scenes_never_panic(
        scene in scene(),
        ops in proptest::collection::vec((0usize..4, any::<usize>(), any::<usize>(), "[\\[\\]{}=,.\"'#\\n a-z0-9_+-]{0,8}"), 1..4),
    ) {
        let mut text = scene.to_toml();
        for (op, a, b, insert) in &ops {
            text = mutate(&text, *op, *a, *b, insert);
        }
        match Scene::from_str(&text, "m.toml") {
            Ok(s) => {
                // Whatever was accepted is valid and round-trips.
                let again = Scene::from_str(&s.to_toml(), "m.toml").unwrap();
                prop_assert_eq!(again, s);
            }
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.starts_with("m.toml: "), "{}", msg);
                prop_assert!(e.kind() != SceneErrorKind::Io);
            }
        }
    }

    #[test]
    fn random_text_never_panics(text in "[\\[\\]{}=,.\"'#\\n a-z0-9_+-]{0,200}") {
        let _ = Scene::from_str(&text, "r.toml");
    }
}

/// `[surface] file = "…"` loads the surface relative to the scene file; `to_toml` writes it
/// inline and reads back to the same scene; `[curve] file` likewise; problems name the key.
#[test]
fn geometry_from_a_file_relative_to_the_scene() {
    use nurbspring_scene::geometry_file::{GeometryFormat, write_geometry_file};
    let dir = tempfile::tempdir().unwrap();
    let paper = Scene::from_path(data("paper.toml")).unwrap();
    let surface = paper.to_surface().unwrap();
    let sub = dir.path().join("geometry");
    std::fs::create_dir(&sub).unwrap();
    write_geometry_file(
        &sub.join("sheet.igs"),
        GeometryFormat::Iges,
        &[paper.shape().unwrap()],
    )
    .unwrap();
    let text = paper_text();
    let start = text.find("[surface]").unwrap();
    let end = text.find("[material]").unwrap();
    let linked = format!(
        "{}[surface]\nfile = \"geometry/sheet.igs\"\n\n{}",
        &text[..start],
        &text[end..]
    );
    let path = dir.path().join("linked.toml");
    std::fs::write(&path, &linked).unwrap();
    let scene = Scene::from_path(&path).unwrap();
    assert_eq!(scene.to_surface().unwrap(), surface);
    assert_eq!(scene.geometry, paper.geometry);
    let back = Scene::from_str(&scene.to_toml(), &path).unwrap();
    assert_eq!(back, scene);

    // A curve.
    let string =
        Scene::from_path(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/string.toml"))
            .unwrap();
    write_geometry_file(
        &dir.path().join("string.obj"),
        GeometryFormat::ObjFreeForm,
        &[string.shape().unwrap()],
    )
    .unwrap();
    let curve = Scene::from_str(
        "[curve]\nfile = \"string.obj\"\n[material]\nmu = 1\nalpha11 = 1\n",
        dir.path().join("c.toml"),
    )
    .unwrap();
    assert_eq!(curve.to_curve().unwrap(), string.to_curve().unwrap());

    // Problems: a surface asked of a curve file, an index past the end, file next to inline keys.
    let err = Scene::from_str(
        "[surface]\nfile = \"string.obj\"\n",
        dir.path().join("s.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("surface.file = \"string.obj\"") && err.contains("no surface"),
        "{err}"
    );
    let err = Scene::from_str(
        "[curve]\nfile = \"string.obj\"\nindex = 2\n",
        dir.path().join("s.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("index 2"), "{err}");
    let err = Scene::from_str(
        "[curve]\nfile = \"string.obj\"\ndegree = 2\n",
        dir.path().join("s.toml"),
    )
    .unwrap_err();
    assert_eq!(err.kind(), SceneErrorKind::Parse);
    assert!(err.to_string().contains("`degree`"), "{err}");
    let err = Scene::from_str("[curve]\nindex = 1\n", "s.toml").unwrap_err();
    assert!(err.to_string().contains("no `file` key"), "{err}");
}
