//! The derivations on scenes (docs/math.md §8, docs/derivations.md): flat sheets clamped by two
//! rings or one ring of control points, a sheet under gravity, a curved rational shell, a
//! membrane strip, a wide sheet under gravity, a graded membrane strip, a rational bending-only
//! bump, an anisotropic membrane under a point load (`data/derivations`, made by
//! `make_scenes.py`), the paper's sheet, a string, and a refinement series of one sheet on
//! 7² … 33² control nets. Each bound sits above the measured value (docs/derivations.md) so
//! that a change that makes a model worse fails; none was chosen to make a number pass.

use std::f64::consts::PI;
use std::path::Path;

use nurbspring_derive::{Derivation, Method, ReferenceKind};
use nurbspring_dnurbs::DnurbsModel;
use nurbspring_scene::Scene;
use nurbspring_sim::{IntegratorKind, RunOptions, Sample};

#[path = "support/sheet.rs"]
mod support;
use support::sheet_text;

fn scene(name: &str) -> Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = if name == "paper" || name == "string" {
        root.join("../../examples").join(format!("{name}.toml"))
    } else {
        root.join("tests/data/derivations")
            .join(format!("{name}.toml"))
    };
    Scene::from_path(path).unwrap()
}

fn derive(s: &Scene, method: Method) -> Derivation {
    let config = s.derivation_config(Some(method)).unwrap();
    nurbspring_derive::derive(&config, None, &mut |_, _| {})
        .unwrap()
        .0
}

/// The lowest frequency is matched by the calibration, to the eigensolver's accuracy.
const CALIBRATED: f64 = 1e-9;
/// The reduction on a Greville lattice reproduces the D-NURBS at the nodes: round-off of the
/// node-space matrices (measured ≤ 3e-13).
const REDUCTION: f64 = 1e-8;

/// `(scene, bound on the central node's relative RMS, bound under the second excitation)`;
/// measured values in docs/derivations.md.
const MODAL: [(&str, f64, f64); 10] = [
    ("paper", 0.04, 0.16),
    ("two_rings", 0.065, 0.15),
    ("one_ring", 0.05, 0.07),
    ("gravity", 0.01, 0.09),
    ("shell", 0.055, 0.165),
    ("strip", 0.005, 0.08),
    ("wide_gravity", 0.006, 0.06),
    ("graded_membrane", 0.017, 0.115),
    ("rational_bump", 0.01, 0.042),
    ("aniso_point_load", 0.053, 0.085),
];

#[test]
fn modal_derivation_follows_the_dnurbs() {
    for (name, bound, second) in MODAL {
        let d = derive(&scene(name), Method::Modal);
        let v = &d.derived.validation;
        assert_eq!(v.reference, ReferenceKind::Modal, "{name}");
        assert!(v.relative_rms <= bound, "{name}: {}", v.relative_rms);
        assert!(
            d.second_excitation.relative_rms <= second,
            "{name}: {}",
            d.second_excitation.relative_rms
        );
        let first = &d.frequencies[0];
        assert!(
            first.relative_difference.abs() <= CALIBRATED,
            "{name}: {first:?}"
        );
        assert!(first.mac.unwrap() > 0.99, "{name}: {first:?}");
        // The horizon covers five periods of the lowest mode, or the scene's t_end.
        assert!(v.horizon >= 5.0 * 2.0 * PI / first.dnurbs - 1e-9, "{name}");
        // A linear model: no spring, every free node with a positive mass.
        let l = d.lattice().unwrap();
        assert!(l.springs.is_empty() && !l.elements.is_empty());
        // The totals add up.
        let total: f64 = l.masses.iter().sum();
        assert!((d.mass.total_msm - total).abs() <= 1e-12 * total);
    }
}

