//! The reliability contract end to end (docs/reliability.md): an output folder holds exactly one
//! complete run, whatever happened to the runs before it; odd paths, huge values and signals
//! give clean refusals, never a panic, a hang or a non-finite file.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

mod support;
use support::{bin, null_in, paper};

/// The paper's scene with `replace` applied to its text.
fn paper_with(dir: &Path, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(paper()).unwrap();
    assert!(text.contains(from), "{from}");
    let p = dir.join("scene.toml");
    std::fs::write(&p, text.replacen(from, to, 1)).unwrap();
    p
}

/// Sorted names in a folder.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    v.sort();
    v
}

/// Frame files of the series `pvd` in a folder (`surface.pvd`: `surface_*.vts`), and the frames
/// the `.pvd` lists.
fn frames(dir: &Path, pvd: &str) -> (usize, usize) {
    let stem = format!("{}_", pvd.trim_end_matches(".pvd"));
    let on_disk = names(dir)
        .iter()
        .filter(|n| n.starts_with(&stem) && (n.ends_with(".vts") || n.ends_with(".vtu")))
        .count();
    let listed = std::fs::read_to_string(dir.join(pvd))
        .unwrap()
        .matches("<DataSet")
        .count();
    (on_disk, listed)
}

fn simulate(scene: &Path, out: &Path, t_end: &str) -> assert_cmd::assert::Assert {
    bin()
        .arg("simulate")
        .arg(scene)
        .args([
            "--model", "dnurbs", "--dt", "0.01", "--t-end", t_end, "--out",
        ])
        .arg(out)
        .assert()
}

#[test]
fn a_shorter_rerun_leaves_no_stale_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    simulate(&paper(), &out, "0.5").success();
    let (disk, listed) = frames(&out, "surface.pvd");
    assert_eq!((disk, listed), (51, 51));
    simulate(&paper(), &out, "0.2").success();
    assert_eq!(frames(&out, "surface.pvd"), (21, 21));
    assert_eq!(frames(&out, "control_net.pvd"), (21, 21));
    // Nothing beside the folder: no staging or parked folders left.
    assert_eq!(names(dir.path()), ["run"]);
}

#[test]
fn a_failed_run_leaves_the_previous_run_intact() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    simulate(&paper(), &out, "0.3").success();
    let before: Vec<(String, Vec<u8>)> = names(&out)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect();
    // The MSM's explicit integrator far above its stability limit, forced: it diverges.
    let e = bin()
        .arg("simulate")
        .arg(paper())
        .args([
            "--model",
            "msm",
            "--integrator",
            "symplectic-euler",
            "--dt",
            "1.0",
            "--t-end",
            "400",
            "--force-unstable",
            "--out",
        ])
        .arg(&out)
        .assert()
        .code(1);
    let stderr = String::from_utf8_lossy(&e.get_output().stderr).to_string();
    assert!(stderr.contains("error"), "{stderr}");
    let after: Vec<(String, Vec<u8>)> = names(&out)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect();
    assert_eq!(before, after, "the failed run changed the folder");
    assert_eq!(names(dir.path()), ["run"]);
}

#[test]
fn a_folder_nurbspring_did_not_write_is_never_replaced() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("notes.txt"), "mine").unwrap();
    let out = bin()
        .arg("derive")
        .arg(paper())
        .arg("--out")
        .arg(dir.path())
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        stderr.contains("--out") && stderr.contains("notes.txt"),
        "{stderr}"
    );
    assert_eq!(names(dir.path()), ["notes.txt"]);
}

#[test]
fn leftovers_of_a_killed_run_are_removed_by_the_next() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    // What SIGKILL leaves: a staging folder of a process that no longer exists.
    let dead = dir.path().join(".run.staging-2147483632-0");
    std::fs::create_dir(&dead).unwrap();
    std::fs::write(dead.join("surface_000000.vts"), "partial").unwrap();
    simulate(&paper(), &out, "0.1").success();
    assert_eq!(names(dir.path()), ["run"]);
}

