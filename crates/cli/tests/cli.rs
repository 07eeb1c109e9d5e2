//! End-to-end tests of the binary: every example scene, every command, and bad input.

use std::path::{Path, PathBuf};

use assert_cmd::Command;

mod support;
use support::null_in;

fn bin() -> Command {
    let mut c = Command::cargo_bin("nurbspring").unwrap();
    c.arg("--quiet");
    c
}

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn paper() -> PathBuf {
    examples().join("paper.toml")
}

fn json_of(out: &[u8]) -> serde_json::Value {
    serde_json::from_slice(out)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(out)))
}

/// A scene written to a temp folder.
fn scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Every example scene passes `check`; every tension-plate example `derive`s (the
/// Kirchhoff–Love examples are run by tests/shell.rs, their spring derivation too, and the
/// paper's derivation refuses them naming the option and the derivations a shell takes).
#[test]
fn every_example_checks() {
    let mut n = 0;
    for entry in std::fs::read_dir(examples()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let out = bin()
                .arg("check")
                .arg(&path)
                .arg("--json")
                .assert()
                .success();
            let v = json_of(&out.get_output().stdout);
            assert!(
                v["dnurbs"]["free_dofs"].as_u64().unwrap() > 0,
                "{}",
                path.display()
            );
            if v["material"]["model"] == "kirchhoff-love" {
                assert!(v["material"]["bending_stiffness"].as_f64().unwrap() > 0.0);
                let out = bin()
                    .arg("derive")
                    .arg(&path)
                    .arg("--derivation")
                    .arg("paper")
                    .arg("--out")
                    .arg(tempfile::tempdir().unwrap().path())
                    .assert()
                    .code(2);
                let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
                assert!(
                    err.contains("--derivation") && err.contains("springs"),
                    "{err}"
                );
                continue;
            }
            // Every example derives an MSM with non-negative constants and a finite error.
            let dir = tempfile::tempdir().unwrap();
            bin()
                .arg("derive")
                .arg(&path)
                .arg("--out")
                .arg(dir.path())
                .assert()
                .success();
            let report: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(dir.path().join("report.json")).unwrap(),
            )
            .unwrap();
            for k in ["k_edge", "k_diag", "k_bend"] {
                if let Some(x) = report["derived"][k].as_f64() {
                    assert!(x >= 0.0, "{}: {k} = {x}", path.display());
                }
            }
            assert!(
                report["validation"]["rms"].as_f64().unwrap().is_finite(),
                "{}",
                path.display()
            );
            assert_eq!(null_in(&report, "report"), None, "{}", path.display());
            n += 1;
        }
    }
    assert!(n >= 3, "expected at least three example scenes, found {n}");
    // The paper's derivation of its scene: the derived MSM run explicitly above its limit
    // diverges, and what it lacks (its error, its period) is left out, never written as null.
    let dir = tempfile::tempdir().unwrap();
    bin()
        .arg("derive")
        .arg(paper())
        .args(["--derivation", "paper", "--out"])
        .arg(dir.path())
        .assert()
        .success();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    assert!(report["paper_parameters"]["explicit_run"]["msm_stopped"].is_string());
    assert_eq!(null_in(&report, "report"), None);
}

/// `eval` at the paper's centre: the printed net gives z = 2 and the point lies in the sheet.
#[test]
fn eval_prints_points_and_derivatives() {
    let out = bin()
        .args(["eval"])
        .arg(paper())
        .args(["--at", "0.5,0.5", "--at", "0,0", "--derivatives", "2"])
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let pts = v["points"].as_array().unwrap();
    assert_eq!(pts.len(), 2);
    assert!((pts[0]["point"][2].as_f64().unwrap() - 2.0).abs() <= 4.0 * f64::EPSILON * 2.0);
    assert_eq!(pts[1]["point"][0].as_f64().unwrap(), 0.0);
    for key in ["u", "v", "uu", "uv", "vv"] {
        assert_eq!(pts[0]["d"][key].as_array().unwrap().len(), 3, "{key}");
    }
    // Without --derivatives there is no "d".
    let out = bin()
        .arg("eval")
        .arg(paper())
        .args(["--at", "0.25,0.75"])
        .assert()
        .success();
    assert!(
        json_of(&out.get_output().stdout)["points"][0]
            .get("d")
            .is_none()
    );
}

#[test]
fn parameter_outside_domain_is_exit_2() {
    let out = bin()
        .arg("eval")
        .arg(paper())
        .args(["--at", "1.5,0.5"])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(err.contains("1.5"), "{err}");
}

#[test]
fn matrices_writes_matrix_market_and_dofs() {
    let dir = tempfile::tempdir().unwrap();
    bin()
        .arg("matrices")
        .arg(paper())
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    for f in ["M.mtx", "D.mtx", "K.mtx", "f.mtx", "dofs.json"] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
    let dofs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("dofs.json")).unwrap())
            .unwrap();
    assert_eq!(dofs["n_dofs"], 105);
    assert_eq!(dofs["free_dofs"].as_array().unwrap().len(), 9);
    let m = std::fs::read_to_string(dir.path().join("M.mtx")).unwrap();
    assert!(m.starts_with("%%MatrixMarket matrix coordinate real symmetric\n"));
    // Only the lower triangle, no explicit zeros; D of γ = 0 has no entries.
    let entries = |text: &str| -> Vec<(usize, usize, f64)> {
        text.lines()
            .filter(|l| !l.starts_with('%'))
            .skip(1)
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (
                    f[0].parse().unwrap(),
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                )
            })
            .collect()
    };
    let m = entries(&m);
    assert!(!m.is_empty());
    assert!(m.iter().all(|&(i, j, v)| i >= j && v != 0.0));
    let d = std::fs::read_to_string(dir.path().join("D.mtx")).unwrap();
    assert!(d.ends_with("\n105 105 0\n"), "{d}");
}

