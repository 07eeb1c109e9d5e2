//! The numbers the commands print and write, checked for value against the mechanics and
//! geometry they come from (not against what they printed last time).

use std::path::Path;

mod support;
use support::{bin, csv_rows, json_of, paper};

// ------------------------------------------------------------------ numbers checked for value
//
// The paper's net (examples/paper.toml): `x` depends on u alone and `y` on v alone (the control
// x by row, y by column), z ≡ 2, μ = 25 over the unit parameter square, no loads.

/// The paper's u knots and control x, v knots and control y, as 1-D cubic B-spline curves.
fn paper_profiles() -> (nurbspring_geom::NurbsCurve, nurbspring_geom::NurbsCurve) {
    use nurbspring_geom::{KnotVector, NurbsCurve};
    let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
    let xs = [0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.];
    let ys = [0., 0.83, 2.5, 4.16, 5.];
    let curve = |k: KnotVector, c: &[f64]| {
        NurbsCurve::try_new(
            k,
            c.iter().map(|&x| [x, 0.0, 0.0]).collect(),
            vec![1.0; c.len()],
        )
        .unwrap()
    };
    (curve(ku, &xs), curve(kv, &ys))
}

#[test]
fn eval_values_are_the_nets_profiles_and_their_calculus() {
    let (u, v, h) = (0.3, 0.7, 1e-4);
    let out = bin()
        .arg("eval")
        .arg(paper())
        .args(["--derivatives", "2"])
        .args(["--at", &format!("{u},{v}")])
        .args(["--at", &format!("{},{v}", u + h)])
        .args(["--at", &format!("{},{v}", u - h)])
        .assert()
        .success();
    let j = json_of(&out.get_output().stdout);
    let vec3 = |p: &serde_json::Value| -> [f64; 3] { [0, 1, 2].map(|i| p[i].as_f64().unwrap()) };
    let p = &j["points"][0];
    let point = vec3(&p["point"]);
    let d = |k: &str| vec3(&p["d"][k]);
    // x(u) and y(v) are the 1-D curves of the net's rows and columns, with their derivatives.
    let (cx, cy) = paper_profiles();
    let (ex, ey) = (cx.derivatives(u, 2).unwrap(), cy.derivatives(v, 2).unwrap());
    let close = |a: f64, b: f64, what: &str| {
        assert!(
            (a - b).abs() <= 1e-14 * b.abs().max(1.0),
            "{what}: {a} vs {b}"
        )
    };
    close(point[0], ex.point[0], "x");
    close(d("u")[0], ex.u[0], "x_u");
    close(d("uu")[0], ex.uu[0], "x_uu");
    close(point[1], ey.point[0], "y");
    close(d("v")[1], ey.u[0], "y_v");
    close(d("vv")[1], ey.uu[0], "y_vv");
    // z ≡ 2, and every derivative the profiles do not have is zero (to round-off of the
    // partition-of-unity sums, scale 5).
    close(point[2], 2.0, "z");
    let zero = |a: f64, what: &str| assert!(a.abs() <= 64.0 * f64::EPSILON * 5.0, "{what}: {a}");
    for (k, comps) in [("u", [1, 2]), ("uu", [1, 2]), ("v", [0, 2]), ("vv", [0, 2])] {
        for c in comps {
            zero(d(k)[c], &format!("{k}[{c}]"));
        }
    }
    for c in 0..3 {
        zero(d("uv")[c], &format!("uv[{c}]"));
    }
    // The central difference of the points at u ± h: error h²/6 |x'''| (x''' = O(10)).
    let (xp, xm) = (
        vec3(&j["points"][1]["point"])[0],
        vec3(&j["points"][2]["point"])[0],
    );
    let fd = (xp - xm) / (2.0 * h);
    assert!((fd - d("u")[0]).abs() < 1e-7, "{fd} vs {}", d("u")[0]);
}

#[test]
fn grid_values_are_points_of_the_surface() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.csv");
    bin()
        .arg("eval")
        .arg(paper())
        .args(["--grid", "9,6", "--out"])
        .arg(&path)
        .assert()
        .success();
    let (cx, cy) = paper_profiles();
    let rows = csv_rows(dir.path(), "grid.csv", Some("u,v,x,y,z"));
    for r in &rows {
        // The grid's own path (the net contracted per row) against the 1-D profiles.
        let (x, y) = (cx.point(r[0]).unwrap()[0], cy.point(r[1]).unwrap()[0]);
        for (got, want) in [(r[2], x), (r[3], y), (r[4], 2.0)] {
            assert!((got - want).abs() <= 1e-14 * want.abs().max(1.0), "{r:?}");
        }
    }
    assert_eq!(rows.len(), 9 * 6);
}

