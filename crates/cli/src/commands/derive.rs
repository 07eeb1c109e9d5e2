//! `nurbspring derive SCENE --out DIR`: the derived MSM and its validation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::report::{constants_text, write_derivation};
use nurbspring_scene::{Error, Scene};

use crate::progress::Progress;
use crate::{CmdResult, Context, prepare_out_dir};

/// Flags of `nurbspring derive`.
#[derive(Args, Debug)]
pub struct DeriveArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Derives the MSM of a scene and writes every output.
pub fn run(ctx: &Context, args: DeriveArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    let config = scene.derivation_config()?;
    let out = prepare_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let (derivation, _) =
        nurbspring_derive::derive_msm(&config, Some(ctx.cancel.clone()), &mut |d, t| {
            bar.update(d, t)
        })
        .map_err(|e| Error::model(&scene.path, None, e))?;
    bar.finish();
    let label = args.scene.display().to_string();
    write_derivation(&out, &label, &scene, &derivation, None, "")?;
    if ctx.verbose() {
        let d = &derivation.derived;
        println!(
            "derived MSM: {}, m = {:.6}; dt_critical = {:.5}; central node rel. RMS = {:.4} ({})",
            constants_text(&d.constants, 6),
            d.m,
            d.dt_critical,
            d.validation.relative_rms,
            d.validation.integrator
        );
        println!("Outputs in {}", out.display());
    }
    Ok(())
}
