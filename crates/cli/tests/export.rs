//! Models out (`export --format sofa|newton|npz`), and the NumPy snippet of docs/export.md
//! against `simulate`'s trajectory.

use std::path::{Path, PathBuf};
use std::process::Command as Process;

mod support;
use support::{bin, examples, root, stderr_of};

/// A small msm.json with every feature the exports carry: springs with and without pre-strain,
/// linear elements of 2, 3 and 4 nodes, fixed nodes, damping, gravity, a node force and initial
/// velocities.
fn small_msm(dir: &Path, with_elements: bool, with_springs: bool) -> PathBuf {
    let (n_u, n_v) = (4, 3);
    let idx = |i: usize, j: usize| i * n_v + j;
    let mut nodes = Vec::new();
    for i in 0..n_u {
        for j in 0..n_v {
            let mut node = serde_json::json!({
                "position": [i as f64 * 0.5, j as f64 * 0.4, 0.05 * (i * j) as f64],
                "mass": 0.1 + 0.02 * (i + j) as f64,
                "fixed": i == 0,
                "damping": 0.03,
            });
            if (i, j) == (3, 1) {
                node["force"] = serde_json::json!([0.0, 0.2, -0.1]);
            }
            nodes.push(node);
        }
    }
    let mut springs = Vec::new();
    if with_springs {
        for i in 0..n_u {
            for j in 0..n_v {
                if i + 1 < n_u {
                    springs.push(serde_json::json!({"a": idx(i, j), "b": idx(i + 1, j), "k": 20.0, "rest_length": 0.45}));
                }
                if j + 1 < n_v {
                    springs
                        .push(serde_json::json!({"a": idx(i, j), "b": idx(i, j + 1), "k": 15.0}));
                }
                if i + 1 < n_u && j + 1 < n_v {
                    springs.push(serde_json::json!({"a": idx(i, j), "b": idx(i + 1, j + 1), "kind": "shear", "k": 5.0}));
                }
            }
        }
    }
    let mut elements = Vec::new();
    if with_elements {
        elements.push(
            serde_json::json!({"kind": "spring_u", "class": "spring_u@interior",
            "nodes": [idx(1, 1), idx(2, 1)], "k": 3.0, "weight": 0.8, "coefficients": [1.0, -1.0]}),
        );
        elements.push(
            serde_json::json!({"kind": "bend_u", "class": "bend_u@boundary",
            "nodes": [idx(0, 2), idx(1, 2), idx(2, 2)], "k": 0.5, "weight": 0.2,
            "coefficients": [4.0, -8.0, 4.0]}),
        );
        elements.push(
            serde_json::json!({"kind": "twist", "class": "twist@interior",
            "nodes": [idx(1, 0), idx(2, 0), idx(1, 1), idx(2, 1)], "k": 0.2, "weight": 0.2,
            "coefficients": [5.0, -5.0, -5.0, 5.0]}),
        );
    }
    let velocities: Vec<[f64; 3]> = (0..n_u * n_v)
        .map(|a| [0.0, 0.01 * a as f64, -0.05])
        .collect();
    let file = serde_json::json!({
        "nodes": nodes,
        "springs": springs,
        "elements": elements,
        "gravity": [0.0, 0.0, -9.81],
        "grid": [n_u, n_v],
        "initial_velocities": velocities,
        "simulation": {"dt": 0.002, "t_end": 0.6, "integrator": "symplectic-euler"},
    });
    let path = dir.join(format!(
        "msm{}{}.json",
        if with_elements { "_e" } else { "" },
        if with_springs { "_s" } else { "" }
    ));
    std::fs::write(&path, serde_json::to_string_pretty(&file).unwrap()).unwrap();
    path
}