/// Entries `(i, j, value)` of a Matrix Market coordinate file, 0-based, both triangles.
fn matrix_market_symmetric(path: &Path) -> Vec<(usize, usize, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = Vec::new();
    for l in text.lines().filter(|l| !l.starts_with('%')).skip(1) {
        let f: Vec<&str> = l.split_whitespace().collect();
        let (i, j, v): (usize, usize, f64) = (
            f[0].parse().unwrap(),
            f[1].parse().unwrap(),
            f[2].parse().unwrap(),
        );
        out.push((i - 1, j - 1, v));
        if i != j {
            out.push((j - 1, i - 1, v));
        }
    }
    out
}

/// M's entries of one coordinate sum to μ × parameter area (partition of unity, docs/math.md
/// §3), M and K couple no two coordinates, K annihilates rigid translations (the energy has
/// only derivatives of c), the load is zero; the free-dof pencil's `Σ ω² = tr(M⁻¹K)` equals
/// the sum over every mode `modes` prints.
#[test]
fn matrices_and_modes_values_follow_from_mechanics() {
    let dir = tempfile::tempdir().unwrap();
    bin()
        .arg("matrices")
        .arg(paper())
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    let m = matrix_market_symmetric(&dir.path().join("M.mtx"));
    let k = matrix_market_symmetric(&dir.path().join("K.mtx"));
    let n = 105;
    for c in 0..3 {
        let sum: f64 = m.iter().filter(|e| e.0 % 3 == c).map(|e| e.2).sum();
        assert!(
            (sum - 25.0).abs() <= 1e-12 * 25.0,
            "Σ M over coordinate {c}: {sum}"
        );
    }
    assert!(m.iter().chain(&k).all(|e| e.0 % 3 == e.1 % 3));
    let k_max = k.iter().fold(0.0_f64, |a, e| a.max(e.2.abs()));
    for c in 0..3 {
        let mut kt = vec![0.0; n];
        for &(i, j, v) in &k {
            if j % 3 == c {
                kt[i] += v;
            }
        }
        let worst = kt.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        assert!(worst <= 1e-12 * k_max, "K · translation {c}: {worst:e}");
    }
    let f = std::fs::read_to_string(dir.path().join("f.mtx")).unwrap();
    let values: Vec<f64> = f
        .lines()
        .filter(|l| !l.starts_with('%'))
        .skip(1)
        .map(|l| l.trim().parse().unwrap())
        .collect();
    assert_eq!(values.len(), n);
    assert!(values.iter().all(|&x| x == 0.0));
    // tr(M_ff⁻¹ K_ff) by Gauss–Jordan on the free dofs of dofs.json.
    let dofs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("dofs.json")).unwrap())
            .unwrap();
    let free: Vec<usize> = dofs["free_dofs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect();
    let nf = free.len();
    let pos = |d: usize| free.iter().position(|&f| f == d);
    let dense = |entries: &[(usize, usize, f64)]| {
        let mut a = vec![vec![0.0; nf]; nf];
        for &(i, j, v) in entries {
            if let (Some(a_i), Some(a_j)) = (pos(i), pos(j)) {
                a[a_i][a_j] += v;
            }
        }
        a
    };
    let (mut mf, mut kf) = (dense(&m), dense(&k));
    for col in 0..nf {
        let piv = mf[col][col];
        for r in 0..nf {
            if r != col {
                let factor = mf[r][col] / piv;
                for c in 0..nf {
                    mf[r][c] -= factor * mf[col][c];
                    kf[r][c] -= factor * kf[col][c];
                }
            }
        }
    }
    let trace: f64 = (0..nf).map(|i| kf[i][i] / mf[i][i]).sum();
    let out = bin()
        .arg("modes")
        .arg(paper())
        .args(["--count", &nf.to_string()])
        .assert()
        .success();
    let omega: Vec<f64> = json_of(&out.get_output().stdout)["omega"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(omega.len(), nf);
    let sum: f64 = omega.iter().map(|w| w * w).sum();
    assert!(
        (sum - trace).abs() <= 1e-10 * trace,
        "Σω² = {sum}, tr(M⁻¹K) = {trace}"
    );
}

/// `stability`'s ω_max (Lanczos) against the dense generalized eigenvalues of the scene's MSM
/// at rest.
#[test]
fn stability_value_is_the_largest_dense_eigenvalue() {
    use nurbspring_sim::DynamicModel;
    let out = bin().arg("stability").arg(paper()).assert().success();
    let w = json_of(&out.get_output().stdout)["omega_max"]
        .as_f64()
        .unwrap();
    let scene = nurbspring_scene::Scene::from_path(paper()).unwrap();
    let setup = scene.msm_setup(&Default::default()).unwrap();
    let model = &setup.model;
    let k = model
        .tangent_stiffness(model.initial_positions())
        .to_dense();
    let m = model.mass().to_sparse().to_dense();
    let eig = nurbspring_linalg::generalized_symmetric_eigen(&k, &m).unwrap();
    let dense = eig.values.last().unwrap().sqrt();
    assert!((w - dense).abs() <= 1e-7 * dense, "{w} vs {dense}");
}

/// `derive`'s report against its own files and definitions: the validation's relative RMS
/// recomputed from central_node.csv, the scan's choice from its candidates, ω_max · Δt_crit = 2,
/// and the masses of msm.json summed.
#[test]
fn derive_report_values_follow_from_its_files() {
    let dir = tempfile::tempdir().unwrap();
    bin()
        .arg("derive")
        .arg(paper())
        .args(["--derivation", "paper", "-q", "--out"])
        .arg(dir.path())
        .assert()
        .success();
    let read = |f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path().join(f)).unwrap()).unwrap()
    };
    let (report, msm) = (read("report.json"), read("msm.json"));
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    // central_node.csv: t, D-NURBS x y z, MSM x y z.
    let rows = csv_rows(
        dir.path(),
        "central_node.csv",
        Some(
            "t,dnurbs_x[u=0.5;v=0.5],dnurbs_y[u=0.5;v=0.5],dnurbs_z[u=0.5;v=0.5],msm_x[node=7;u=0.5;v=0.5],msm_y[node=7;u=0.5;v=0.5],msm_z[node=7;u=0.5;v=0.5]",
        ),
    );
    let validation = &report["validation"];
    assert_eq!(rows.len() as u64, validation["samples"].as_u64().unwrap());
    let first = &rows[0];
    let (mut sum, mut amplitude) = (0.0, 0.0_f64);
    for r in &rows {
        sum += (1..4).map(|c| (r[c] - r[c + 3]).powi(2)).sum::<f64>();
        amplitude = amplitude.max(
            (1..4)
                .map(|c| (r[c] - first[c]).powi(2))
                .sum::<f64>()
                .sqrt(),
        );
    }
    let rms = (sum / rows.len() as f64).sqrt();
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(num(&validation["rms"]), rms) < 1e-12);
    assert!(rel(num(&validation["relative_rms"]), rms / amplitude) < 1e-12);
    assert!(rel(num(&validation["dnurbs_amplitude"]), amplitude) < 1e-12);
    // The scan keeps the finite candidate with the smallest RMS.
    let best = report["mass"]["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["rms"].is_f64())
        .min_by(|a, b| num(&a["rms"]).total_cmp(&num(&b["rms"])))
        .unwrap();
    assert_eq!(num(&report["mass"]["selected"]), num(&best["m"]));
    let derived = &report["derived"];
    assert_eq!(num(&derived["m"]), num(&best["m"]));
    assert!((num(&derived["omega_max"]) * num(&derived["dt_critical"]) - 2.0).abs() < 1e-12);
    // The totals of the mass report are the node masses of msm.json.
    let nodes = msm["nodes"].as_array().unwrap();
    let total: f64 = nodes.iter().map(|n| num(&n["mass"])).sum();
    let free: f64 = nodes
        .iter()
        .filter(|n| n["fixed"] == false)
        .map(|n| num(&n["mass"]))
        .sum();
    assert!(rel(num(&report["mass"]["total_msm"]), total) < 1e-12);
    assert!(rel(num(&report["mass"]["free_msm"]), free) < 1e-12);
    // The D-NURBS mass is μ × parameter area (25 for the paper's sheet).
    assert!(rel(num(&report["mass"]["total_dnurbs"]), 25.0) < 1e-12);
}
