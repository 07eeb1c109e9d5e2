//! `nurbspring matrices SCENE --out DIR`: the D-NURBS matrices in Matrix Market form.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::export::write_matrices;

use nurbspring_scene::resources::Job;

use crate::{CmdResult, Context, commit_out_dir, stage_out_dir};

/// Flags of `nurbspring matrices`.
#[derive(Args, Debug)]
pub struct MatricesArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Assembles and writes M, D, K, f and the dof ordering.
pub fn run(ctx: &Context, args: MatricesArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    ctx.check_resources(&scene, Job::Assemble, Some(&args.out))?;
    let model = scene.build_dnurbs()?;
    let staged = stage_out_dir(&args.out)?;
    write_matrices(staged.path(), &model, &args.scene.display().to_string())?;
    let out = commit_out_dir(staged)?;
    if ctx.verbose() {
        let k = &model.matrices().stiffness;
        println!(
            "wrote M, D, K ({} × {}, {} non-zeros in K), f and dofs.json to {}",
            k.nrows(),
            k.ncols(),
            k.nnz(),
            out.display()
        );
    }
    Ok(())
}