/// A sheet of this file's own (not the `derive` benchmark's) on an `n × n` bicubic net at the
/// Greville abscissae of uniform clamped knots: 1.2 × 1, anisotropic membrane and bending
/// terms with twist, two rings fixed, struck obliquely, Δt = 0.01 over 20 s.
fn refinement_text(n: usize) -> String {
    let inner = n - 4;
    let mut knots = vec![0.0; 4];
    knots.extend((1..=inner).map(|i| i as f64 / (inner + 1) as f64));
    knots.extend([1.0; 4]);
    let greville: Vec<f64> = (0..n)
        .map(|i| knots[i + 1..i + 4].iter().sum::<f64>() / 3.0)
        .collect();
    let rows: Vec<String> = greville
        .iter()
        .map(|x| {
            let row: Vec<String> = greville
                .iter()
                .map(|y| format!("[{:?}, {y:?}, 0.0]", 1.2 * x))
                .collect();
            format!("[{}]", row.join(", "))
        })
        .collect();
    format!(
        "[surface]\ndegree_u = 3\ndegree_v = 3\nknots_u = {knots:?}\nknots_v = {knots:?}\n\
         control_points = [{}]\n[material]\nmu = 1.5\nalpha11 = 1.0\nalpha22 = 0.6\n\
         beta11 = 0.02\nbeta22 = 0.02\nbeta12 = 0.01\n[constraints]\nfixed_rings = 2\n\
         [initial]\nvelocity = [0.05, 0.0, -0.15]\n[simulation]\ndt = 0.01\nt_end = 20.0\n",
        rows.join(",\n")
    )
}

/// `(n, bound on the central node's relative RMS, bound under the second excitation)` of the
/// refinement series; measured values in docs/derivations.md.
const SERIES: [(usize, f64, f64); 6] = [
    (7, 0.036, 0.13),
    (9, 0.017, 0.058),
    (13, 0.024, 0.043),
    (17, 0.026, 0.055),
    (25, 0.021, 0.038),
    (33, 0.008, 0.047),
];

/// The default derivation on one sheet refined from 7² to 33² control points: each figure
/// within its bound, the lowest frequency exact, and the finest net no worse than 17².
#[test]
fn the_modal_derivation_keeps_up_with_refinement() {
    let mut own = Vec::new();
    for (n, bound, second) in SERIES {
        let s = Scene::from_str(&refinement_text(n), "refinement.toml").unwrap();
        let d = derive(&s, Method::Modal);
        let v = &d.derived.validation;
        assert!(v.relative_rms <= bound, "{n}²: {}", v.relative_rms);
        assert!(
            d.second_excitation.relative_rms <= second,
            "{n}²: {}",
            d.second_excitation.relative_rms
        );
        assert!(
            d.frequencies[0].relative_difference.abs() <= CALIBRATED,
            "{n}²: {:?}",
            d.frequencies[0]
        );
        // A small motion: inside the linear range, no warning about it.
        assert!(d.regime.motion < d.regime.amplitude, "{n}²: {:?}", d.regime);
        assert!(d.regime.modes >= 9, "{n}²: {:?}", d.regime);
        own.push(v.relative_rms);
    }
    assert!(own[5] <= own[3], "33²: {} against 17²: {}", own[5], own[3]);
}

/// A wide sheet sagging under gravity to 45% of its size: both linear models agree (the
/// figure above), and the verdict and a warning say that the motion is outside the range
/// either describes.
#[test]
fn a_motion_beyond_the_linear_range_is_flagged() {
    let d = derive(&scene("wide_gravity"), Method::Modal);
    let r = &d.regime;
    assert!(r.motion > 4.0 * r.amplitude, "{r:?}");
    assert!(
        d.warnings
            .iter()
            .any(|w| w.contains("outside") || w.contains("linear range")),
        "{:?}",
        d.warnings
    );
}

#[test]
fn reduction_reproduces_the_dnurbs_on_a_greville_lattice() {
    for name in ["paper", "two_rings", "gravity", "shell", "string"] {
        let d = derive(&scene(name), Method::Reduction);
        assert!(
            d.derived.validation.relative_rms <= REDUCTION,
            "{name}: {}",
            d.derived.validation.relative_rms
        );
        assert!(d.second_excitation.relative_rms <= REDUCTION, "{name}");
        let r = d.reduction().unwrap();
        assert!(!r.guyan);
        for f in &d.frequencies {
            assert!(f.relative_difference.abs() <= 1e-9, "{name}: {f:?}");
        }
    }
}