#[test]
fn modes_are_ascending_and_positive() {
    let out = bin()
        .arg("modes")
        .arg(paper())
        .args(["--count", "3"])
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let w: Vec<f64> = v["omega"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(w.len(), 3);
    assert!(w[0] > 0.0 && w[0] <= w[1] && w[1] <= w[2], "{w:?}");
    let t0 = v["periods"][0].as_f64().unwrap();
    assert!((t0 - 2.0 * std::f64::consts::PI / w[0]).abs() < 1e-12 * t0);
}

#[test]
fn stability_prints_omega_max_and_dt_critical() {
    let out = bin().arg("stability").arg(paper()).assert().success();
    let v = json_of(&out.get_output().stdout);
    let w = v["omega_max"].as_f64().unwrap();
    let dt = v["dt_critical"].as_f64().unwrap();
    assert!((w * dt - 2.0).abs() < 1e-12);
}

#[test]
fn simulate_dnurbs_writes_trajectory_energy_and_series() {
    let dir = tempfile::tempdir().unwrap();
    bin()
        .arg("simulate")
        .arg(paper())
        .args(["--model", "dnurbs", "--t-end", "0.8", "--out"])
        .arg(dir.path())
        .assert()
        .success();
    let traj = std::fs::read_to_string(dir.path().join("trajectory.csv")).unwrap();
    let header = traj.lines().next().unwrap();
    // Each probe's column says where it is (the centre of the domain first).
    assert!(
        header.starts_with("t,probe0_x[u=0.5;v=0.5],probe0_y[u=0.5;v=0.5],probe0_z[u=0.5;v=0.5]"),
        "{header}"
    );
    assert_eq!(traj.lines().count(), 1 + 11);
    assert!(dir.path().join("energy.csv").exists());
    let pvd = std::fs::read_to_string(dir.path().join("surface.pvd")).unwrap();
    assert!(pvd.contains("surface_000000.vts"));
    // Frames carry displacement and velocity; a control-net series runs alongside.
    let frame = std::fs::read_to_string(dir.path().join("surface_000003.vts")).unwrap();
    assert!(frame.contains("Name=\"displacement\"") && frame.contains("Name=\"velocity\""));
    let net = std::fs::read_to_string(dir.path().join("control_net.pvd")).unwrap();
    assert_eq!(net.matches("<DataSet").count(), 11);
    assert!(net.contains("file=\"control_net_000010.vtu\""));
    let frame = std::fs::read_to_string(dir.path().join("control_net_000010.vtu")).unwrap();
    for name in ["displacement", "velocity", "weight"] {
        assert!(frame.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    assert!(frame.contains("NumberOfPoints=\"35\"") && frame.contains("NumberOfCells=\"58\""));
    // A curve's frames are polylines in .vtu files of a curve.pvd series.
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("simulate")
        .arg(examples().join("string.toml"))
        .args(["--model", "dnurbs", "--t-end", "0.05", "--json", "--out"])
        .arg(dir.path())
        .assert()
        .success();
    assert_eq!(json_of(&out.get_output().stdout)["pvd"], "curve.pvd");
    let pvd = std::fs::read_to_string(dir.path().join("curve.pvd")).unwrap();
    assert!(pvd.contains("file=\"curve_000005.vtu\""), "{pvd}");
    let frame = std::fs::read_to_string(dir.path().join("curve_000005.vtu")).unwrap();
    assert!(frame.contains("<UnstructuredGrid>") && frame.contains("Name=\"velocity\""));
    assert!(dir.path().join("control_net_000005.vtu").exists());
}

#[test]
fn simulate_msm_explicit_above_limit_is_refused_then_forced() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model",
            "msm",
            "--integrator",
            "symplectic-euler",
            "--dt",
            "0.08",
            "--out",
        ])
        .arg(dir.path())
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(err.contains("--dt") && err.contains("unstable"), "{err}");
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model",
            "msm",
            "--integrator",
            "symplectic-euler",
            "--dt",
            "0.08",
            "--force-unstable",
            "--out",
        ])
        .arg(dir.path())
        .assert()
        .code(1);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(err.contains("step"), "{err}");
    // --force-unstable alone forces the scene's own explicit integrator: the same failure.
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args(["--model", "msm", "--force-unstable", "--out"])
        .arg(dir.path())
        .assert()
        .code(1);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(err.contains("step"), "{err}");
    // The implicit run is fine; without -q it prints the stability line on stderr, and the
    // result line on stdout.
    let out = Command::cargo_bin("nurbspring")
        .unwrap()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model",
            "msm",
            "--integrator",
            "backward-euler",
            "--t-end",
            "0.8",
            "--out",
        ])
        .arg(dir.path())
        .assert()
        .success();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.get_output().stdout).to_string(),
        String::from_utf8_lossy(&out.get_output().stderr).to_string(),
    );
    assert!(
        stderr.starts_with("stability: omega_max = ") && stderr.contains("backward-euler"),
        "{stderr}"
    );
    assert_eq!(
        stdout.trim(),
        format!(
            "MSM run (backward-euler, 10 steps, 11 samples, 11 ParaView frames) written to {}",
            dir.path().display()
        )
    );
    assert!(dir.path().join("lattice.pvd").exists());
    // -q keeps the result line and hides the stability line.
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model",
            "msm",
            "--integrator",
            "newmark",
            "--t-end",
            "0.8",
        ])
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    assert!(out.get_output().stderr.is_empty());
    assert!(String::from_utf8_lossy(&out.get_output().stdout).starts_with("MSM run (newmark"));
}

