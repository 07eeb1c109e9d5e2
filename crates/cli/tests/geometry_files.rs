//! Geometry in and out: `import`, `export --format geomdl-json|iges|obj`, `refine`, and a
//! scene's `[surface] file`.

use std::path::PathBuf;

use nurbspring_exchange::{Shape, geomdl, iges, obj};
use nurbspring_geom::{NurbsCurve, NurbsSurface};
use nurbspring_scene::Scene;

mod support;
use support::{bin, examples, root, stderr_of};

fn iges_fixture(name: &str) -> PathBuf {
    root().join("crates/exchange/tests/data/iges").join(name)
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