/// A string of unit parameter length: `ω_n = nπ √(α/μ)` (here α = μ); the D-NURBS converges to
/// it, the MSM matches the lowest exactly and the next within its stencil error.
#[test]
fn string_frequencies() {
    let d = derive(&scene("string"), Method::Modal);
    let f = &d.frequencies;
    assert!((f[0].dnurbs - PI).abs() <= 1e-4 * PI, "{}", f[0].dnurbs);
    assert!(
        (f[1].dnurbs - 2.0 * PI).abs() <= 1e-3 * PI,
        "{}",
        f[1].dnurbs
    );
    assert!((f[0].msm - PI).abs() <= 1e-4 * PI);
    assert!((f[1].msm / (2.0 * PI) - 1.0).abs() <= 0.03, "{}", f[1].msm);
    assert!(
        d.derived.validation.relative_rms <= 0.01,
        "{}",
        d.derived.validation.relative_rms
    );
    let l = d.lattice().unwrap();
    assert_eq!(l.grid, Some((12, 1)));
}

/// A damped sheet: node damping is `(γ/μ) m_n`, both models run by Newmark, and the scalar
/// reference equals the full D-NURBS model's own Newmark run.
#[test]
fn damping_follows_the_dnurbs() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/derivations/two_rings.toml"),
    )
    .unwrap()
    .replace("mu = 2.0", "mu = 2.0\ngamma = 0.4");
    let s = Scene::from_str(&text, "damped.toml").unwrap();
    let d = derive(&s, Method::Modal);
    let l = d.lattice().unwrap();
    for (m, c) in l.masses.iter().zip(&l.damping) {
        assert!((c - 0.2 * m).abs() <= 1e-15 * m, "{c} vs {m}");
    }
    assert_eq!(d.derived.validation.reference, ReferenceKind::Newmark);
    assert!(
        d.derived.validation.relative_rms <= 0.12,
        "{}",
        d.derived.validation.relative_rms
    );
    // The scalar Newmark reference against the model's own Newmark run at the central probe.
    let model: DnurbsModel = s.build_dnurbs().unwrap();
    let (u, v) = d.probes[0];
    let v_dt = d.derived.validation.dt;
    let opts = RunOptions::new(v_dt, 1.0, IntegratorKind::Newmark);
    let mut points = Vec::new();
    let initial = s.initial_conditions().state(&model);
    let mut observe = |smp: &Sample<'_>| {
        points.push(model.point(u, v, &model.full_coordinates(smp.q)).unwrap());
    };
    model.simulate(initial, &opts, &mut observe).unwrap();
    for (a, b) in points.iter().zip(&d.dnurbs_trajectory.probes[0]) {
        for x in 0..3 {
            assert!((a[x] - b[x]).abs() <= 1e-10, "{a:?} vs {b:?}");
        }
    }
}

/// Every derivation carries the material's damping γ: the lattices' nodes `γ/μ` times their
/// mass (the D-NURBS's `D = (γ/μ) M`), the reduction its ratio; a scene's own `msm.damping`
/// is kept as given (the paper's derivation used to write node damping 0 for a damped cloth).
#[test]
fn every_derivation_carries_the_material_damping() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/derivations/two_rings.toml"),
    )
    .unwrap()
    .replace("mu = 2.0", "mu = 2.0\ngamma = 0.4");
    let text = text.replace("t_end = 20.0", "t_end = 1.0");
    let s = Scene::from_str(&text, "damped.toml").unwrap();
    // Every derivation of the tension plate (the shell's, springs, has its own tests).
    for method in Method::ALL.into_iter().filter(|m| m.takes(false)) {
        let d = derive(&s, method);
        match (d.lattice(), d.reduction()) {
            (Some(l), _) => {
                for (a, (m, c)) in l.masses.iter().zip(&l.damping).enumerate() {
                    assert!(
                        (c - 0.2 * m).abs() <= 1e-14 * m,
                        "{}: node {a}: damping {c} for mass {m}",
                        method.name()
                    );
                }
                assert!(l.damping.iter().any(|&c| c > 0.0), "{}", method.name());
            }
            (None, Some(r)) => assert_eq!(r.damping_ratio, 0.2),
            (None, None) => panic!("{}: no model", method.name()),
        }
    }
    // The scene's own msm.damping is the lattice's (examples/sheet_gravity.toml keeps 0.01).
    let given = Scene::from_str(&format!("{text}\n[msm]\ndamping = 0.05\n"), "given.toml").unwrap();
    let d = derive(&given, Method::Paper);
    assert!(d.lattice().unwrap().damping.iter().all(|&c| c == 0.05));
}

