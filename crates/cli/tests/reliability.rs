//! The reliability contract end to end (docs/reliability.md): an output folder holds exactly one
//! complete run, whatever happened to the runs before it; odd paths, huge values and signals
//! give clean refusals, never a panic, a hang or a non-finite file.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use assert_cmd::Command;

fn bin() -> Command {
    let mut c = Command::cargo_bin("nurbspring").unwrap();
    c.arg("--quiet");
    c
}

fn paper() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper.toml")
}

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
