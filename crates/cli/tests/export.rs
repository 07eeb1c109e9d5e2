//! Geometry in and out (`import`, `export --format geomdl-json|iges|obj`, `refine`, a scene's
//! `[surface] file`), models out (`export --format sofa|npz`), and the NumPy snippet of
//! docs/export.md against `simulate`'s trajectory.

use std::path::{Path, PathBuf};
use std::process::Command as Process;

use nurbspring_exchange::{Shape, geomdl, iges, obj};
use nurbspring_geom::{NurbsCurve, NurbsSurface};
use nurbspring_scene::Scene;

mod support;
use support::bin;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn examples() -> PathBuf {
    root().join("examples")
}

fn iges_fixture(name: &str) -> PathBuf {
    root().join("crates/exchange/tests/data/iges").join(name)
}

fn stderr_of(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stderr).into_owned()
}

/// The largest distance between two surfaces on an `n × n` grid of their common domain.
fn surface_gap(a: &NurbsSurface, b: &NurbsSurface, n: usize) -> f64 {
    assert_eq!(a.domain(), b.domain());
    let ((u0, u1), (v0, v1)) = a.domain();
    let mut worst = 0.0_f64;
    for i in 0..n {
        for j in 0..n {
            let u = u0 + (u1 - u0) * i as f64 / (n - 1) as f64;
            let v = v0 + (v1 - v0) * j as f64 / (n - 1) as f64;
            let (p, q) = (a.point(u, v).unwrap(), b.point(u, v).unwrap());
            for c in 0..3 {
                worst = worst.max((p[c] - q[c]).abs());
            }
        }
    }
    worst
}