/// Out of the box the paper scene's MSM run (symplectic Euler at Δt = 0.08 > Δt_crit) falls
/// back to newmark with one warning line; the summary's Δt_crit is `stability`'s.
#[test]
fn simulate_msm_above_the_limit_runs_substeps_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args(["--model", "msm", "--t-end", "0.8", "--json", "--out"])
        .arg(dir.path())
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    assert_eq!(v["model"], "msm");
    assert_eq!(v["integrator"], "symplectic-euler");
    assert_eq!(v["dt"], 0.08);
    assert_eq!(v["steps"], 10);
    assert_eq!(v["samples"], 11);
    assert_eq!(v["frames"], 11);
    let stability = json_of(
        &bin()
            .arg("stability")
            .arg(paper())
            .assert()
            .success()
            .get_output()
            .stdout,
    );
    assert_eq!(v["dt_critical"], stability["dt_critical"]);
    let dt_critical = v["dt_critical"].as_f64().unwrap();
    assert!(dt_critical < 0.08, "{dt_critical}");
    // The substep is below the limit at rest (the uniform limit is at most that one).
    let n = v["substeps"].as_u64().unwrap() as usize;
    let h = 0.08 / n as f64;
    assert!(
        n >= 2 && h < dt_critical,
        "{n} substeps of {h} against {dt_critical}"
    );
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("warning: symplectic-euler is unstable at dt = 0.08 s")
            && stderr.contains(&format!("{dt_critical:.4e}"))
            && stderr.contains(&format!("running it in {n} substeps of dt/{n}")),
        "{stderr}"
    );
    assert_eq!(
        v["warnings"][0].as_str().unwrap(),
        stderr["warning: ".len()..].trim_end()
    );
    // The substeps are plain steps of dt/n: the run asked for at that step gives the same
    // states at every n-th sample.
    let plain = tempfile::tempdir().unwrap();
    bin()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model",
            "msm",
            "--integrator",
            "symplectic-euler",
            "--t-end",
            "0.8",
        ])
        .args(["--dt", &format!("{h}"), "--out"])
        .arg(plain.path())
        .assert()
        .success();
    let (rows, plain_rows) = (trajectory_rows(dir.path()), trajectory_rows(plain.path()));
    assert_eq!(plain_rows.len(), 10 * n + 1);
    for (k, row) in rows.iter().enumerate() {
        let other = &plain_rows[k * n];
        assert!(
            (row[0] - other[0]).abs() <= 1e-15,
            "t {} vs {}",
            row[0],
            other[0]
        );
        assert_eq!(row[1..], other[1..], "sample {k}");
    }
    // No load potential; the total is the sum of its parts.
    for r in &energy_rows(dir.path()) {
        assert_eq!(r[3], 0.0);
        assert!((r[4] - (r[1] + r[2] + r[3])).abs() <= 1e-15 * r[4], "{r:?}");
    }
}

#[test]
fn simulate_msm_falls_back_to_newmark_when_substeps_would_be_too_many() {
    // At dt = 200 s the paper's lattice (dt_critical 0.046 s) would need more than 4096
    // substeps a step: the implicit scheme runs instead, with a warning.
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model", "msm", "--dt", "200", "--t-end", "400", "--json", "--out",
        ])
        .arg(dir.path())
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    assert_eq!(v["integrator"], "newmark");
    assert_eq!(v["substeps"], 1);
    assert_eq!(v["steps"], 2);
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        stderr.starts_with("warning: symplectic-euler is unstable at dt = 200 s")
            && stderr.contains("running newmark instead"),
        "{stderr}"
    );
    // Newmark conserves the undamped, unloaded lattice's energy closely.
    let rows = energy_rows(dir.path());
    let e0 = rows[0][4];
    for r in &rows {
        assert!((r[4] - e0).abs() <= 1e-2 * e0, "{r:?} vs {e0}");
    }
}

/// The rows of a CSV file of `dir` after its header (checked when given).
fn csv_rows(dir: &Path, file: &str, header: Option<&str>) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    let mut lines = text.lines();
    let first = lines.next().unwrap();
    if let Some(h) = header {
        assert_eq!(first, h, "{file}");
    }
    lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect()
}

/// The rows of `trajectory.csv` (t, then x, y, z of each probe).
fn trajectory_rows(dir: &Path) -> Vec<Vec<f64>> {
    csv_rows(dir, "trajectory.csv", None)
}

/// The rows of `energy.csv` after checking its header.
fn energy_rows(dir: &Path) -> Vec<Vec<f64>> {
    csv_rows(dir, "energy.csv", Some("t,kinetic,elastic,external,total"))
}