/// The paper's derivation keeps its constants; its validation is 3-D at the node's own point
/// and its warnings say what is wrong.
#[test]
fn paper_derivation_is_flagged() {
    let d = derive(&scene("paper"), Method::Paper);
    let fit = d.paper_fit().unwrap();
    assert!(
        (fit.selected.constants.value(nurbspring_msm::Class::Spring(
            nurbspring_msm::SpringKind::Structural
        )) - 0.387452)
            .abs()
            < 1e-5
    );
    assert!(
        d.warnings.iter().any(|w| w.contains("relative RMS")),
        "{:?}",
        d.warnings
    );
    assert!(
        d.warnings.iter().any(|w| w.contains("mass")),
        "{:?}",
        d.warnings
    );
    assert!(d.mass.free_msm < 0.01 * d.mass.free_dnurbs);
}

/// Bad input for the derivations: named keys.
#[test]
fn derivation_refusals_name_the_key() {
    let s = scene("string");
    // Excitation without any excitation.
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/derivations/two_rings.toml"),
    )
    .unwrap()
    .replace("velocity = [0, 0, -0.1]", "velocity = [0, 0, 0]");
    let quiet = Scene::from_str(&text, "quiet.toml").unwrap();
    let Err(e) = quiet.derive(
        quiet.choose_derivation(Some((Method::Excitation, "derivation"))),
        None,
        &mut |_, _| {},
    ) else {
        panic!("an excitation fit without excitation must be refused")
    };
    assert!(e.to_string().contains("initial.velocity"), "{e}");
    // A reduction onto more nodes than control points.
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/derivations/two_rings.toml"),
    )
    .unwrap()
    .replace(
        "[initial]",
        "[msm]\ngrid = \"uniform\"\nnodes_u = 15\nnodes_v = 12\n[initial]",
    );
    let fine = Scene::from_str(&text, "fine.toml").unwrap();
    let Err(e) = fine.derive(
        fine.choose_derivation(Some((Method::Reduction, "derivation"))),
        None,
        &mut |_, _| {},
    ) else {
        panic!("a reduction onto more nodes than control points must be refused")
    };
    assert!(
        e.to_string().contains("msm.grid") && e.to_string().contains("greville"),
        "{e}"
    );
    // Surface-only elements on a curve.
    let text =
        std::fs::read_to_string(s.path.clone()).unwrap() + "\n[msm]\nelements = [\"twist\"]\n";
    let e = Scene::from_str(&text, "twisted.toml").unwrap_err();
    assert!(e.to_string().contains("msm.elements"), "{e}");
}

/// A shell scene takes `springs`, `modal`, `excitation` or `reduction` in `fit.derivation`;
/// the paper's is refused naming the key and the derivations it takes.
#[test]
fn a_shell_scene_takes_every_derivation_but_the_papers() {
    let cloth = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cloth_corners.toml"),
    )
    .unwrap();
    let with = |name: &str| format!("{cloth}\n[fit]\nderivation = \"{name}\"\n");
    for method in [
        Method::Springs,
        Method::Modal,
        Method::Excitation,
        Method::Reduction,
    ] {
        let s = Scene::from_str(&with(method.name()), "cloth.toml").unwrap();
        assert_eq!(s.derivation().0, method);
        assert!(s.derives_from_shell(&s.choose_derivation(None)));
    }
    let e = Scene::from_str(&with(Method::Paper.name()), "cloth.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("fit.derivation")
            && e.contains("\"modal\", \"excitation\", \"reduction\" or \"springs\""),
        "{e}"
    );
}

/// A scene the linear derivations cannot take falls back to the paper's unless one is named.
#[test]
fn linear_constraints_fall_back_to_the_paper() {
    let text = std::fs::read_to_string(scene("paper").path.clone()).unwrap().replacen(
        "[constraints]",
        "[[constraints.linear]]\nterms = [{ point = [3, 2], component = \"x\", coefficient = 1.0 }, { point = [3, 3], component = \"x\", coefficient = -1.0 }]\n[constraints]",
        1,
    );
    let s = Scene::from_str(&text, "linear.toml").unwrap();
    let (method, why) = s.derivation();
    assert_eq!(method, Method::Paper);
    assert!(why.unwrap().contains("constraints.linear"));
    let named = Scene::from_str(
        &text.replacen("[fit]", "[fit]\nderivation = \"modal\"", 1),
        "named.toml",
    )
    .unwrap();
    assert_eq!(named.derivation(), (Method::Modal, None));
    let Err(e) = named.derive(named.choose_derivation(None), None, &mut |_, _| {}) else {
        panic!("the modal derivation cannot take linear constraints")
    };
    assert!(e.to_string().contains("constraints.linear"), "{e}");
    assert_eq!(scene("paper").derivation(), (Method::Modal, None));
}

