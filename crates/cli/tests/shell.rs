//! The Kirchhoff–Love examples run end to end through the binary and reproduce their
//! benchmarks (docs/shell.md): the Scordelis–Lo roof, Sze's cantilever under end shear at every
//! tabulated load level, and the cloth held at two corners falling under gravity.

mod support;
use support::{bin, example, json_of, null_in, stderr_of};

/// `steady --linear` of the quarter roof: the free edge's midpoint sinks by 0.3006 (the
/// Kirchhoff–Love value; degree 4 on 16² spans gives 0.300592, Kratos' Shell3pElement
/// 0.30059), within 1 %.
#[test]
fn scordelis_lo_example_sinks_by_the_reference() {
    let out = bin()
        .arg("steady")
        .arg(example("scordelis_lo.toml"))
        .arg("--linear")
        .assert()
        .success();
    let v = json_of(&out.get_output().stdout);
    let probe = &v["probes"][1];
    assert_eq!(
        (probe["u"].as_f64(), probe["v"].as_f64()),
        (Some(1.0), Some(0.0))
    );
    let w = -probe["displacement"][2].as_f64().unwrap();
    assert!((w - 0.3006).abs() < 0.01 * 0.3006, "{w}");
}

/// `steady --load-steps 20` of the cantilever: load_path.csv holds the tip's displacements at
/// every level of Sze's table, each within 1 % of the tabulated w (and of −u, relative to w).
#[test]
fn cantilever_example_follows_the_sze_table() {
    // P/P_max, −u_tip, w_tip (Sze, Liu, Lo 2004, Table 1).
    let table = [
        (0.05, 0.026, 0.663),
        (0.10, 0.103, 1.309),
        (0.20, 0.381, 2.493),
        (0.30, 0.763, 3.488),
        (0.40, 1.184, 4.292),
        (0.50, 1.604, 4.933),
        (0.60, 2.002, 5.444),
        (0.70, 2.370, 5.855),
        (0.80, 2.705, 6.190),
        (0.90, 3.010, 6.467),
        (1.00, 3.286, 6.698),
    ];
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("strip");
    bin()
        .arg("steady")
        .arg(example("cantilever_strip.toml"))
        .args(["--load-steps", "20", "--out"])
        .arg(&out_dir)
        .assert()
        .success();
    let text = std::fs::read_to_string(out_dir.join("load_path.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    // Probe 1 is the tip (the scene's probe); its columns name (u, v).
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (cu, cw) = (col("probe1_dx[u=1;v=0.5]"), col("probe1_dz[u=1;v=0.5]"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 20);
    for (load, u, w) in table {
        let row = rows.iter().find(|r| (r[0] - load).abs() < 1e-12).unwrap();
        let (du, dw) = (-row[cu], row[cw]);
        assert!((dw - w).abs() < 0.01 * w, "P/Pmax {load}: w {dw} vs {w}");
        assert!((du - u).abs() < 0.01 * w, "P/Pmax {load}: -u {du} vs {u}");
    }
}

/// `simulate --model dnurbs` of the cloth: it falls and swings (the free corner drops by more
/// than a tenth of its size within 0.5 s) and its energy never grows: the total (kinetic +
/// elastic + load potential) stays at or below its start, up to Newton's tolerance, as the
/// material damping only removes energy.
#[test]
fn cloth_example_falls_without_gaining_energy() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cloth");
    let run = bin()
        .arg("simulate")
        .arg(example("cloth_corners.toml"))
        .args(["--model", "dnurbs", "--t-end", "0.3", "--out"])
        .arg(&out)
        .assert()
        .success();
    assert!(
        !stderr_of(&run).contains("gains energy"),
        "{}",
        stderr_of(&run)
    );
    let energy = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    let rows: Vec<Vec<f64>> = energy
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let drop = rows.iter().map(|r| r[3]).fold(0.0_f64, f64::min).abs();
    for r in &rows {
        assert!(
            r[4] <= 1e-3 * drop,
            "t = {}: total energy {} (load potential drop {drop})",
            r[0],
            r[4]
        );
    }
    let traj = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let last: Vec<f64> = traj
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let first: Vec<f64> = traj
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    // Columns: t, probe0 x y z, probe1 (0.5, 1) x y z, probe2 (1, 1) x y z.
    assert!(
        first[9] - last[9] > 0.05,
        "the free corner fell by {}",
        first[9] - last[9]
    );
}

/// A run whose energy rises more than its dynamics can make it is flagged: the cloth with
/// generalized-α at ρ∞ = 0.8 gains energy from about 1 s on (docs/math.md §11.2).
#[test]
fn a_run_that_gains_energy_is_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example("cloth_corners.toml"))
        .unwrap()
        .replace("rho_infinity = 0.5", "rho_infinity = 0.8");
    let scene = dir.path().join("cloth.toml");
    std::fs::write(&scene, text).unwrap();
    let run = bin()
        .arg("simulate")
        .arg(&scene)
        .args(["--model", "dnurbs", "--t-end", "1.1", "--out"])
        .arg(dir.path().join("run"))
        .assert()
        .success();
    let err = stderr_of(&run);
    assert!(
        err.contains("gains energy") && err.contains("rho_infinity"),
        "{err}"
    );
}