/// Under gravity the elastic energy stays ≥ 0 and the load potential is its own column, for
/// both models: the sheet falls, so the load potential decreases from its initial value.
#[test]
fn energy_columns_separate_elastic_and_load_potential() {
    for model in ["dnurbs", "msm"] {
        let dir = tempfile::tempdir().unwrap();
        bin()
            .arg("simulate")
            .arg(examples().join("sheet_gravity.toml"))
            .args(["--model", model, "--t-end", "0.2", "--out"])
            .arg(dir.path())
            .assert()
            .success();
        let rows = energy_rows(dir.path());
        // 40 steps, a sample every 10.
        assert_eq!(rows.len(), 5, "{model}");
        let (first, last) = (&rows[0], &rows[rows.len() - 1]);
        assert_eq!(first[1], 0.0, "{model}: starts at rest");
        for r in &rows {
            assert!(r[1] >= 0.0 && r[2] >= 0.0, "{model}: {r:?}");
            let scale = r[1].abs() + r[2].abs() + r[3].abs();
            assert!(
                (r[4] - (r[1] + r[2] + r[3])).abs() <= 1e-14 * scale,
                "{r:?}"
            );
        }
        assert!(last[3] < first[3], "{model}: {first:?} -> {last:?}");
        assert!(last[1] > 0.0 && last[2] > 0.0, "{model}: {last:?}");
        if model == "msm" {
            assert_eq!(
                first[3], 0.0,
                "the MSM's load potential is zero at the start"
            );
        }
    }
}

/// Without `output.vtk_every` a long run writes at most 200 frames, evenly spaced, and says how
/// to get more; with it, every requested frame.
#[test]
fn simulate_writes_at_most_200_frames_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(paper())
        .unwrap()
        .replace("[output]\nvtk_every = 1\n", "");
    let p = scene(dir.path(), "long.toml", &text);
    let out = Command::cargo_bin("nurbspring")
        .unwrap()
        .arg("simulate")
        .arg(&p)
        .args(["--model", "dnurbs", "--dt", "0.002", "--json", "--out"])
        .arg(dir.path().join("run"))
        .assert()
        .success();
    // 2000 steps, 2001 samples: a frame every ⌈2001 / 200⌉ = 11 samples, ⌈2001 / 11⌉ = 182.
    let v = json_of(&out.get_output().stdout);
    assert_eq!(v["samples"], 2001);
    assert_eq!(v["vtk_every"], 11);
    assert_eq!(v["frames"], 182);
    let pvd = std::fs::read_to_string(dir.path().join("run/surface.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 182);
    let second: f64 = pvd
        .split("timestep=\"")
        .nth(2)
        .unwrap()
        .split('"')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((second - 11.0 * 0.002).abs() < 1e-12, "{second}");
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(stderr.contains("output.vtk_every"), "{stderr}");
    // The paper scene sets vtk_every = 1: a frame per sample.
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args(["--model", "dnurbs", "--json", "--out"])
        .arg(dir.path().join("run"))
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    assert_eq!(
        (v["samples"].as_u64(), v["frames"].as_u64()),
        (Some(51), Some(51))
    );
}

/// `check` warns (stderr, and `warnings` in --json) for Δt above the explicit limit, zero
/// stiffness and a body free to move rigidly; the other examples have no warnings.
#[test]
fn check_warns_for_unstable_dt_zero_stiffness_and_rigid_motion() {
    let out = bin()
        .arg("check")
        .arg(paper())
        .arg("--json")
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let w: Vec<&str> = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    let dt_critical = v["msm"]["dt_critical"].as_f64().unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("simulation.dt = 0.08 is above the explicit limit")
            && w[0].contains(&format!("dt_critical = {dt_critical:.4e} s"))
            && w[0].contains("symplectic-euler"),
        "{w:?}"
    );
    let text = bin().arg("check").arg(paper()).assert().success();
    let stderr = String::from_utf8_lossy(&text.get_output().stderr).to_string();
    assert_eq!(stderr.trim_end(), format!("warning: {}", w[0]));

    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(examples().join("sheet_gravity.toml")).unwrap();
    let soft = good
        .replace("alpha11 = 20.0", "alpha11 = 0.0")
        .replace("alpha22 = 20.0", "alpha22 = 0.0")
        .replace("beta11 = 0.05", "beta11 = 0.0")
        .replace("beta22 = 0.05", "beta22 = 0.0");
    let free: String = good
        .lines()
        .filter(|l| !l.starts_with("fixed ="))
        .map(|l| format!("{l}\n"))
        .collect();
    for (name, text, needle) in [
        (
            "soft.toml",
            soft,
            "material: zero stiffness (alpha11, alpha22, beta11, beta12, beta22 all 0)",
        ),
        (
            "free.toml",
            free,
            "constraints: no fixed control points, no linear constraints and no edge conditions",
        ),
    ] {
        let p = scene(dir.path(), name, &text);
        let out = bin().arg("check").arg(&p).arg("--json").assert().success();
        let v = json_of(&out.get_output().stdout);
        let w = v["warnings"].as_array().unwrap();
        assert_eq!(w.len(), 1, "{name}: {w:?}");
        assert!(w[0].as_str().unwrap().starts_with(needle), "{name}: {w:?}");
    }
    for example in [
        "sheet_gravity.toml",
        "half_cylinder.toml",
        "string.toml",
        "iges_patch.toml",
    ] {
        let out = bin()
            .arg("check")
            .arg(examples().join(example))
            .arg("--json")
            .assert()
            .success();
        let v = json_of(&out.get_output().stdout);
        assert_eq!(v["warnings"], serde_json::json!([]), "{example}");
    }
}

/// An msm.json (or any .json) where a scene is expected: exit 2 and a message saying what the
/// file is and which commands take it, not a TOML parse error.
#[test]
fn msm_json_as_a_scene_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = scene(dir.path(), "msm.json", "{\"format\": \"nurbspring-msm\"}");
    for args in [
        vec!["check"],
        vec!["simulate", "--model", "dnurbs", "--out", "x"],
        vec!["derive", "--out", "x"],
    ] {
        let out = bin()
            .arg(args[0])
            .arg(&p)
            .args(&args[1..])
            .current_dir(dir.path())
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("msm.json: a JSON file, not a scene")
                && err.contains("simulate FILE --model msm")
                && !err.contains("TOML parse"),
            "{args:?}: {err}"
        );
        assert!(!dir.path().join("x").exists());
    }
}