/// The Python to use: `NURBSPRING_PYTHON`, else `python3`; `None` (the test is skipped) when
/// it cannot import `module`.
fn python_with(module: &str) -> Option<String> {
    let python = std::env::var("NURBSPRING_PYTHON").unwrap_or_else(|_| "python3".to_string());
    let ok = Process::new(&python)
        .args(["-c", &format!("import {module}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        Some(python)
    } else {
        eprintln!("skipped: {python} cannot import {module}");
        None
    }
}

fn read_csv(path: &Path) -> (String, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.trim().parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// The first ```python block of docs/export.md.
fn numpy_snippet() -> String {
    let doc = std::fs::read_to_string(root().join("docs/export.md")).unwrap();
    let start = doc.find("```python\n").unwrap() + "```python\n".len();
    let end = start + doc[start..].find("```").unwrap();
    doc[start..end].to_string()
}

fn assert_same_trajectory(ours: &Path, theirs: &Path) {
    let (h1, a) = read_csv(ours);
    let (h2, b) = read_csv(theirs);
    assert_eq!(h1, h2);
    assert_eq!(a.len(), b.len());
    assert!(a.len() > 10);
    let scale = a.iter().flatten().fold(1.0_f64, |m, x| m.max(x.abs()));
    let mut worst = 0.0_f64;
    for (r, s) in a.iter().zip(&b) {
        assert_eq!(r.len(), s.len());
        for (x, y) in r.iter().zip(s) {
            worst = worst.max((x - y).abs());
        }
    }
    assert!(worst <= 1e-10 * scale, "trajectories differ by {worst:e}");
    // The runs are not trivial: the probe moves.
    let first = &a[0];
    let moved = a
        .iter()
        .flat_map(|r| (1..r.len()).map(move |c| (r[c] - first[c]).abs()))
        .fold(0.0, f64::max);
    assert!(moved > 1e-3, "the probe moves by {moved:e} only");
}

/// The NumPy snippet of docs/export.md, run on the `.npz` export, reproduces `simulate`'s
/// trajectory.csv: on a hand-made model with every feature, on the derived string (linear
/// elements only) and on a scene's spring lattice. Skipped when no Python with NumPy is found
/// (`NURBSPRING_PYTHON` names the interpreter, default `python3`).
#[test]
fn numpy_snippet_reproduces_the_msm_trajectory() {
    let Some(python) = python_with("numpy") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("step_msm.py");
    std::fs::write(&script, numpy_snippet()).unwrap();
    let derived = dir.path().join("string");
    bin()
        .arg("derive")
        .arg(examples().join("string.toml"))
        .arg("--out")
        .arg(&derived)
        .assert()
        .success();
    // (model, integrator: None runs the one the archive records, with no flag to simulate).
    let small = small_msm(dir.path(), true, true);
    // Springs with axial damping and hinges with non-zero rest angles.
    let cloth = cloth_msm(dir.path(), true);
    let models: [(PathBuf, Option<&str>); 9] = [
        (cloth.clone(), Some("symplectic-euler")),
        (cloth, Some("backward-euler")),
        (small.clone(), Some("symplectic-euler")),
        (small.clone(), Some("verlet")),
        (small.clone(), Some("rk4")),
        (small.clone(), Some("backward-euler")),
        (small, Some("newmark")),
        // Linear elements only: its recorded integrator is modal.
        (derived.join("msm.json"), None),
        // A scene's own lattice: damping, gravity, two probes, every 10th step kept.
        (
            examples().join("sheet_gravity.toml"),
            Some("symplectic-euler"),
        ),
    ];
    for (k, (model, integrator)) in models.iter().enumerate() {
        let npz = dir.path().join(format!("model{k}.npz"));
        bin()
            .arg("export")
            .arg(model)
            .args(["--format", "npz", "--out"])
            .arg(&npz)
            .assert()
            .success();
        let run = dir.path().join(format!("run{k}"));
        let mut simulate = bin();
        simulate.arg("simulate").arg(model).args(["--model", "msm"]);
        if let Some(i) = integrator {
            simulate.args(["--integrator", i]);
        }
        simulate.arg("--out").arg(&run).assert().success();
        let theirs = dir.path().join(format!("numpy{k}.csv"));
        let mut python_run = Process::new(&python);
        python_run.arg(&script).arg(&npz).arg(&theirs);
        if let Some(i) = integrator {
            python_run.arg(i);
        }
        let out = python_run.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_same_trajectory(&run.join("trajectory.csv"), &theirs);
    }
    // Above the explicit limit the script refuses rather than stepping into overflow.
    let stiff = dir.path().join("stiff.npz");
    bin()
        .arg("export")
        .arg(examples().join("sheet_gravity.toml"))
        .args(["--format", "npz", "--k-edge", "1e6", "--out"])
        .arg(&stiff)
        .assert()
        .success();
    let out = Process::new(&python)
        .arg(&script)
        .arg(&stiff)
        .arg(dir.path().join("never.csv"))
        .arg("symplectic-euler")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unstable at dt") && err.contains("dt_critical"),
        "{err}"
    );
    assert!(!dir.path().join("never.csv").exists());
}

/// The meshio snippet of docs/export.md ("The lattice in other tools") turns the `.npz` of the
/// paper derivation into a mesh whose `line` cells are the springs, and meshio reads the VTU it
/// writes back. Skipped when no Python with meshio is found (`NURBSPRING_PYTHON`).
#[test]
fn meshio_snippet_reads_the_springs_from_the_npz() {
    let Some(python) = python_with("meshio") else {
        return;
    };
    let doc = std::fs::read_to_string(root().join("docs/export.md")).unwrap();
    let at = doc.find("```python\nimport meshio").unwrap() + "```python\n".len();
    let snippet = &doc[at..at + doc[at..].find("```").unwrap()];
    let dir = tempfile::tempdir().unwrap();
    let derived = dir.path().join("d");
    bin()
        .arg("derive")
        .arg(examples().join("paper.toml"))
        .args(["--derivation", "paper", "-q", "--out"])
        .arg(&derived)
        .assert()
        .success();
    bin()
        .arg("export")
        .arg(derived.join("msm.json"))
        .args(["--format", "npz", "--out"])
        .arg(dir.path().join("msm.npz"))
        .assert()
        .success();
    let check = "\nback = meshio.read('lattice_meshio.vtu')\n\
                 assert back.cells[0].type == 'line'\n\
                 assert np.array_equal(back.cells[0].data, z['springs'])\n\
                 print(len(back.cells[0].data))\n";
    let out = Process::new(&python)
        .current_dir(dir.path())
        .args(["-c", &format!("{snippet}{check}")])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let msm: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(derived.join("msm.json")).unwrap()).unwrap();
    let springs = msm["springs"].as_array().unwrap().len();
    assert!(springs > 0);
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        springs.to_string()
    );
}

