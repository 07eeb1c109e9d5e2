//! `nurbspring steady SCENE [--out DIR]`: the D-NURBS steady state under the scene's loads
//! (paper eq. 8).

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use crate::convert;
use crate::{CmdResult, Context, Failure, prepare_out_dir};

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
pub fn run(_ctx: &Context, args: SteadyArgs) -> CmdResult {
    let scene = convert::load_scene(&args.scene)?;
    let model = convert::dnurbs_model(&scene)?;
    let p = model
        .steady_state()
        .map_err(|e| convert::dnurbs_failure(e).context(&args.scene))?;
    let probes = convert::probe_matrix(&scene, &model)?;
    let mut now = vec![0.0; probes.nrows()];
    let mut before = vec![0.0; probes.nrows()];
    probes.mul_vec(&p, &mut now);
    probes.mul_vec(model.p0(), &mut before);
    let params = convert::probes(&scene);
    let points: Vec<_> = params
        .iter()
        .enumerate()
        .map(|(i, &(u, v))| {
            let at = [now[3 * i], now[3 * i + 1], now[3 * i + 2]];
            let d = [
                at[0] - before[3 * i],
                at[1] - before[3 * i + 1],
                at[2] - before[3 * i + 2],
            ];
            json!({"u": u, "v": v, "point": at, "displacement": d})
        })
        .collect();
    if let Some(dir) = &args.out {
        let out = prepare_out_dir(dir)?;
        let dpp = model.matrices().dofs_per_point;
        crate::output::write_geometry_frame(&out.join("steady.vts"), model.geometry(), &p, dpp)?;
        let rows =
            (0..model.geometry().n_control_points()).map(|k| p[dpp * k..dpp * k + dpp].to_vec());
        let header: &[&str] = if dpp == 4 {
            &["x", "y", "z", "w"]
        } else {
            &["x", "y", "z"]
        };
        nurbspring_io::output::write_csv(out.join("steady.csv"), header, rows)
            .map_err(Failure::run)?;
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&json!({"probes": points})).map_err(Failure::run)?
    );
    Ok(())
}
