//! `nurbspring modes SCENE [--count N]`: natural frequencies of the constrained D-NURBS.

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use crate::convert;
use crate::{CmdResult, Context, Failure};

/// Flags of `nurbspring modes`.
#[derive(Args, Debug)]
pub struct ModesArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// How many modes, lowest first.
    #[arg(long, default_value_t = 10)]
    count: usize,
}

/// Prints the lowest angular frequencies and periods as JSON.
pub fn run(_ctx: &Context, args: ModesArgs) -> CmdResult {
    if args.count == 0 {
        return Err(Failure::input(anyhow::anyhow!(
            "--count must be at least 1"
        )));
    }
    let scene = convert::load_scene(&args.scene)?;
    let model = convert::dnurbs_model(&scene)?;
    let modes = model
        .modes(args.count)
        .map_err(|e| convert::dnurbs_failure(e).context(&args.scene))?;
    let periods: Vec<Option<f64>> = modes
        .omega
        .iter()
        .map(|&w| {
            if w > 0.0 {
                Some(2.0 * std::f64::consts::PI / w)
            } else {
                None
            }
        })
        .collect();
    let text = serde_json::to_string_pretty(&json!({
        "omega": modes.omega,
        "periods": periods,
        "units": {"omega": "rad/s", "periods": "s"},
        "free_dofs": model.dof_map().n_free(),
    }))
    .map_err(Failure::run)?;
    println!("{text}");
    Ok(())
}
