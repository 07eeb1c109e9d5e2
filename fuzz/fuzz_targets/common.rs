//! The pipeline every fuzz input goes through: parse and validate the scene, build both models,
//! take a few steps of each with every integrator that applies, and set up the stiffness fit.
//! Errors are expected; panics, hangs and aborts are findings.

use nurbspring_scene::{MsmOverrides, Scene};
use nurbspring_sim::{IntegratorKind, RunOptions, simulate};

/// Largest problem run through the models (keeps each execution in milliseconds).
const MAX_CONTROL_POINTS: usize = 400;
/// Steps of each integrator.
const STEPS: f64 = 3.0;

/// Runs one scene text through the pipeline.
pub fn run_scene_text(text: &str) {
    let Ok(scene) = Scene::from_str(text, "fuzz.toml") else {
        return;
    };
    if scene.geometry.n_control_points() > MAX_CONTROL_POINTS
        || scene.msm.nodes_u.saturating_mul(scene.msm.nodes_v) > MAX_CONTROL_POINTS
    {
        return;
    }
    let Ok(model) = scene.build_dnurbs() else {
        return;
    };
    let dt = scene.simulation.dt;
    let initial = scene.initial_conditions().state(&model);
    for kind in [IntegratorKind::TerzopoulosQin, IntegratorKind::Newmark] {
        let opts = RunOptions::new(dt, STEPS * dt, kind);
        let _ = model.simulate(initial.clone(), &opts, &mut |_: &nurbspring_sim::Sample<'_>| {});
    }
    let _ = model.steady_state();
    let _ = model.modes(3);
    if !scene.geometry.is_surface() {
        return;
    }
    if let Ok(setup) = scene.msm_setup(&MsmOverrides::default()) {
        for kind in nurbspring_msm::MsmModel::INTEGRATORS {
            let mut opts = RunOptions::new(dt, STEPS * dt, kind);
            opts.force_unstable = true;
            let _ = simulate(&setup.model, setup.initial.clone(), &opts, &mut |_: &nurbspring_sim::Sample<'_>| {});
        }
        let _ = setup.model.stability();
    }
    if let Ok(config) = scene.derivation_config(Some(nurbspring_derive::Method::Paper))
        && let Ok(setup) = nurbspring_derive::Setup::new(&config)
    {
        for dofs in [nurbspring_derive::FitDofs::All, nurbspring_derive::FitDofs::Free] {
            for nonnegative in [false, true] {
                let _ = setup.solve(dofs, nonnegative);
            }
        }
    }
}