/// `derive` of the cloth derives rest-length springs and hinges (the default for a shell):
/// msm.json carries them and `simulate msm.json` runs it; report.md opens with the verdict and
/// the lowest elastic frequency is the shell's.
#[test]
fn cloth_derives_springs_and_hinges_that_simulate() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    bin()
        .arg("derive")
        .arg(example("cloth_corners.toml"))
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let text = std::fs::read_to_string(out.join("report.json")).unwrap();
    let report: serde_json::Value = serde_json::from_str(&text).unwrap();
    // The cloth's load path stops at once: what it lacks is left out, never written as null.
    assert_eq!(null_in(&report, "report"), None);
    assert_eq!(report["derivation"], "springs");
    assert!(report["large_motion"]["static_failure"].is_string());
    // The dynamic run's shell is a reference: its energy does not rise.
    let dynamic = &report["large_motion"]["dynamic"];
    assert_eq!(dynamic["rho_infinity"], 0.5);
    assert!(
        dynamic["shell_energy_gain"].as_f64().unwrap() <= 0.1,
        "{dynamic}"
    );
    let first = report["frequencies"][0]["relative_error"].as_f64().unwrap();
    assert!(first.abs() < 1e-9, "{first}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.lines().nth(2).unwrap().starts_with("**Verdict.**"),
        "{md}"
    );
    let msm: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("msm.json")).unwrap()).unwrap();
    assert_eq!(
        msm["hinges"].as_array().unwrap().len() as u64,
        report["hinges"].as_u64().unwrap()
    );
    bin()
        .arg("simulate")
        .arg(out.join("msm.json"))
        .arg("--model")
        .arg("msm")
        .arg("--t-end")
        .arg("0.05")
        .arg("--out")
        .arg(dir.path().join("run"))
        .assert()
        .success();
}

/// `derive --derivation modal` (and `excitation`) of a shell makes the same springs and hinges
/// with one scale per class and band, reported as groups (and the excited modes it fitted); a
/// derivation of the tension plate is refused naming the option.
#[test]
fn a_shell_derives_modal_springs_and_refuses_the_paper() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["modal", "excitation"] {
        let out = dir.path().join(name);
        bin()
            .arg("derive")
            .arg(example("cloth_corners.toml"))
            .arg("--derivation")
            .arg(name)
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                .unwrap();
        assert_eq!(null_in(&report, "report"), None);
        assert_eq!(report["derivation"], name);
        let groups = report["groups"].as_array().unwrap();
        let grouped: u64 = groups.iter().map(|g| g["elements"].as_u64().unwrap()).sum();
        assert_eq!(
            grouped,
            report["springs"].as_u64().unwrap() + report["hinges"].as_u64().unwrap()
        );
        let first = report["frequencies"][0]["relative_error"].as_f64().unwrap();
        assert!(first.abs() < 1e-9, "{first}");
        let md = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(md.contains(&format!("(derivation `{name}`)")), "{md}");
        // The cloth's gravity moves its elastic modes: the excitation derivation lists them.
        assert_eq!(
            report["excited_modes"]
                .as_array()
                .is_some_and(|m| !m.is_empty()),
            name == "excitation",
            "{report}"
        );
    }
    let refused = bin()
        .arg("derive")
        .arg(example("cloth_corners.toml"))
        .arg("--derivation")
        .arg("paper")
        .arg("--out")
        .arg(dir.path().join("p"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&refused.get_output().stderr).to_string();
    assert!(
        err.contains("--derivation")
            && err.contains("\"modal\", \"excitation\", \"reduction\" or \"springs\""),
        "{err}"
    );
    assert!(!dir.path().join("p").exists());
}

/// `derive --derivation reduction` of a shell writes the exact reduction of the shell
/// linearized at rest onto the nodes' x, y and z: reduction.json with square, symmetric
/// `3n × 3n` matrices, a report whose modes are the shell's, and no msm.json (`simulate`
/// refuses the file, naming what it is).
#[test]
fn a_shell_reduces_onto_the_nodes_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    bin()
        .arg("derive")
        .arg(example("cantilever_strip.toml"))
        .arg("--derivation")
        .arg("reduction")
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(null_in(&report, "report"), None);
    assert_eq!(report["derivation"], "reduction");
    assert_eq!(report["kind"], "exact");
    for f in report["frequencies"].as_array().unwrap() {
        assert!(f["relative_error"].as_f64().unwrap().abs() < 1e-9, "{f}");
    }
    assert!(report["small_motion"]["relative_rms"].as_f64().unwrap() < 1e-8);
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("reduction.json")).unwrap())
            .unwrap();
    assert!(file["ordering"].as_str().unwrap().contains("interleaved"));
    let n = 3 * file["free"].as_array().unwrap().len();
    let k = file["stiffness"].as_array().unwrap();
    assert_eq!(k.len(), n);
    assert!(k.iter().all(|row| row.as_array().unwrap().len() == n));
    assert_eq!(file["loads"].as_array().unwrap().len(), n / 3);
    assert!(!out.join("msm.json").exists());
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.lines().nth(2).unwrap().starts_with("**Verdict.**"),
        "{md}"
    );
    bin()
        .arg("simulate")
        .arg(out.join("reduction.json"))
        .arg("--out")
        .arg(dir.path().join("s"))
        .assert()
        .code(2);
}

/// What the spring lattice cannot carry is refused with the key: the quarter roof's symmetry
/// edges (a lattice node is fixed whole), and the spring derivation of a tension plate.
#[test]
fn springs_refuse_symmetry_and_the_tension_plate() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .arg("derive")
        .arg(example("scordelis_lo.toml"))
        .arg("--out")
        .arg(dir.path().join("a"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        err.contains("constraints") && err.contains("symmetry"),
        "{err}"
    );
    assert!(!dir.path().join("a").exists());
    let out = bin()
        .arg("derive")
        .arg(example("sheet_gravity.toml"))
        .arg("--derivation")
        .arg("springs")
        .arg("--out")
        .arg(dir.path().join("b"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        err.contains("material.model") && err.contains("kirchhoff-love"),
        "{err}"
    );
}