/// `--integrator` lists its values; an unknown one is refused by clap (exit 2) with the list.
#[test]
fn integrator_values_are_listed() {
    let out = bin().args(["simulate", "--help"]).assert().success();
    let help = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    for name in [
        "terzopoulos-qin",
        "newmark",
        "backward-euler",
        "symplectic-euler",
        "verlet",
        "rk4",
        "modal",
    ] {
        assert!(help.contains(&format!("- {name}:")), "{name}: {help}");
    }
    let out = bin()
        .arg("simulate")
        .arg(paper())
        .args(["--model", "msm", "--integrator", "euler", "--out", "x"])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        err.contains("possible values") && err.contains("backward-euler"),
        "{err}"
    );
    // The top-level help explains the tool and shows an example.
    let out = bin().arg("--help").assert().success();
    let help = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    assert!(help.contains("Examples:") && help.contains("nurbspring derive examples/paper.toml"));
    assert!(help.contains("--json"), "{help}");
}

/// Every command that reports numbers has --json with its report's keys.
#[test]
fn matrices_and_derive_print_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("matrices")
        .arg(paper())
        .args(["--json", "--out"])
        .arg(dir.path().join("m"))
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    assert_eq!(v["dofs"], 105);
    assert_eq!(v["free_dofs"], 9);
    // γ = 0: D has no entries.
    assert_eq!(v["stored_entries"]["D"], 0);
    let k = std::fs::read_to_string(dir.path().join("m/K.mtx")).unwrap();
    let size = k.lines().find(|l| !l.starts_with('%')).unwrap();
    assert_eq!(size, format!("105 105 {}", v["stored_entries"]["K"]));
    let out = bin()
        .arg("derive")
        .arg(paper())
        .args(["--derivation", "paper", "--json", "--out"])
        .arg(dir.path().join("d"))
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("d/report.json")).unwrap())
            .unwrap();
    assert_eq!(v, file);
    assert!(v["derived"]["k_edge"].as_f64().unwrap() > 0.0);
    // The figures: the mass scan's x unit and selected mass, the scene MSM's k_bend, the
    // energy legend.
    let svg = |name: &str| std::fs::read_to_string(dir.path().join("d").join(name)).unwrap();
    let scan = svg("mass_scan.svg");
    let selected = v["mass"]["selected"].as_f64().unwrap();
    assert!(
        scan.contains("node mass m [kg] (an eigenvalue of M)"),
        "{scan}"
    );
    assert!(
        scan.contains(&format!("selected m = {selected:.6}")),
        "{scan}"
    );
    let central = svg("central_node.svg");
    assert!(
        central.contains("scene&apos;s MSM k_edge=2.7225, k_diag=0.8661, k_bend=0, m=0.005"),
        "{central}"
    );
    let energy = svg("energy.svg");
    // Both models: the D-NURBS reference (its exact modal solution, energies in closed form)
    // and the derived MSM.
    for needle in [
        "D-NURBS total (kinetic + elastic + load)",
        "D-NURBS kinetic",
        "MSM total (kinetic + elastic + load)",
        "MSM kinetic",
        "energy / largest kinetic + elastic energy of the model",
    ] {
        assert!(energy.contains(needle), "{needle}");
    }
}

/// `derive` writes every file; msm.json is loadable by `simulate --model msm`.
#[test]
fn derive_writes_everything_and_msm_json_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    bin()
        .arg("derive")
        .arg(paper())
        .args(["--derivation", "paper"])
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    for f in [
        "msm.json",
        "report.json",
        "report.md",
        "central_node.csv",
        "central_node.svg",
        "central_node.png",
    ] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    for key in [
        "/fit/all_dofs/k_edge",
        "/fit/all_dofs/k_diag",
        "/fit/all_dofs/relative_residual",
        "/fit/free_dofs/k_edge",
        "/fit/free_dofs/k_diag",
        "/fit/free_dofs/relative_residual",
        "/mass/eigenvalues",
        "/mass/candidates",
        "/mass/selected",
        "/paper_parameters/dt_critical",
        "/derived/dt_critical",
        "/validation/rms",
        "/validation/max_abs",
        "/validation/relative_rms",
    ] {
        assert!(report.pointer(key).is_some(), "report.json lacks {key}");
    }
    let csv = std::fs::read_to_string(dir.path().join("central_node.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        // Where each model is watched: the D-NURBS at the central node's parameters.
        "t,dnurbs_x[u=0.5;v=0.5],dnurbs_y[u=0.5;v=0.5],dnurbs_z[u=0.5;v=0.5],msm_x[node=7;u=0.5;v=0.5],msm_y[node=7;u=0.5;v=0.5],msm_z[node=7;u=0.5;v=0.5]"
    );
    let sim_dir = dir.path().join("sim");
    bin()
        .arg("simulate")
        .arg(dir.path().join("msm.json"))
        .args(["--model", "msm", "--t-end", "0.4", "--out"])
        .arg(&sim_dir)
        .assert()
        .success();
    assert!(sim_dir.join("trajectory.csv").exists());
}