/// The `.npz` arrays, read back with NumPy: names, shapes, dtypes and values.
#[test]
fn npz_export_holds_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let model = small_msm(dir.path(), true, true);
    let npz = dir.path().join("m.npz");
    bin()
        .arg("export")
        .arg(&model)
        .args(["--format", "npz", "--out"])
        .arg(&npz)
        .assert()
        .success();
    let bytes = std::fs::read(&npz).unwrap();
    assert_eq!(&bytes[..4], b"PK\x03\x04");
    for name in [
        "positions.npy",
        "springs.npy",
        "element_nodes.npy",
        "probe_nodes.npy",
    ] {
        assert!(
            bytes.windows(name.len()).any(|w| w == name.as_bytes()),
            "{name}"
        );
    }
    let Some(python) = python_with("numpy") else {
        return;
    };
    let check = r#"
import sys
import numpy as np
m = np.load(sys.argv[1])
assert m["positions"].shape == (12, 3) and m["positions"].dtype == np.float64
assert m["masses"].shape == (12,) and m["fixed"].dtype == np.bool_
assert m["fixed"].sum() == 3
assert m["springs"].shape == (23, 2) and m["springs"].dtype == np.int64
assert m["spring_k"].shape == (23,) and m["spring_rest_length"].shape == (23,)
assert abs(m["spring_rest_length"][0] - 0.45) < 1e-15
assert m["element_nodes"].shape == (3, 4)
assert list(m["element_nodes"][0]) == [4, 7, -1, -1]
assert list(m["element_coefficients"][1]) == [4.0, -8.0, 4.0, 0.0]
assert list(m["element_kind"]) == ["spring_u", "bend_u", "twist"]
assert m["element_class"][1] == "bend_u@boundary"
assert str(m["integrator"]) == "symplectic-euler"
assert float(m["dt"]) == 0.002 and int(m["save_every"]) == 1
assert list(m["grid"]) == [4, 3]
assert np.allclose(m["forces"][10], [0.0, 0.2, -0.1])
assert np.all(m["initial_velocities"][:3] == 0.0)
print("ok")
"#;
    let out = Process::new(&python)
        .args(["-c", check])
        .arg(&npz)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The SOFA scene: run its `createScene` against a stand-in for SofaPython3's node API and check