fn curve_gap(a: &NurbsCurve, b: &NurbsCurve, n: usize) -> f64 {
    assert_eq!(a.domain(), b.domain());
    let (u0, u1) = a.domain();
    (0..n)
        .map(|i| {
            let u = u0 + (u1 - u0) * i as f64 / (n - 1) as f64;
            let (p, q) = (a.point(u).unwrap(), b.point(u).unwrap());
            (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

fn net_scale(points: &[[f64; 3]]) -> f64 {
    points.iter().flatten().fold(1.0_f64, |m, x| m.max(x.abs()))
}

/// `import` of an Open CASCADE IGES file writes a scene that loads, checks and holds the file's
/// surface bit for bit; `--link` writes `file = "…"` that resolves relative to the scene.
#[test]
fn import_iges_inline_and_linked() {
    let dir = tempfile::tempdir().unwrap();
    let igs = iges_fixture("ocp_faces.igs");
    let expected = iges::read_file(&igs).unwrap().shapes[0]
        .as_surface()
        .unwrap()
        .clone();
    let inline = dir.path().join("inline.toml");
    bin()
        .args(["import"])
        .arg(&igs)
        .arg("--out")
        .arg(&inline)
        .assert()
        .success();
    let text = std::fs::read_to_string(&inline).unwrap();
    assert!(
        text.starts_with("# Imported by `nurbspring import`"),
        "{text}"
    );
    assert!(text.contains("[material]") && text.contains("[constraints]"));
    let scene = Scene::from_path(&inline).unwrap();
    assert_eq!(scene.to_surface().unwrap(), expected);
    bin().arg("check").arg(&inline).assert().success();

    let sub = dir.path().join("scenes");
    std::fs::create_dir(&sub).unwrap();
    let copy = dir.path().join("patch.igs");
    std::fs::copy(&igs, &copy).unwrap();
    let linked = sub.join("linked.toml");
    bin()
        .arg("import")
        .arg(&copy)
        .args(["--link", "--out"])
        .arg(&linked)
        .assert()
        .success();
    let text = std::fs::read_to_string(&linked).unwrap();
    assert!(text.contains("file = \"../patch.igs\""), "{text}");
    let scene = Scene::from_path(&linked).unwrap();
    assert_eq!(scene.to_surface().unwrap(), expected);
}

/// geomdl JSON and OBJ import; `--curve` and `--index` choose the shape.
#[test]
fn import_geomdl_and_obj_curves_and_surfaces() {
    let dir = tempfile::tempdir().unwrap();
    let data = root().join("crates/exchange/tests/data/geomdl");
    let surfaces = geomdl::read_file(data.join("surfaces.json")).unwrap();
    let out = dir.path().join("s.toml");
    bin()
        .arg("import")
        .arg(data.join("surfaces.json"))
        .args(["--index", "1", "--out"])
        .arg(&out)
        .assert()
        .success();
    let s = Scene::from_path(&out).unwrap();
    assert_eq!(Shape::Surface(s.to_surface().unwrap()), surfaces[1]);

    let curves = geomdl::read_file(data.join("curves.json")).unwrap();
    let out = dir.path().join("c.toml");
    bin()
        .arg("import")
        .arg(data.join("curves.json"))
        .args(["--out"])
        .arg(&out)
        .assert()
        .success();
    let c = Scene::from_path(&out).unwrap();
    assert_eq!(Shape::Curve(c.to_curve().unwrap()), curves[0]);
    bin().arg("check").arg(&out).assert().success();

    // OBJ free-form, written by nurbspring from the paper's surface.
    let obj_file = dir.path().join("paper.obj");
    bin()
        .arg("export")
        .arg(examples().join("paper.toml"))
        .args(["--format", "obj", "--out"])
        .arg(&obj_file)
        .assert()
        .success();
    let out = dir.path().join("o.toml");
    bin()
        .arg("import")
        .arg(&obj_file)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let paper = Scene::from_path(examples().join("paper.toml")).unwrap();
    assert_eq!(
        Scene::from_path(&out).unwrap().to_surface().unwrap(),
        paper.to_surface().unwrap()
    );
    // Asking for a shape that is not there: exit 2, naming the file.
    let a = bin()
        .arg("import")
        .arg(data.join("curves.json"))
        .args(["--index", "99", "--curve", "--out"])
        .arg(dir.path().join("x.toml"))
        .assert()
        .code(2);
    let err = stderr_of(&a);
    assert!(
        err.contains("curves.json") && err.contains("missing entity"),
        "{err}"
    );
}

/// `export` writes the scene's geometry in each format; reading it back gives the same
/// surface (rational, from the half cylinder) bit for bit.
#[test]
fn export_geometry_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = examples().join("half_cylinder.toml");
    let surface = Scene::from_path(&scene_path).unwrap().to_surface().unwrap();
    for (format, file) in [
        ("geomdl-json", "s.json"),
        ("iges", "s.igs"),
        ("obj", "s.obj"),
    ] {
        let out = dir.path().join(file);
        bin()
            .arg("export")
            .arg(&scene_path)
            .args(["--format", format, "--out"])
            .arg(&out)
            .assert()
            .success();
        let shapes = match format {
            "geomdl-json" => geomdl::read_file(&out).unwrap(),
            "iges" => iges::read_file(&out).unwrap().shapes,
            _ => obj::read_file(&out).unwrap(),
        };
        assert_eq!(shapes, vec![Shape::Surface(surface.clone())], "{format}");
    }
    // A curve too.
    let out = dir.path().join("c.igs");
    bin()
        .arg("export")
        .arg(examples().join("string.toml"))
        .args(["--format", "iges", "--out"])
        .arg(&out)
        .assert()
        .success();
    let curve = Scene::from_path(examples().join("string.toml"))
        .unwrap()
        .to_curve()
        .unwrap();
    assert_eq!(
        iges::read_file(&out).unwrap().shapes,
        vec![Shape::Curve(curve)]
    );
    // An msm.json is not a scene.
    let a = bin()
        .arg("export")
        .arg(dir.path().join("msm.json"))
        .args(["--format", "iges", "--out"])
        .arg(dir.path().join("x.igs"))
        .assert()
        .code(2);
    assert!(stderr_of(&a).contains("msm.json"));
}

/// `--tessellate N`: an N × N quad mesh with one `vt` and one unit `vn` per vertex, faces `a/a/a`.
#[test]
fn tessellated_obj_has_normals_and_uvs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mesh.obj");
    bin()
        .arg("export")
        .arg(examples().join("half_cylinder.toml"))
        .args(["--format", "obj", "--tessellate", "9", "--out"])
        .arg(&out)
        .assert()
        .success();
    let text = std::fs::read_to_string(&out).unwrap();
    let count = |tag: &str| text.lines().filter(|l| l.starts_with(tag)).count();
    assert_eq!(count("v "), 81);
    assert_eq!(count("vt "), 81);
    assert_eq!(count("vn "), 81);
    assert_eq!(count("f "), 64);
    assert!(
        text.contains("\nf 1/1/1 10/10/10 11/11/11 2/2/2\n"),
        "{text}"
    );
    for l in text.lines().filter(|l| l.starts_with("vn ")) {
        let n: Vec<f64> = l[3..].split(' ').map(|x| x.parse().unwrap()).collect();
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-12, "{l}");
    }
    let vt: Vec<&str> = text.lines().filter(|l| l.starts_with("vt ")).collect();
    assert_eq!(vt[0], "vt 0 0");
    assert_eq!(vt[80], "vt 1 1");
    // The mesh still reads as a mesh.
    let mesh = nurbspring_io::output::read_obj(&out).unwrap();
    assert_eq!((mesh.vertices.len(), mesh.faces.len()), (81, 64));
}

/// `refine` moves nothing: the refined surface (rational, half cylinder; and the paper's sheet)
/// and curve evaluate to the same points as the coarse ones, to round-off.
#[test]
fn refine_keeps_the_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let half = std::fs::read_to_string(examples().join("half_cylinder.toml")).unwrap();
    let start = half.find("fixed = [").unwrap();
    let end = start + half[start..].find('\n').unwrap();
    let half = format!("{}fixed_rings = 1{}", &half[..start], &half[end..]);
    let half_path = dir.path().join("half.toml");
    std::fs::write(&half_path, half).unwrap();
    for (scene, args) in [
        (
            examples().join("paper.toml"),
            vec![
                "--elevate",
                "4,5",
                "--insert-u",
                "0.1,0.6,0.6",
                "--insert-v",
                "0.3",
            ],
        ),
        (
            half_path.clone(),
            vec![
                "--insert-u",
                "0.25,0.75",
                "--insert-v",
                "0.1,0.9",
                "--elevate",
                "3,3",
            ],
        ),
    ] {
        let out = dir.path().join("fine.toml");
        bin()
            .arg("refine")
            .arg(&scene)
            .args(&args)
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        let coarse = Scene::from_path(&scene).unwrap().to_surface().unwrap();
        let fine_scene = Scene::from_path(&out).unwrap();
        let fine = fine_scene.to_surface().unwrap();
        assert!(fine.n_control_points() > coarse.n_control_points());
        let gap = surface_gap(&coarse, &fine, 41);
        let scale = net_scale(coarse.control_points());
        assert!(
            gap <= 1e-13 * scale,
            "{}: moved by {gap:e}",
            scene.display()
        );
        bin().arg("check").arg(&out).assert().success();
    }
    // The paper's surface raised to degrees (4, 5).
    let fine = Scene::from_path(dir.path().join("fine.toml")).unwrap();
    assert!(fine.path.ends_with("fine.toml"));

    // A curve: degree 3 → 5 and two knots.
    let curve = dir.path().join("curve.toml");
    std::fs::write(
        &curve,
        "[curve]\ndegree = 2\nknots = [0, 0, 0, 0.4, 1, 1, 1]\n\
         control_points = [[0, 0, 0], [1, 2, 0], [2, -1, 1], [3, 0, 0]]\n\
         weights = [1, 0.5, 2, 1]\n[material]\nmu = 1\nalpha11 = 1\n[constraints]\nfixed_rings = 1\n",
    )
    .unwrap();
    let out = dir.path().join("curve_fine.toml");
    bin()
        .arg("refine")
        .arg(&curve)
        .args(["--elevate", "5", "--insert-u", "0.2,0.7", "--out"])
        .arg(&out)
        .assert()
        .success();
    let a = Scene::from_path(&curve).unwrap().to_curve().unwrap();
    let b = Scene::from_path(&out).unwrap().to_curve().unwrap();
    assert_eq!(b.basis().degree(), 5);
    assert!(curve_gap(&a, &b, 401) <= 1e-13 * 3.0);

    // Refusals, exit 2 naming the option or key.
    for (scene, args, needle) in [
        (curve.clone(), vec!["--elevate", "1"], "--elevate"),
        (curve.clone(), vec!["--insert-v", "0.5"], "--insert-v"),
        (curve.clone(), vec!["--insert-u", "7"], "--insert-u"),
        (
            examples().join("paper.toml"),
            vec!["--elevate", "4"],
            "--elevate",
        ),
        (
            examples().join("half_cylinder.toml"),
            vec!["--insert-u", "0.5"],
            "constraints.fixed",
        ),
        (
            examples().join("string.toml"),
            vec!["--insert-u", "0.5"],
            "initial.velocities",
        ),
        (curve.clone(), vec![], "nothing to do"),
    ] {
        let a = bin()
            .arg("refine")
            .arg(&scene)
            .args(&args)
            .arg("--out")
            .arg(dir.path().join("x.toml"))
            .assert()
            .code(2);
        let err = stderr_of(&a);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

/// Bad geometry files exit with status 2 and name the file and, where the format has lines, the
/// line: a zero weight, an unsupported entity type, a malformed record, inconsistent knot counts,
/// a missing entity; the same through a scene's `[surface] file`.
#[test]
fn bad_geometry_files_exit_2_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let paper = Scene::from_path(examples().join("paper.toml")).unwrap();
    let good = iges::write(&[Shape::Surface(paper.to_surface().unwrap())]);
    let import = |name: &str, text: &str| -> String {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let a = bin()
            .arg("import")
            .arg(&path)
            .arg("--out")
            .arg(dir.path().join("out.toml"))
            .assert()
            .code(2);
        let err = stderr_of(&a);
        assert!(err.contains(name), "{name}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        err
    };
    // Weight 0: the first weight of the 128 entity (all weights are 1.0 in the paper's sheet).
    let p_start = good.lines().position(|l| l.as_bytes()[72] == b'P').unwrap();
    let mut lines: Vec<String> = good.lines().map(str::to_string).collect();
    let (line_no, col) = lines
        .iter()
        .enumerate()
        .skip(p_start)
        .find_map(|(k, l)| l[..64].find("1.0,").map(|c| (k, c)))
        .unwrap();
    lines[line_no].replace_range(col..col + 4, "0.0,");
    let err = import("zero_weight.igs", &(lines.join("\n") + "\n"));
    assert!(err.contains("line ") && err.contains("weight"), "{err}");

    // Unsupported entity type: the 128 relabelled as a 120 (surface of revolution).
    let relabelled: String = good
        .lines()
        .map(|l| {
            let l = l.to_string();
            match l.as_bytes()[72] {
                b'D' if l.starts_with("     128") => format!("     120{}", &l[8..]),
                b'P' if l.starts_with("128,") => format!("120,{}", &l[4..]),
                _ => l,
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n";
    let err = import("revolution.igs", &relabelled);
    assert!(err.contains("120"), "{err}");

    // Malformed records: a short IGES line, a JSON syntax error, an OBJ statement.
    let mut short: Vec<&str> = good.lines().collect();
    let cut = &short[p_start][..40];
    short[p_start] = cut;
    let err = import("short.igs", &(short.join("\n") + "\n"));
    assert!(err.contains(&format!("line {}", p_start + 1)), "{err}");
    let err = import(
        "broken.json",
        "{\"shape\": {\"type\": \"surface\",\n \"data\": [}}",
    );
    assert!(err.contains("line 2"), "{err}");
    let err = import("broken.obj", "v 0 0 0\nv 1 0 0\ncstype bspline\ndeg x\n");
    assert!(err.contains("line 4"), "{err}");

    // Inconsistent knot count (geomdl JSON).
    let json = geomdl::write(&[Shape::Surface(paper.to_surface().unwrap())]).unwrap();
    let json = json.replacen("[0.0, 0.0, 0.0, 0.0, 0.25,", "[0.0, 0.0, 0.0, 0.25,", 1);
    let json = json.replacen("[0.0,0.0,0.0,0.0,0.25,", "[0.0,0.0,0.0,0.25,", 1);
    let err = import("knots.json", &json);
    assert!(err.contains("knot"), "{err}");

    // Unknown extension.
    let err = import("surface.step", "ISO-10303-21;");
    assert!(err.contains(".igs"), "{err}");

    // Through a scene: a missing file, a file without a surface, a bad file; all exit 2 naming
    // the scene, the key and the geometry file.
    let curve_only = dir.path().join("curve.json");
    let string = Scene::from_path(examples().join("string.toml")).unwrap();
    geomdl::write_file(&curve_only, &[Shape::Curve(string.to_curve().unwrap())]).unwrap();
    for (file, needle) in [
        ("absent.igs", "absent.igs"),
        ("curve.json", "missing entity"),
        ("zero_weight.igs", "line "),
    ] {
        let scene = dir.path().join("linked.toml");
        std::fs::write(
            &scene,
            format!("[surface]\nfile = \"{file}\"\n[material]\nmu = 1\nbeta11 = 1\n"),
        )
        .unwrap();
        let a = bin().arg("check").arg(&scene).assert().code(2);
        let err = stderr_of(&a);
        assert!(
            err.contains("linked.toml") && err.contains("surface.file") && err.contains(needle),
            "{file}: {err}"
        );
    }
    // `file` next to inline keys is refused.
    let scene = dir.path().join("both.toml");
    std::fs::write(
        &scene,
        "[surface]\nfile = \"x.igs\"\ndegree_u = 3\n[material]\nmu = 1\n",
    )
    .unwrap();
    let a = bin().arg("check").arg(&scene).assert().code(2);
    assert!(stderr_of(&a).contains("degree_u"));
}

/// The IGES example (an Open CASCADE file linked from the scene) holds the file's surface.
#[test]
fn iges_example_reads_its_file() {
    let scene = Scene::from_path(examples().join("iges_patch.toml")).unwrap();
    let expected = iges::read_file(examples().join("iges_patch.igs")).unwrap();
    assert_eq!(
        Shape::Surface(scene.to_surface().unwrap()),
        expected.shapes[0]
    );
}

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
