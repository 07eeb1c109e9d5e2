//! `check`'s run-time estimate of `derive` (scene::runtime): the paper's scan counts the
//! candidates the derivation will try, a pruned scan is estimated below a complete one, and an
//! estimate that leaves out the explicit substeps says it is a lower bound.

use std::path::PathBuf;

use nurbspring_derive::{Method, Setup, mass_eigenvalues};
use nurbspring_scene::Scene;

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// A flat bicubic `n × n` net with uniform knots, two rings held, struck by a velocity.
fn square_net(n: usize, extra: &str) -> Scene {
    let spans = n - 3;
    let mut knots = vec![0.0; 4];
    knots.extend((1..spans).map(|i| i as f64 / spans as f64));
    knots.extend([1.0; 4]);
    let g: Vec<f64> = (0..n)
        .map(|i| knots[i + 1..i + 4].iter().sum::<f64>() / 3.0)
        .collect();
    let rows: Vec<String> = g
        .iter()
        .map(|x| {
            let row: Vec<String> = g.iter().map(|y| format!("[{x}, {y}, 0.0]")).collect();
            format!("[{}]", row.join(", "))
        })
        .collect();
    let text = format!(
        "[surface]\ndegree_u = 3\ndegree_v = 3\nknots_u = {knots:?}\nknots_v = {knots:?}\n\
         control_points = [{}]\n[material]\nmu = 1.0\nalpha11 = 1.0\nalpha22 = 1.0\n\
         beta11 = 0.01\nbeta22 = 0.01\n[constraints]\nfixed_rings = 1\n\
         [initial]\nvelocity = [0.0, 0.0, -0.1]\n[simulation]\ndt = 0.01\nt_end = 2.0\n{extra}",
        rows.join(",\n")
    );
    Scene::from_str(&text, "square.toml").unwrap()
}

/// The term of the scan, if any.
fn scan_term(scene: &Scene) -> Option<String> {
    let e = scene.derive_runtime(Method::Paper);
    e.terms
        .into_iter()
        .map(|t| t.what)
        .find(|w| w.starts_with("the mass scan"))
}

/// The number in "the mass scan: N candidates".
fn candidates(scene: &Scene) -> usize {
    let d = scan_term(scene).expect("a scan");
    let at = d.find(" candidates").unwrap_or_else(|| panic!("{d}"));
    d[..at].rsplit(' ').next().unwrap().parse().unwrap()
}

/// The distinct non-null eigenvalues of the scene's D-NURBS mass matrix, as the scan finds them.
fn scanned(scene: &Scene) -> usize {
    let config = scene.derivation_config(Some(Method::Paper)).unwrap();
    let setup = Setup::new(&config).unwrap();
    mass_eigenvalues(&setup.model().matrices().mass)
        .unwrap()
        .len()
}

#[test]
fn the_paper_scan_is_estimated_with_the_candidates_it_will_try() {
    // The paper's scene (5 × 7 control points: every product of the two 1-D spectra distinct)
    // and square nets (S ⊗ S: n(n + 1)/2 distinct products).
    let paper = Scene::from_path(example("paper.toml")).unwrap();
    assert_eq!(candidates(&paper), scanned(&paper));
    for n in [6, 9] {
        let scene = square_net(n, "");
        assert_eq!(candidates(&scene), n * (n + 1) / 2);
        assert_eq!(candidates(&scene), scanned(&scene), "{n}");
    }
    // At most `fit.max_candidates`.
    assert_eq!(candidates(&square_net(9, "[fit]\nmax_candidates = 7\n")), 7);
}

#[test]
fn pruning_implicit_runs_and_explicit_substeps_are_stated() {
    // `extra` continues the [simulation] table.
    let scene = |simulation: &str, fit: &str| {
        let text = format!(
            "{simulation}[msm]\ngrid = \"uniform\"\nnodes_u = 17\nnodes_v = 17\nmass = 0.01\n{fit}"
        );
        square_net(9, &text)
    };
    let implicit = "msm_integrator = \"backward-euler\"\n";
    let pruned = scene(implicit, "").derive_runtime(Method::Paper);
    let complete =
        scene(implicit, "[fit]\nmass_scan = \"complete\"\n").derive_runtime(Method::Paper);
    assert!(!pruned.at_least && !complete.at_least);
    assert!(
        pruned.seconds < 0.5 * complete.seconds,
        "{pruned:?} {complete:?}"
    );
    assert!(
        complete.dominant.contains("every run whole"),
        "{complete:?}"
    );
    // An explicit MSM: its substeps are not known before the fit.
    let explicit = scene("", "").derive_runtime(Method::Paper);
    assert!(
        explicit.at_least && explicit.about.starts_with("at least"),
        "{explicit:?}"
    );
    // A fixed mass has no scan.
    let fixed = scene("", "[fit]\nmass = \"fixed\"\n").derive_runtime(Method::Paper);
    assert!(
        fixed.terms.iter().all(|t| !t.what.contains("mass scan")),
        "{fixed:?}"
    );
    // The estimate grows with the net: the modal derivation's dense modes by n³.
    let (small, large) = (
        square_net(9, "").derive_runtime(Method::Modal).seconds,
        square_net(18, "").derive_runtime(Method::Modal).seconds,
    );
    assert!(large > 4.0 * small, "{small} {large}");
}

/// A shell scene's spring models are estimated by their large-motion runs, its reduction by
/// its dense eigenproblems on the nodes' coordinates: seconds against a fraction of one.
#[test]
fn a_shell_reduction_is_estimated_apart_from_its_spring_models() {
    let strip = Scene::from_path(example("cantilever_strip.toml")).unwrap();
    let springs = strip.derive_runtime(Method::Springs);
    let modal = strip.derive_runtime(Method::Modal);
    let reduction = strip.derive_runtime(Method::Reduction);
    assert!(springs.dominant.contains("large-motion"), "{springs:?}");
    assert_eq!(modal.seconds, springs.seconds);
    assert!(reduction.dominant.contains("reduction"), "{reduction:?}");
    assert!(reduction.seconds < 0.01 * springs.seconds, "{reduction:?}");
}
