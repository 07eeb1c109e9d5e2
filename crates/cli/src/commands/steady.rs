//! `nurbspring steady SCENE [--out DIR]`: the D-NURBS steady state under the scene's loads
//! (paper eq. 8).

use std::path::PathBuf;

use clap::Args;
use nurbspring_derive::Omega;
use nurbspring_scene::export::write_steady;
use nurbspring_scene::{Error, Scene};
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

/// Solves `K (p − p_rest) = f` on the free dofs and prints the probes' displacements as JSON.
pub fn run(ctx: &Context, args: SteadyArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    ctx.check_resources(
        &scene,
        nurbspring_scene::resources::Job::Factorize,
        args.out.as_deref(),
    )?;
    let model = scene.build_dnurbs()?;
    let p = model
        .steady_state()
        .map_err(|e| Error::model(&scene.path, None, e))?;
    let params = scene.probe_params()?;
    let probes = Omega::new(model.geometry(), &params, scene.dnurbs.weights_as_dofs)
        .map_err(|e| Error::model(&scene.path, Some("simulation.probes"), e))?;
    let (now, before) = (probes.apply(&p), probes.apply(model.p0()));
    let points: Vec<_> = params
        .iter()
        .zip(now.iter().zip(&before))
        .map(|(&(u, v), (at, b))| {
            let d = [at[0] - b[0], at[1] - b[1], at[2] - b[2]];
            json!({"u": u, "v": v, "point": at, "displacement": d})
        })
        .collect();
    if let Some(dir) = &args.out {
        let staged = stage_out_dir(dir)?;
        write_steady(staged.path(), &model, &p)?;
        commit_out_dir(staged)?;
    }
    print_json(&json!({"probes": points}))
}