/// the components and their data; a model with linear elements is refused.
#[test]
fn sofa_scene_builds_the_graph() {
    let dir = tempfile::tempdir().unwrap();
    let springs_only = small_msm(dir.path(), false, true);
    let scene = dir.path().join("scene.py");
    let a = bin()
        .arg("export")
        .arg(&springs_only)
        .args(["--format", "sofa", "--out"])
        .arg(&scene)
        .assert()
        .success();
    assert!(stderr_of(&a).is_empty(), "{}", stderr_of(&a));
    let text = std::fs::read_to_string(&scene).unwrap();
    for needle in [
        "MechanicalObject",
        "DiagonalMass",
        "SpringForceField",
        "FixedProjectiveConstraint",
        "EulerExplicitSolver",
        "UniformVelocityDampingForceField",
        "SOFA holds every part of this model",
    ] {
        assert!(text.contains(needle), "{needle}");
    }

    // Springs and linear elements: leaving the elements out would change the model.
    let mixed = small_msm(dir.path(), true, true);
    let a = bin()
        .arg("export")
        .arg(&mixed)
        .args(["--format", "sofa", "--out"])
        .arg(dir.path().join("mixed.py"))
        .assert()
        .code(2);
    let err = stderr_of(&a);
    assert!(
        err.contains("3 linear elements") && err.contains("bend_u@boundary"),
        "{err}"
    );
    assert!(!dir.path().join("mixed.py").exists());
    let linear = small_msm(dir.path(), true, false);
    let a = bin()
        .arg("export")
        .arg(&linear)
        .args(["--format", "sofa", "--out"])
        .arg(dir.path().join("linear.py"))
        .assert()
        .code(2);
    assert!(stderr_of(&a).contains("--format npz"), "{}", stderr_of(&a));

    let Some(python) = python_with("sys") else {
        return;
    };
    let stub = r#"
import runpy, sys
class Node:
    def __init__(self, name):
        self.name, self.objects, self.children = name, [], []
    def addObject(self, kind, **data):
        self.objects.append((kind, data))
    def addChild(self, name):
        child = Node(name)
        self.children.append(child)
        return child
scene = runpy.run_path(sys.argv[1])
root = Node("root")
scene["createScene"](root)
body = root.children[0]
kinds = [k for k, _ in body.objects]
assert kinds == ["EulerExplicitSolver", "MechanicalObject", "DiagonalMass", "SpringForceField",
                 "FixedProjectiveConstraint", "UniformVelocityDampingForceField",
                 "ConstantForceField"], kinds
data = dict(body.objects)
assert data["EulerExplicitSolver"]["symplectic"] is True
assert len(data["MechanicalObject"]["position"]) == 12
assert len(data["DiagonalMass"]["vertexMass"]) == 12
assert data["FixedProjectiveConstraint"]["indices"] == [0, 1, 2]
spring = data["SpringForceField"]["spring"].split()
assert len(spring) == 5 * 23, len(spring)
assert spring[:5] == ["0", "3", "20.0", "0.0", "0.45"], spring[:5]
assert abs(data["UniformVelocityDampingForceField"]["dampingCoefficient"] - 0.03) < 1e-15
assert root.gravity == [0.0, 0.0, -9.81] and root.dt == 0.002
print("ok")
"#;
    let out = Process::new(&python)
        .args(["-c", stub])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A triangulated `n_u × n_v` cloth (alternating diagonals) with springs on every edge and a
/// hinge on every interior edge, rest angles left to the file's positions: flat, or with
/// `curved` a bump (non-zero rest angles). Two corners fixed, gravity, axial damping.
fn cloth_msm(dir: &Path, curved: bool) -> PathBuf {
    let (n_u, n_v) = (5, 4);
    let idx = |i: usize, j: usize| i * n_v + j;
    let mut nodes = Vec::new();
    for i in 0..n_u {
        for j in 0..n_v {
            let (x, y) = (
                i as f64 / (n_u - 1) as f64,
                0.8 * j as f64 / (n_v - 1) as f64,
            );
            let z = if curved {
                0.15 * (2.0 * x).sin() * y.cos()
            } else {
                0.0
            };
            nodes.push(serde_json::json!({
                "position": [x, y, z], "mass": 0.01, "damping": 0.002,
                "fixed": i == 0 && (j == 0 || j == n_v - 1),
            }));
        }
    }
    let mut triangles = Vec::new();
    for i in 0..n_u - 1 {
        for j in 0..n_v - 1 {
            let (p00, p10, p11, p01) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            if (i + j) % 2 == 0 {
                triangles.extend([[p00, p10, p11], [p00, p11, p01]]);
            } else {
                triangles.extend([[p00, p10, p01], [p10, p11, p01]]);
            }
        }
    }
    let (mut springs, mut hinges) = (Vec::new(), Vec::new());
    let mut first: std::collections::HashMap<(usize, usize), [usize; 3]> = Default::default();
    for t in &triangles {
        for c in 0..3 {
            let (f, to, o) = (t[c], t[(c + 1) % 3], t[(c + 2) % 3]);
            let key = (f.min(to), f.max(to));
            let grid = f / n_v == to / n_v || f % n_v == to % n_v;
            match first.remove(&key) {
                Some([f0, t0, o0]) => hinges.push(serde_json::json!({
                    "nodes": [f0, t0, o0, o],
                    "class": if grid { "hinge" } else { "hinge_diagonal" },
                    "k": if grid { 0.02 } else { 0.01 },
                })),
                None => {
                    springs.push(serde_json::json!({
                        "a": f, "b": to, "kind": if grid { "structural" } else { "shear" },
                        "k": if grid { 40.0 } else { 15.0 }, "damping": 0.01,
                    }));
                    first.insert(key, [f, to, o]);
                }
            }
        }
    }
    let file = serde_json::json!({
        "nodes": nodes, "springs": springs, "hinges": hinges, "triangles": triangles,
        "gravity": [0.0, 0.0, -9.81], "grid": [n_u, n_v],
        "simulation": {"dt": 0.0005, "t_end": 0.05, "integrator": "symplectic-euler"},
    });
    let path = dir.join(if curved {
        "cloth_curved.json"
    } else {
        "cloth_flat.json"
    });
    std::fs::write(&path, serde_json::to_string_pretty(&file).unwrap()).unwrap();
    path
}

/// Hinges in SOFA: a flat cloth's hinges become `FastTriangularBendingSprings` (with the
/// conversion said in the header); a curved rest shape, which SOFA's bending energy cannot hold
/// stress-free, is refused with exit status 2 naming the hinges. The Newton script refuses
/// linear elements, which Newton's particle model has no counterpart of.
#[test]
fn exporters_hold_hinges_or_refuse_what_they_cannot_express() {
    let dir = tempfile::tempdir().unwrap();
    let flat = cloth_msm(dir.path(), false);
    let scene = dir.path().join("cloth.py");
    let a = bin()
        .arg("export")
        .arg(&flat)
        .args(["--format", "sofa", "--out"])
        .arg(&scene)
        .assert()
        .success();
    assert!(
        stderr_of(&a).contains("hinges are FastTriangularBendingSprings"),
        "{}",
        stderr_of(&a)
    );
    let text = std::fs::read_to_string(&scene).unwrap();
    for needle in [
        "FastTriangularBendingSprings",
        "bendingStiffness",
        "BENDING = [",
    ] {
        assert!(text.contains(needle), "{needle}");
    }

    let curved = cloth_msm(dir.path(), true);
    let out = dir.path().join("curved.py");
    let a = bin()
        .arg("export")
        .arg(&curved)
        .args(["--format", "sofa", "--out"])
        .arg(&out)
        .assert()
        .code(2);
    let err = stderr_of(&a);
    assert!(err.contains("hinge") && err.contains("rest angle"), "{err}");
    assert!(!out.exists(), "nothing written on refusal");
    // The Newton script holds the curved cloth (rest angles are Newton's too).
    bin()
        .arg("export")
        .arg(&curved)
        .args(["--format", "newton", "--out"])
        .arg(dir.path().join("curved_newton.py"))
        .assert()
        .success();

    let linear = small_msm(dir.path(), true, true);
    let out = dir.path().join("linear_newton.py");
    let a = bin()
        .arg("export")
        .arg(&linear)
        .args(["--format", "newton", "--out"])
        .arg(&out)
        .assert()
        .code(2);
    let err = stderr_of(&a);
    assert!(
        err.contains("3 linear elements") && err.contains("--format npz"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written on refusal");
}