/// Bad scenes: exit code 2, one clear message naming the key, nothing left half-written.
#[test]
fn bad_scenes_exit_2_with_a_message() {
    let good = std::fs::read_to_string(paper()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "decreasing knots",
            good.replacen("0.25, 0.5, 0.75", "0.5, 0.25, 0.75", 1),
            "knots_u",
        ),
        (
            "negative mu",
            good.replacen("mu = 25.0", "mu = -25.0", 1),
            "mu",
        ),
        (
            "unknown key",
            good.replacen("mu = 25.0", "muu = 25.0", 1),
            "mu",
        ),
        ("truncated", good[..good.len() / 3].to_string(), "line"),
        ("dt zero", good.replacen("dt = 0.08", "dt = 0.0", 1), "dt"),
        (
            "nan",
            good.replacen("beta11 = 0.01", "beta11 = nan", 1),
            "beta11",
        ),
    ];
    for (name, text, key) in cases {
        let p = scene(
            dir.path(),
            &format!("{}.toml", name.replace(' ', "_")),
            &text,
        );
        let out_dir = dir.path().join(format!("out_{}", name.replace(' ', "_")));
        let out = bin()
            .arg("derive")
            .arg(&p)
            .arg("--out")
            .arg(&out_dir)
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
        assert!(err.contains(key), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(
            !out_dir.exists() || std::fs::read_dir(&out_dir).unwrap().next().is_none(),
            "{name}: output left"
        );
    }
}

/// Bad derivation input: exit code 2 and a message naming the key, for the scene key and the
/// command-line flag alike.
#[test]
fn derivation_refusals_exit_2_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let paper_text = std::fs::read_to_string(paper()).unwrap();
    let quiet = paper_text.replacen(
        "velocity = [0.0, 0.0, -0.2]",
        "velocity = [0.0, 0.0, 0.0]",
        1,
    );
    assert_ne!(
        quiet, paper_text,
        "the paper's scene sets an initial velocity"
    );
    let string = std::fs::read_to_string(examples().join("string.toml")).unwrap();
    let cases: Vec<(&str, String, Vec<&str>, &str)> = vec![
        (
            "excitation without excitation",
            quiet,
            vec!["--derivation", "excitation"],
            "initial.velocity",
        ),
        (
            "reduction onto more nodes than control points",
            paper_text.replacen(
                "[msm]",
                "[msm]\ngrid = \"uniform\"\nnodes_u = 12\nnodes_v = 9",
                1,
            ),
            vec!["--derivation", "reduction"],
            "msm.grid",
        ),
        (
            "twist on a curve",
            string.clone() + "\n[msm]\nelements = [\"twist\"]\n",
            vec![],
            "msm.elements",
        ),
        (
            "a kind twice",
            paper_text.replacen("[msm]", "[msm]\nelements = [\"bend_u\", \"bend_u\"]", 1),
            vec![],
            "msm.elements",
        ),
        (
            "no kind",
            paper_text.replacen("[msm]", "[msm]\nelements = []", 1),
            vec![],
            "msm.elements",
        ),
        (
            "unknown derivation",
            paper_text.replacen("[fit]", "[fit]\nderivation = \"magic\"", 1),
            vec![],
            "derivation",
        ),
    ];
    for (name, text, args, key) in cases {
        let p = scene(
            dir.path(),
            &format!("{}.toml", name.replace(' ', "_")),
            &text,
        );
        let out_dir = dir.path().join(format!("out_{}", name.replace(' ', "_")));
        let out = bin()
            .arg("derive")
            .arg(&p)
            .args(&args)
            .arg("--out")
            .arg(&out_dir)
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
        assert!(err.contains(key), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(
            !out_dir.exists() || std::fs::read_dir(&out_dir).unwrap().next().is_none(),
            "{name}: output left"
        );
    }
}

#[test]
fn missing_file_is_exit_2() {
    let out = bin()
        .args(["check", "/nonexistent/scene.toml"])
        .assert()
        .code(2);
    assert!(String::from_utf8_lossy(&out.get_output().stderr).contains("/nonexistent/scene.toml"));
}

/// The paper command runs, prints the verdict table and writes the outputs.
#[test]
fn paper_command_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("paper")
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    for needle in [
        "k_edge",
        "k_diag",
        "m (an eigenvalue",
        "Figure 3",
        "verdict",
    ] {
        assert!(text.contains(needle), "{needle} missing from:\n{text}");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    assert!(report["paper"]["verdicts"].as_array().unwrap().len() >= 5);
    // The readings whose explicit run diverges leave their error out: no null in the report.
    assert_eq!(null_in(&report, "report"), None);
    // --json prints that report.json instead of the table.
    let out = bin()
        .arg("paper")
        .arg("--json")
        .arg("--out")
        .arg(dir.path())
        .assert()
        .success();
    let printed = json_of(&out.get_output().stdout);
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    assert_eq!(printed, written);
    assert_eq!(printed["paper"]["verdicts"], report["paper"]["verdicts"]);
}

/// The built-in scene is the example file.
#[test]
fn built_in_scene_is_the_example() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    bin().arg("paper").arg("--out").arg(&a).assert().success();
    bin()
        .arg("derive")
        .arg(paper())
        .args(["--derivation", "paper"])
        .arg("--out")
        .arg(&b)
        .assert()
        .success();
    let ra: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("report.json")).unwrap()).unwrap();
    let rb: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(b.join("report.json")).unwrap()).unwrap();
    assert_eq!(ra["fit"], rb["fit"]);
    assert_eq!(ra["mass"], rb["mass"]);
}

