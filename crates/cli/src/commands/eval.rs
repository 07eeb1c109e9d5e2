//! `nurbspring eval SCENE --at U,V [--derivatives N]` and `--grid NU,NV --out FILE`.

use std::path::PathBuf;

use anyhow::anyhow;
use clap::Args;
use nurbspring_dnurbs::Geometry;
use serde_json::json;

use crate::convert;
use crate::{CmdResult, Context, Failure};

/// Flags of `nurbspring eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Scene file (TOML) with a [surface] or [curve].
    scene: PathBuf,
    /// Parameter to evaluate at: `U,V` for a surface, `U` for a curve (repeatable).
    #[arg(long = "at", value_name = "U,V")]
    at: Vec<String>,
    /// Also print derivatives up to this order (0, 1 or 2).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=2))]
    derivatives: u8,
    /// Tessellate on an NU × NV uniform parameter grid (a curve: NU points) and write --out.
    #[arg(long, value_name = "NU,NV")]
    grid: Option<String>,
    /// Output file of --grid: .csv, .vts, .vtu or .obj.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn parse_params(s: &str, n: usize) -> Result<Vec<f64>, Failure> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != n {
        return Err(Failure::input(anyhow!(
            "--at {s}: expected {n} comma-separated number{}",
            if n == 1 { "" } else { "s" }
        )));
    }
    parts
        .iter()
        .map(|p| {
            p.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Failure::input(anyhow!("--at {s}: `{p}` is not a finite number")))
        })
        .collect()
}

/// Evaluates the scene's geometry.
pub fn run(_ctx: &Context, args: EvalArgs) -> CmdResult {
    let scene = convert::load_scene(&args.scene)?;
    let geometry = convert::geometry(&scene)?;
    if args.at.is_empty() && args.grid.is_none() {
        return Err(Failure::input(anyhow!(
            "nothing to evaluate: give --at U,V (repeatable) or --grid NU,NV --out FILE"
        )));
    }
    let order = args.derivatives as usize;
    let mut points = Vec::new();
    for at in &args.at {
        match &geometry {
            Geometry::Surface(s) => {
                let uv = parse_params(at, 2)?;
                let d = s
                    .derivatives(uv[0], uv[1], order)
                    .map_err(|e| Failure::input(anyhow!("--at {at}: {e}")))?;
                let mut entry = json!({"u": uv[0], "v": uv[1], "point": d.point});
                if order >= 1 {
                    let mut dd = json!({"u": d.u, "v": d.v});
                    if order >= 2 {
                        dd["uu"] = json!(d.uu);
                        dd["uv"] = json!(d.uv);
                        dd["vv"] = json!(d.vv);
                    }
                    entry["d"] = dd;
                }
                points.push(entry);
            }
            Geometry::Curve(c) => {
                let u = parse_params(at, 1)?;
                let d = c
                    .derivatives(u[0], order)
                    .map_err(|e| Failure::input(anyhow!("--at {at}: {e}")))?;
                let mut entry = json!({"u": u[0], "point": d.point});
                if order >= 1 {
                    let mut dd = json!({"u": d.u});
                    if order >= 2 {
                        dd["uu"] = json!(d.uu);
                    }
                    entry["d"] = dd;
                }
                points.push(entry);
            }
        }
    }
    if let Some(grid) = &args.grid {
        let out = args.out.as_ref().ok_or_else(|| {
            Failure::input(anyhow!(
                "--grid needs --out FILE (.csv, .vts, .vtu or .obj)"
            ))
        })?;
        crate::output::write_tessellation(out, &geometry, grid)?;
    }
    if !args.at.is_empty() {
        let text =
            serde_json::to_string_pretty(&json!({"points": points})).map_err(Failure::run)?;
        println!("{text}");
    }
    Ok(())
}
