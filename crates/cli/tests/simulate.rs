//! `simulate` end to end: the D-NURBS and MSM runs, the explicit step limit (refused, forced,
//! substeps, the implicit fallback), and the files it writes.

use std::path::Path;

use assert_cmd::Command;

mod support;
use support::{bin, csv_rows, examples, json_of, paper, scene};

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