/// `steady`: a clamped sheet sags under gravity; a free-floating one is refused (exit 2).
#[test]
fn steady_state_sags_and_free_body_is_refused() {
    let out = bin()
        .arg("steady")
        .arg(examples().join("sheet_gravity.toml"))
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let dz = v["probes"][0]["displacement"][2].as_f64().unwrap();
    assert!(dz < 0.0, "{dz}");
    let free = std::fs::read_to_string(examples().join("sheet_gravity.toml"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("fixed ="))
        .collect::<Vec<_>>()
        .join("\n");
    let dir = tempfile::tempdir().unwrap();
    let p = scene(dir.path(), "free.toml", &free);
    let out = bin().arg("steady").arg(&p).assert().code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        err.contains("free.toml") && err.to_lowercase().contains("singular"),
        "{err}"
    );
}

/// The rational sheet of the scene tests (weights as unknowns, free weights, one ring fixed).
fn rational_sheet() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scene/tests/data/rational_sheet.toml"),
    )
    .unwrap()
}

#[test]
fn modes_count_the_unknowns_solved_and_say_what_they_linearize() {
    let dir = tempfile::tempdir().unwrap();
    let linear = rational_sheet().replace(
        "fixed_weights = false",
        "fixed_weights = false\n\
         [[constraints.linear]]\nterms = [{ point = [1, 1], component = \"z\" }, { point = [3, 3], component = \"z\", coefficient = -1.0 }]\n\
         [[constraints.linear]]\nterms = [{ point = [2, 2], component = \"w\" }]\nrhs = 1.25",
    );
    let p = scene(dir.path(), "linear.toml", &linear);
    let out = bin()
        .arg("modes")
        .arg(&p)
        .args(["--count", "2"])
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let check = bin().arg("check").arg("--json").arg(&p).assert().success();
    let c = json_of(&check.get_output().stdout);
    let free = c["dnurbs"]["free_dofs"].as_u64().unwrap();
    assert_eq!(v["free_dofs"].as_u64().unwrap(), free - 2, "{v}");
    assert_eq!(c["dnurbs"]["reduced_dofs"].as_u64().unwrap(), free - 2);
    assert!(
        v["matrices"]
            .as_str()
            .unwrap()
            .contains("linearized at the initial shape"),
        "{v}"
    );
    // A weight in a linear constraint removes the scale ambiguity: no weight is pinned.
    assert!(c["dnurbs"].get("scale_fixing_weight").is_none(), "{c}");
}

#[test]
fn steady_with_weights_as_unknowns_reports_the_nonlinear_solve() {
    let dir = tempfile::tempdir().unwrap();
    let p = scene(dir.path(), "sheet.toml", &rational_sheet());
    let out = bin().arg("steady").arg(&p).assert().success();
    let v = json_of(&out.get_output().stdout);
    assert!(
        v["solve"]["equations"]
            .as_str()
            .unwrap()
            .starts_with("nonlinear")
    );
    assert!(v["solve"]["iterations"].as_u64().unwrap() > 1);
    assert!(v["solve"]["relative_residual"].as_f64().unwrap() <= 1e-13);
    assert!(v["probes"][0]["displacement"][2].as_f64().unwrap() < 0.0);
    let check = bin().arg("check").arg(&p).assert().success();
    let text = String::from_utf8_lossy(&check.get_output().stdout).to_string();
    assert!(
        text.contains(
            "scale_fixing_weight: \"weight of control point [0, 0] (dof 3) held at w = 1\""
        ),
        "{text}"
    );
}

#[test]
fn coarse_rule_warns_and_bad_fixed_point_weights_is_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let coarse = rational_sheet().replace(
        "weights_as_dofs = true",
        "weights_as_dofs = true\nquadrature_points = 2",
    );
    let p = scene(dir.path(), "coarse.toml", &coarse);
    let out = bin().arg("modes").arg(&p).assert().success();
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        err.contains("warning: dnurbs.quadrature_points = 2"),
        "{err}"
    );
    let bad = rational_sheet().replace(
        "fixed_weights = false",
        "fixed_weights = true\nfixed_point_weights = \"held\"",
    );
    let p = scene(dir.path(), "bad.toml", &bad);
    let out = bin().arg("check").arg(&p).assert().code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        err.contains("bad.toml") && err.contains("constraints.fixed_point_weights = \"held\""),
        "{err}"
    );
}

/// `-q` hides progress and notes, never a command's result line.
#[test]
fn quiet_keeps_the_result_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: Vec<(Vec<std::ffi::OsString>, String)> = vec![
        (
            vec![
                "matrices".into(),
                paper().into(),
                "--out".into(),
                d.join("m").into(),
            ],
            "wrote M, D, K (105 × 105, symmetric;".to_string(),
        ),
        (
            vec![
                "refine".into(),
                paper().into(),
                "--insert-u".into(),
                "0.1".into(),
                "--out".into(),
                d.join("r.toml").into(),
            ],
            "refined surface".to_string(),
        ),
        (
            vec![
                "export".into(),
                paper().into(),
                "--format".into(),
                "geomdl-json".into(),
                "--out".into(),
                d.join("x.json").into(),
            ],
            "surface".to_string(),
        ),
    ];
    for (args, start) in cases {
        let out = bin().args(&args).assert().success();
        let stdout = String::from_utf8_lossy(&out.get_output().stdout).to_string();
        assert_eq!(stdout.lines().count(), 1, "{args:?}: {stdout}");
        assert!(
            stdout.starts_with(&start) && stdout.contains(" to "),
            "{args:?}: {stdout}"
        );
    }
}

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

