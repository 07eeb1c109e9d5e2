//! End-to-end tests of the binary: every example scene, every command, and bad input
//! (`simulate` in tests/simulate.rs, values checked against mechanics in tests/values.rs).

use std::path::{Path, PathBuf};

mod support;
use support::{bin, examples, json_of, null_in, paper, scene};

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