#[cfg(unix)]
#[test]
fn sigterm_and_sighup_stop_cleanly_and_keep_the_previous_run() {
    for signal in ["TERM", "HUP", "INT"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        simulate(&paper(), &out, "0.1").success();
        let before = std::fs::read(out.join("trajectory.csv")).unwrap();
        // A run long enough to be interrupted: small steps, few samples and frames.
        let long = paper_with(
            dir.path(),
            "save_every = 1",
            "save_every = 1000\n[output]\nvtk_every = 100",
        );
        let text =
            std::fs::read_to_string(&long)
                .unwrap()
                .replacen("[output]\nvtk_every = 1\n", "", 1);
        std::fs::write(&long, text).unwrap();
        let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("nurbspring"))
            .arg("--quiet")
            .arg("simulate")
            .arg(&long)
            .args([
                "--model", "dnurbs", "--dt", "0.0001", "--t-end", "1000", "--out",
            ])
            .arg(&out)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(700));
        let status = std::process::Command::new("kill")
            .arg(format!("-{signal}"))
            .arg(child.id().to_string())
            .status()
            .unwrap();
        assert!(status.success());
        let start = Instant::now();
        let code = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s.code();
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "SIG{signal}: still running"
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        assert_eq!(code, Some(130), "SIG{signal}");
        // One line on stderr, saying where the samples are; nothing "written" on stdout.
        let (mut stdout, mut stderr) = (String::new(), String::new());
        use std::io::Read;
        child
            .stdout
            .take()
            .unwrap()
            .read_to_string(&mut stdout)
            .unwrap();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut stderr)
            .unwrap();
        assert!(stdout.is_empty(), "SIG{signal}: {stdout}");
        assert_eq!(stderr.lines().count(), 1, "SIG{signal}: {stderr}");
        assert!(
            stderr.starts_with("error: interrupted: ") && stderr.contains("run.interrupted"),
            "SIG{signal}: {stderr}"
        );
        assert_eq!(
            std::fs::read(out.join("trajectory.csv")).unwrap(),
            before,
            "SIG{signal} changed the previous run"
        );
        let kept = dir.path().join("run.interrupted");
        assert!(
            kept.join("trajectory.csv").exists(),
            "SIG{signal}: {:?}",
            names(dir.path())
        );
        assert_eq!(names(dir.path()), ["run", "run.interrupted", "scene.toml"]);
    }
}

#[cfg(unix)]
#[test]
fn a_fifo_as_the_scene_is_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("scene.toml");
    let ok = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(ok.success());
    let out = bin()
        .arg("check")
        .arg(&fifo)
        .timeout(Duration::from_secs(20))
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(
        stderr.contains("scene.toml") && stderr.contains("regular file"),
        "{stderr}"
    );
}

#[test]
fn values_that_would_overflow_are_bad_input_naming_the_key() {
    for (from, to, key) in [
        ("alpha11 = 0.0", "alpha11 = 1e308", "alpha11"),
        ("beta11 = 0.01", "beta11 = 1e31", "beta11"),
        (
            "[0.0, 0.0, 2.0]",
            "[1e300, 0.0, 2.0]",
            "control_points[0][0][0]",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let scene = paper_with(dir.path(), from, to);
        for cmd in ["check", "derive", "matrices"] {
            let mut c = bin();
            c.arg(cmd).arg(&scene);
            if cmd != "check" {
                c.arg("--out").arg(dir.path().join("out"));
            }
            let out = c.assert().code(2);
            let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
            assert!(
                stderr.contains("scene.toml") && stderr.contains(key) && stderr.contains("1e30"),
                "{cmd} {to}: {stderr}"
            );
            assert!(!dir.path().join("out").exists());
        }
    }
}

#[test]
fn a_huge_lattice_mass_is_refused_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let scene = paper_with(dir.path(), "mass = 0.005", "mass = 1e308");
    for cmd in ["check", "stability"] {
        let out = bin().arg(cmd).arg(&scene).assert().code(2);
        let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
        assert!(stderr.contains("mass"), "{cmd}: {stderr}");
    }
}

