//! `nurbspring steady SCENE [--out DIR]`: the D-NURBS steady state under the scene's loads
//! (paper eq. 8; with weights as unknowns the nonlinear equilibrium, docs/math.md §3).

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::export::write_steady;
use nurbspring_scene::run::steady_state;
use serde_json::json;

use crate::{CmdResult, Context, commit_out_dir, print_json, stage_out_dir};

/// Flags of `nurbspring steady`.
#[derive(Args, Debug)]
pub struct SteadyArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Also write the deformed surface (`steady.vts`) and control points (`steady.csv`) here.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Solves `K(p) (p − p_rest) = f_p(p)` on the free dofs and prints the probes' surface points
/// at rest and their displacements as JSON.
pub fn run(ctx: &Context, args: SteadyArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    ctx.check_resources(
        &scene,
        nurbspring_scene::resources::Job::Factorize,
        args.out.as_deref(),
    )?;
    let steady = steady_state(&scene)?;
    for w in &steady.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(dir) = &args.out {
        let staged = stage_out_dir(dir)?;
        write_steady(staged.path(), &steady.model, &steady.p)?;
        commit_out_dir(staged)?;
    }
    let equations = if scene.dnurbs.weights_as_dofs {
        "nonlinear: K(p)(p - p_rest) = f(p), M, K, f at the solution"
    } else {
        "linear: K (p - p_rest) = f"
    };
    print_json(&json!({
        "probes": steady.probes,
        "solve": {
            "equations": equations,
            "iterations": steady.iterations,
            "relative_residual": steady.residual,
        },
    }))
}
