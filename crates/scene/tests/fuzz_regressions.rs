//! Inputs the fuzz targets found (`fuzz/`, docs/reliability.md), kept as tests of the main
//! suite: each must now finish with a result or a clean error.

use std::path::Path;

use nurbspring_dnurbs::AUTO_SPAN;
use nurbspring_scene::Scene;
use nurbspring_scene::run::steady_state;

fn scene(name: &str) -> Scene {
    Scene::from_path(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz")
            .join(name),
    )
    .unwrap()
}

/// A libFuzzer timeout: weights as unknowns on a bilinear patch with one weight of 0.078. The
/// automatic quadrature rule is searched within AUTO_SPAN rules of the start, and the nonlinear
/// steady state ends (here: a free-floating sheet, so an error naming why).
#[test]
fn quadrature_search_on_a_skewed_rational_patch_is_bounded() {
    let s = scene("quadrature_timeout.toml");
    let model = s.build_dnurbs().unwrap();
    let q = model.quadrature();
    assert!(q.automatic && !q.polynomial, "{q:?}");
    // Degree 1, weights as unknowns: the search starts at 3 points.
    assert!(q.points <= 3 + AUTO_SPAN, "{q:?}");
    match steady_state(&s, &Default::default(), &mut |_| {}) {
        Ok(st) => assert!(st.p.iter().all(|x| x.is_finite())),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}