/// A command that never looks at the cancel flag (here `check`, building and bounding a large
/// lattice) ends at once on SIGTERM, with the cancellation code.
#[cfg(unix)]
#[test]
fn sigterm_ends_a_non_cancellable_command_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let scene = paper_with(
        dir.path(),
        "structural = true",
        "grid = \"uniform\"\nnodes_u = 300\nnodes_v = 300\nstructural = true",
    );
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("nurbspring"))
        .arg("--quiet")
        .arg("check")
        .arg(&scene)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "check ended too soon");
    let sent = Instant::now();
    let ok = std::process::Command::new("kill")
        .arg("-TERM")
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(ok.success());
    let code = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        assert!(sent.elapsed() < Duration::from_secs(3), "still running");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert_eq!(code, Some(130));
    assert_eq!(names(dir.path()), ["scene.toml"]);
}

#[path = "../../scene/tests/support/sheet.rs"]
mod sheet;

/// `sh -c 'ulimit -v KIB && exec nurbspring ARGS'`: the command under an address-space limit.
fn under_address_limit(kib: u64, args: &[&str]) -> std::process::Output {
    let bin = assert_cmd::cargo::cargo_bin("nurbspring");
    let mut line = format!("ulimit -v {kib} && exec '{}' --quiet", bin.display());
    for a in args {
        line.push_str(&format!(" '{a}'"));
    }
    std::process::Command::new("sh")
        .args(["-c", &line])
        .output()
        .unwrap()
}

/// A hostile-input campaign found `check` and `derive` of a 400 × 400 net aborting (SIGABRT on
/// a failed allocation) under `ulimit -v 4194304`: the limits now respect RLIMIT_AS, so both
/// are refused up front (exit 2, naming the limit), and no staging folder is left behind.
#[test]
fn an_address_space_limit_refuses_what_would_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sheet400.toml");
    std::fs::write(&scene, sheet::sheet_text(400, 0.01)).unwrap();
    let scene = scene.to_str().unwrap().to_string();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap().to_string();
    for args in [
        vec!["check", scene.as_str()],
        vec!["derive", scene.as_str(), "--out", out.as_str()],
        vec!["modes", scene.as_str()],
    ] {
        let o = under_address_limit(4 << 20, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("ulimit -v"), "{args:?}: {err}");
    }
    assert_eq!(names(dir.path()), vec!["sheet400.toml".to_string()]);
    // --max-memory cannot lift the limit above the address space left.
    let o = under_address_limit(4 << 20, &["--max-memory", "100G", "check", &scene]);
    assert_eq!(o.status.code(), Some(2));
}

/// Every number of report.json of a hostile derivation is a number (JSON has no NaN: serde
/// writes null, so a missing number is left out), or the derivation is refused naming why.
fn assert_no_null(value: &serde_json::Value, path: &str) {
    if let Some(at) = null_in(value, path) {
        panic!("null at {at}");
    }
}

