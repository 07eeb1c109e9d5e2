//! `nurbspring steady SCENE [--out DIR] [--load-steps N] [--linear]`: the D-NURBS steady
//! state under the scene's loads (paper eq. 8; with weights as unknowns the nonlinear
//! equilibrium; the Kirchhoff–Love shell's nonlinear equilibrium path, docs/math.md §3, §10.5).

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::export::write_steady;
use nurbspring_scene::run::{SteadyRequest, steady_state, write_load_path};
use serde_json::json;

use crate::progress::Progress;
use crate::{CmdResult, Context, commit_out_dir, print_json, stage_out_dir};

/// Flags of `nurbspring steady`.
#[derive(Args, Debug)]
pub struct SteadyArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Also write the deformed surface (`steady.vts`) and control points (`steady.csv`) here,
    /// and with --load-steps the probes' displacements at each level (`load_path.csv`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Record N equal load levels λ = 1/N … 1 (the shell's Newton path; a linear model scales
    /// its solution) and write them to DIR/load_path.csv (needs --out).
    #[arg(long, value_name = "N")]
    load_steps: Option<usize>,
    /// Kirchhoff–Love scenes: solve the linearization at rest, K_T(p0) Δp = f, instead of the
    /// nonlinear equilibrium.
    #[arg(long)]
    linear: bool,
}

/// Solves the equilibrium on the free dofs and prints the probes' surface points at rest and
/// their displacements as JSON.
pub fn run(ctx: &Context, args: SteadyArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    if args.load_steps.is_some() && args.out.is_none() {
        return Err(nurbspring_scene::Error::Option {
            name: "--load-steps".into(),
            value: args.load_steps.unwrap_or(0).to_string(),
            message: "writes load_path.csv into the output folder: give --out DIR".into(),
        });
    }
    ctx.check_resources(
        &scene,
        nurbspring_scene::resources::Job::Factorize,
        args.out.as_deref(),
    )?;
    let request = SteadyRequest {
        load_steps: args.load_steps.unwrap_or(1),
        linear: args.linear,
        cancel: Some(ctx.cancel.clone()),
    };
    let bar = Progress::new(ctx.global.quiet, "load", 1000);
    let mut progress = |lambda: f64| bar.set((lambda * 1000.0).round() as u64);
    let steady = steady_state(&scene, &request, &mut progress)?;
    bar.finish();
    for w in &steady.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(dir) = &args.out {
        let staged = stage_out_dir(dir)?;
        write_steady(staged.path(), &steady.model, &steady.p)?;
        if args.load_steps.is_some() {
            write_load_path(staged.path(), &steady)?;
        }
        commit_out_dir(staged)?;
    }
    print_json(&json!({
        "probes": steady.probes,
        "solve": {
            "equations": steady.equations,
            "iterations": steady.iterations,
            "increments": steady.increments,
            "relative_residual": steady.residual,
        },
    }))
}
