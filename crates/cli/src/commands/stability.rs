//! `nurbspring stability SCENE`: explicit stability limit of the scene's MSM.

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use crate::commands::simulate::MsmOverrides;
use crate::convert;
use crate::{CmdResult, Context, Failure};

/// Flags of `nurbspring stability`.
#[derive(Args, Debug)]
pub struct StabilityArgs {
    /// Scene file (TOML) or an msm.json lattice.
    scene: PathBuf,
    #[command(flatten)]
    overrides: MsmOverrides,
}

/// Prints `{"omega_max": …, "dt_critical": …}`.
pub fn run(_ctx: &Context, args: StabilityArgs) -> CmdResult {
    let (model, _, _) = convert::msm_model(&args.scene, &args.overrides)?;
    let s = model.stability().map_err(convert::msm_failure)?;
    let text = serde_json::to_string_pretty(
        &json!({"omega_max": s.omega_max, "dt_critical": s.dt_critical}),
    )
    .map_err(Failure::run)?;
    println!("{text}");
    Ok(())
}