/// The sheet of the `derive` benchmark (`support/sheet.rs`) with Δt = 0.05.
fn sheet(n: usize) -> Scene {
    Scene::from_str(&sheet_text(n, 0.05), "sheet.toml").unwrap()
}

/// Above `DENSE_MODES` unknowns both models are followed through their lowest
/// `TRUNCATED_MODES` modes, and say so; the truncated D-NURBS reference against the exact one
/// (every mode, dense, computed here) at the central node: the difference is below the share
/// of the motion left out.
#[test]
fn a_large_net_is_validated_on_its_lowest_modes() {
    use nurbspring_derive::{DENSE_MODES, DnurbsModes, Judge, ModalBasis, Setup, TRUNCATED_MODES};
    let s = sheet(49);
    let d = derive(&s, Method::Modal);
    let v = &d.derived.validation;
    assert_eq!(v.reference, ReferenceKind::TruncatedModal);
    assert_eq!(v.integrator, "truncated-modal");
    let (dn, msm) = (
        v.dnurbs_truncation.clone().unwrap(),
        v.msm_truncation.clone().unwrap(),
    );
    assert_eq!((dn.modes, dn.unknowns), (TRUNCATED_MODES, 45 * 45));
    assert!(dn.unknowns > DENSE_MODES && msm.unknowns > DENSE_MODES);
    let left_out = dn.left_out.unwrap();
    assert!(left_out > 0.0 && left_out < 0.005, "{left_out}");
    assert!(d.second_excitation.dnurbs_truncation.is_some());
    // The exact reference, every mode.
    let config = s.derivation_config(Some(Method::Modal)).unwrap();
    let setup = Setup::new(&config).unwrap();
    let truncated = DnurbsModes::new(&setup, "test").unwrap();
    let exact = DnurbsModes {
        basis: ModalBasis::all(&truncated.system.stiffness, &truncated.system.mass).unwrap(),
        system: truncated.system.clone(),
    };
    let (a, kind_a) = Judge::new(&setup, &config, Some(truncated))
        .unwrap()
        .reference()
        .unwrap();
    let (b, kind_b) = Judge::new(&setup, &config, Some(exact))
        .unwrap()
        .reference()
        .unwrap();
    assert_eq!(
        (kind_a, kind_b),
        (ReferenceKind::TruncatedModal, ReferenceKind::Modal)
    );
    let c = nurbspring_derive::compare_points(&b.t, &b.probes[0], &a.probes[0]);
    // Measured: 2.1e-3 at the central node, 3.2e-3 left out.
    assert!(
        c.relative_rms <= left_out,
        "{} vs {left_out}",
        c.relative_rms
    );
}

/// The memory estimate of `derive` on a large net counts the Lanczos bases of the truncated
/// modal runs, not dense eigenproblems, for the modal derivation (129 × 129 net: measured peak
/// 0.51 GB); the reduction keeps its dense matrices.
#[test]
fn the_memory_estimate_of_a_large_net_counts_lanczos_bases() {
    use nurbspring_scene::resources::Job;
    let s = sheet(129);
    let parts = |method| -> Vec<&'static str> {
        s.estimate(Job::Derive(method))
            .memory_parts
            .iter()
            .map(|p| p.what)
            .collect()
    };
    let modal = parts(Method::Modal);
    assert!(
        modal.contains(&"Lanczos bases of the lowest modes"),
        "{modal:?}"
    );
    assert!(!modal.contains(&"dense eigenproblems"), "{modal:?}");
    let memory = s.estimate(Job::Derive(Method::Modal)).memory;
    assert!((510 << 20..4 << 30).contains(&memory), "{memory}");
    assert!(parts(Method::Reduction).contains(&"dense eigenproblems"));
    assert!(
        sheet(33)
            .estimate(Job::Derive(Method::Modal))
            .memory_parts
            .iter()
            .any(|p| p.what == "dense eigenproblems")
    );
}