/// A curve whose end knot is 1 + 2⁻⁵², a degree-20 Bézier curve, probes at (1, 1) and at
/// subnormal parameters: each derivation finishes with numbers only (a probe whose models both
/// stay still has relative RMS 0; it was 0/0, written as null).
#[test]
fn hostile_derivations_report_numbers_or_refuse() {
    let dir = tempfile::tempdir().unwrap();
    let string = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/string.toml"),
    )
    .unwrap()
    .replace("t_end = 4.0", "t_end = 1.0");
    let end_knot = string.replace("1.0, 1.0, 1.0, 1.0]", "1.0, 1.0, 1.0, 1.0000000000000002]");
    assert_ne!(end_knot, string);
    let p = 20;
    let points: Vec<String> = (0..=p)
        .map(|i| format!("[{:?}, 0.0, 0.0]", 2.0 * i as f64 / p as f64))
        .collect();
    let velocities: Vec<String> = (0..=p)
        .map(|i| {
            format!(
                "[0.0, 0.0, {:?}]",
                if i == 0 || i == p { 0.0 } else { -0.1 }
            )
        })
        .collect();
    let bezier = format!(
        "[curve]\ndegree = {p}\nknots = {:?}\ncontrol_points = [{}]\n[material]\nmu = 0.5\n\
         alpha11 = 0.5\n[constraints]\nfixed_rings = 1\n[initial]\nvelocities = [{}]\n\
         [simulation]\ndt = 0.01\nt_end = 1.0\n",
        [vec![0.0; p + 1], vec![1.0; p + 1]].concat(),
        points.join(", "),
        velocities.join(", ")
    );
    let probes_at = |probes: &str| {
        std::fs::read_to_string(paper())
            .unwrap()
            .replace("t_end = 4.0", &format!("t_end = 0.8\nprobes = {probes}"))
    };
    for (k, (text, refused)) in [
        (end_knot, false),
        (bezier, false),
        // The paper's sheet is clamped by two rings: both probes sit on fixed nodes, where
        // both models stay still and agree exactly (relative RMS 0, not 0/0).
        (probes_at("[[1.0, 1.0]]"), false),
        (probes_at("[[0.5, 0.5], [5e-324, 5e-324]]"), false),
        (probes_at("[[0.5, 0.5], [0.4, 0.5]]"), false),
    ]
    .into_iter()
    .enumerate()
    {
        let scene = dir.path().join(format!("hostile{k}.toml"));
        std::fs::write(&scene, text).unwrap();
        let out = dir.path().join(format!("out{k}"));
        let o = bin()
            .arg("derive")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        if refused {
            assert_eq!(o.status.code(), Some(2), "{k}: {err}");
            assert!(
                err.contains("simulation.probes") && err.contains("fixed"),
                "{err}"
            );
            continue;
        }
        assert!(o.status.success(), "{k}: {err}");
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                .unwrap();
        assert_no_null(&report, &format!("hostile{k}"));
    }
}

/// 100 000 probes and 200 000 duplicate springs took over 20 s: both are refused at once, with
/// the limit or what to do.
#[test]
fn huge_probe_lists_and_duplicate_springs_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let probes: Vec<String> = (0..100_000)
        .map(|i| format!("[{:?}, 0.5]", 0.1 + 0.8 * i as f64 / 100_000.0))
        .collect();
    let scene = paper_with(
        dir.path(),
        "t_end = 4.0",
        &format!("t_end = 4.0\nprobes = [{}]", probes.join(", ")),
    );
    let start = Instant::now();
    let o = bin().arg("check").arg(&scene).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("simulation.probes") && err.contains("1000"),
        "{err}"
    );
    let mut springs = vec![r#"{"a": 0, "b": 1, "k": 1}"#; 100_000];
    springs.extend(vec![r#"{"a": 1, "b": 2, "k": 1}"#; 100_000]);
    let msm = dir.path().join("dup.json");
    std::fs::write(
        &msm,
        format!(
            r#"{{"nodes": [{{"position": [0, 0, 0], "mass": 1, "fixed": true}},
                {{"position": [1, 0, 0], "mass": 1}}, {{"position": [2, 0, 0], "mass": 1}}],
                "springs": [{}]}}"#,
            springs.join(", ")
        ),
    )
    .unwrap();
    let o = bin()
        .arg("simulate")
        .arg(&msm)
        .args(["--model", "msm", "--out"])
        .arg(dir.path().join("run"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("spring 1 joins nodes 0 and 1 like spring 0"),
        "{err}"
    );
    assert!(start.elapsed() < Duration::from_secs(20));
}
