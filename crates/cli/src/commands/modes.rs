//! `nurbspring modes SCENE [--count N]`: natural frequencies of the constrained D-NURBS
//! (with weights as unknowns: of its linearization at the initial shape).

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::{Error, Scene};
use serde_json::json;

use crate::{CmdResult, Context, print_json};

/// Flags of `nurbspring modes`.
#[derive(Args, Debug)]
pub struct ModesArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// How many modes, lowest first.
    #[arg(long, default_value_t = 10)]
    count: usize,
}

/// Prints the lowest angular frequencies and periods as JSON; `free_dofs` is the size of the
/// eigenproblem solved (free dofs less one per independent linear constraint). With weights as
/// unknowns the modes are those of the matrices at the initial shape.
pub fn run(ctx: &Context, args: ModesArgs) -> CmdResult {
    if args.count == 0 {
        return Err(Error::option("--count", 0, "must be at least 1"));
    }
    let scene = Scene::from_path(&args.scene)?;
    ctx.check_resources(&scene, nurbspring_scene::resources::Job::Factorize, None)?;
    let model = scene.build_dnurbs()?;
    if let Some(w) = model.quadrature().warning() {
        eprintln!("warning: {w}");
    }
    let modes = model
        .modes(args.count)
        .map_err(|e| Error::model(&scene.path, None, e))?;
    let periods: Vec<Option<f64>> = modes
        .omega
        .iter()
        .map(|&w| (w > 0.0).then(|| 2.0 * std::f64::consts::PI / w))
        .collect();
    let matrices = if scene.dnurbs.weights_as_dofs {
        "linearized at the initial shape: K(p(0)) phi = omega^2 M(p(0)) phi (weights as unknowns)"
    } else {
        "constant: K phi = omega^2 M phi"
    };
    print_json(&json!({
        "omega": modes.omega,
        "periods": periods,
        "units": {"omega": "rad/s", "periods": "s"},
        "free_dofs": model.n_free(),
        "matrices": matrices,
    }))
}
