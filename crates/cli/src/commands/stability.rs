//! `nurbspring stability SCENE`: explicit stability limit of the scene's MSM.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Error;
use serde_json::json;

use crate::commands::{MsmFlags, flag};
use crate::{CmdResult, Context, print_json};

/// Flags of `nurbspring stability`.
#[derive(Args, Debug)]
pub struct StabilityArgs {
    /// Scene file (TOML) or an msm.json lattice.
    scene: PathBuf,
    #[command(flatten)]
    overrides: MsmFlags,
}

/// Prints `{"omega_max": …, "dt_critical": …}`.
pub fn run(ctx: &Context, args: StabilityArgs) -> CmdResult {
    let setup = ctx.load_msm(&args.scene, &args.overrides.overrides(), &flag, None)?;
    let s = setup
        .model
        .stability()
        .map_err(|e| Error::model(&setup.path, None, e))?;
    print_json(&json!({"omega_max": s.omega_max, "dt_critical": s.dt_critical}))
}