/// A damped cloth with no `[msm]` constants and two probes of its own.
fn cloth_without_constants(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(paper())
        .unwrap()
        .lines()
        .filter(|l| {
            !["k_edge", "k_diag", "mass =", "damping ="]
                .iter()
                .any(|k| l.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n")
        .replace("gamma = 0.0", "gamma = 0.5")
        .replace(
            "t_end = 4.0",
            "t_end = 0.8\nprobes = [[0.2, 0.3], [0.7, 0.6]]",
        );
    let path = dir.join("cloth.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A scene without its MSM's constants has no model of its own: `simulate --model msm`,
/// `stability` and `export --format sofa|npz` refuse it (exit 2) naming the keys and the
/// command that derives one, instead of writing k = 1 and 1 kg a node; with the constants given
/// as flags they run. `check` says which keys are missing and computes no stability limit.
#[test]
fn a_scene_without_msm_constants_is_never_run_from_placeholders() {
    let dir = tempfile::tempdir().unwrap();
    let cloth = cloth_without_constants(dir.path());
    let text = std::fs::read_to_string(&cloth).unwrap();
    assert!(
        !text.contains("k_edge") && text.contains("gamma = 0.5"),
        "{text}"
    );
    let refused = |args: &[&str]| {
        let out = bin().args(args).arg(&cloth).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        for needle in ["msm.k_edge", "msm.k_diag", "msm.mass", "nurbspring derive"] {
            assert!(err.contains(needle), "{args:?}: {err}");
        }
    };
    let out = dir.path().join("x");
    let out = out.to_str().unwrap();
    refused(&["simulate", "--model", "msm", "--out", out]);
    refused(&["export", "--format", "sofa", "--out", out]);
    refused(&["export", "--format", "npz", "--out", out]);
    refused(&["stability"]);
    assert!(!Path::new(out).exists());
    let check = bin()
        .arg("check")
        .arg("--json")
        .arg(&cloth)
        .output()
        .unwrap();
    assert!(check.status.success());
    let v: serde_json::Value = serde_json::from_slice(&check.stdout).unwrap();
    assert_eq!(
        v["msm"]["missing"],
        serde_json::json!(["msm.k_edge", "msm.k_diag", "msm.mass"])
    );
    assert!(v["msm"]["dt_critical"].is_null());
    assert_eq!(v["derive"]["lattice"], "greville");
    assert_eq!(v["simulation"]["steps"], 10);
    // Given as flags, the lattice runs; its damping is the material's per unit mass, γ/μ · m.
    let sofa = dir.path().join("cloth.py");
    bin()
        .arg("export")
        .arg(&cloth)
        .args([
            "--format", "sofa", "--k-edge", "2", "--k-diag", "1", "--mass", "0.4",
        ])
        .arg("--out")
        .arg(&sofa)
        .assert()
        .success();
    let py = std::fs::read_to_string(&sofa).unwrap();
    assert!(
        py.contains("NODE_DAMPING = 0.008"),
        "γ/μ · m = 0.5/25 · 0.4"
    );
    assert!(py.contains("runSofa cloth.py") && !py.contains("{this file}"));
}

/// Every probe of a scene survives into msm.json (`probe_nodes`, the centre first), and the
/// trajectory of the derived model records each one, its column naming the node and its (u, v).
#[test]
fn a_derived_model_keeps_every_probe() {
    let dir = tempfile::tempdir().unwrap();
    let cloth = cloth_without_constants(dir.path());
    let derived = dir.path().join("d");
    bin()
        .arg("derive")
        .arg(&cloth)
        .args(["--derivation", "paper", "-q", "--out"])
        .arg(&derived)
        .assert()
        .success();
    let msm: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(derived.join("msm.json")).unwrap()).unwrap();
    let probes = msm["probe_nodes"].as_array().unwrap();
    assert_eq!(probes.len(), 3);
    // Node damping is γ/μ times the node mass (the paper's derivation too).
    for node in msm["nodes"].as_array().unwrap() {
        let (m, c) = (
            node["mass"].as_f64().unwrap(),
            node["damping"].as_f64().unwrap(),
        );
        assert!((c - 0.02 * m).abs() <= 1e-15, "{c} vs {m}");
    }
    let run = dir.path().join("run");
    bin()
        .arg("simulate")
        .arg(derived.join("msm.json"))
        .args(["--model", "msm", "-q", "--out"])
        .arg(&run)
        .assert()
        .success();
    let text = std::fs::read_to_string(run.join("trajectory.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!(header.len(), 1 + 3 * 3);
    for (p, node) in probes.iter().enumerate() {
        let a = node.as_u64().unwrap() as usize;
        let uv = msm["nodes"][a]["uv"].as_array().unwrap();
        let want = format!(
            "probe{p}_x[node={a};u={};v={}]",
            uv[0].as_f64().unwrap(),
            uv[1].as_f64().unwrap()
        );
        assert_eq!(header[1 + 3 * p], want);
    }
}

/// reduction.json is not an MSM: `simulate` and `export` refuse it saying what it is and what
/// to run instead (they used to fail on "unknown field `kind`"); derive's result line names
/// the reduction and its mass, with no empty constants list.
#[test]
fn a_reduction_is_refused_by_simulate_and_export_with_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let o = bin()
        .arg("derive")
        .arg(paper())
        .args(["--derivation", "reduction", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    let line = String::from_utf8_lossy(&o.stdout);
    assert!(line.starts_with("exact reduction onto"), "{line}");
    assert!(!line.contains(": ,"), "{line}");
    let file = out.join("reduction.json");
    for args in [
        vec!["simulate", "--model", "msm", "--out"],
        vec!["export", "--format", "npz", "--out"],
    ] {
        let o = bin()
            .arg(args[0])
            .arg(&file)
            .args(&args[1..])
            .arg(dir.path().join("x"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("not a mass-spring model") && err.contains("DIR/msm.json"),
            "{err}"
        );
    }
}
