//! `nurbspring matrices SCENE --out DIR`: the D-NURBS matrices in Matrix Market form.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::export::write_matrices;

use crate::{CmdResult, Context, prepare_out_dir};

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
    let model = scene.build_dnurbs()?;
    let out = prepare_out_dir(&args.out)?;
    write_matrices(&out, &model, &args.scene.display().to_string())?;
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
