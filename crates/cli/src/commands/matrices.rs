//! `nurbspring matrices SCENE --out DIR`: the D-NURBS matrices in Matrix Market form.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::export::write_matrices;

use nurbspring_scene::resources::Job;

use crate::{CmdResult, Context, commit_out_dir, print_json, stage_out_dir};

/// Flags of `nurbspring matrices`.
#[derive(Args, Debug)]
pub struct MatricesArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Print what was written as JSON on stdout instead of the result line.
    #[arg(long)]
    json: bool,
}

/// Assembles and writes M, D, K, f and the dof ordering.
pub fn run(ctx: &Context, args: MatricesArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    ctx.check_resources(&scene, Job::Assemble, Some(&args.out))?;
    let model = scene.build_dnurbs()?;
    let staged = stage_out_dir(&args.out)?;
    let written = write_matrices(staged.path(), &model, &args.scene.display().to_string())?;
    let out = commit_out_dir(staged)?;
    if args.json {
        let mut v = serde_json::to_value(&written).unwrap_or_default();
        if let serde_json::Value::Object(map) = &mut v {
            map.insert("out".into(), out.display().to_string().into());
        }
        return print_json(&v);
    }
    let e = &written.stored_entries;
    println!(
        "wrote M, D, K ({n} × {n}, symmetric; {} / {} / {} stored entries), f and dofs.json to {}",
        e["M"],
        e["D"],
        e["K"],
        out.display(),
        n = written.dofs,
    );
    Ok(())
}
