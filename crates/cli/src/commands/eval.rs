//! `nurbspring eval SCENE --at U,V [--derivatives N]` and `--grid NU,NV --out FILE`.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Geometry;
use nurbspring_scene::export::{TessellationFormat, point_json, write_tessellation};
use nurbspring_scene::{Error, Scene};
use serde_json::json;

use crate::{CmdResult, Context, print_json};

/// Flags of `nurbspring eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Scene file (TOML) with a [surface] or [curve].
    scene: PathBuf,
    /// Parameter to evaluate at: `U,V` for a surface, `U` for a curve (repeatable).
    #[arg(long = "at", value_name = "U,V", allow_hyphen_values = true)]
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

/// `n` comma-separated finite numbers of `--at`.
fn parse_params(s: &str, n: usize) -> Result<Vec<f64>, Error> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != n {
        return Err(Error::option(
            "--at",
            s,
            format!(
                "expected {n} comma-separated number{}",
                if n == 1 { "" } else { "s" }
            ),
        ));
    }
    parts
        .iter()
        .map(|p| {
            p.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Error::option("--at", s, format!("`{p}` is not a finite number")))
        })
        .collect()
}

/// `n` integers ≥ 2 of `--grid`, at most 5·10⁷ points.
fn parse_grid(spec: &str, n: usize) -> Result<Vec<usize>, Error> {
    let bad = || {
        Error::option(
            "--grid",
            spec,
            format!("expected {n} integer{} ≥ 2", if n == 1 { "" } else { "s" }),
        )
    };
    let parts: Vec<&str> = spec.split(',').map(str::trim).collect();
    if parts.len() != n {
        return Err(bad());
    }
    let v: Vec<usize> = parts
        .iter()
        .map(|p| p.parse::<usize>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    if v.iter().any(|&x| x < 2) {
        return Err(bad());
    }
    if v.iter()
        .try_fold(1usize, |a, &b| a.checked_mul(b))
        .is_none_or(|p| p > 50_000_000)
    {
        return Err(Error::option("--grid", spec, "more than 5·10^7 points"));
    }
    Ok(v)
}

/// Evaluates the scene's geometry.
pub fn run(_ctx: &Context, args: EvalArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    let geometry = scene.build_geometry()?;
    if args.at.is_empty() && args.grid.is_none() {
        return Err(Error::option(
            "--at",
            "(none)",
            "nothing to evaluate: give --at U,V (repeatable) or --grid NU,NV --out FILE",
        ));
    }
    let order = args.derivatives as usize;
    let mut points = Vec::new();
    for at in &args.at {
        let outside = |e: nurbspring_scene::GeomError| Error::option("--at", at, e.to_string());
        let params = parse_params(at, if geometry.is_curve() { 1 } else { 2 })?;
        points.push(point_json(&geometry, &params, order).map_err(outside)?);
    }
    if let Some(grid) = &args.grid {
        let out = args.out.as_ref().ok_or_else(|| {
            Error::option(
                "--grid",
                grid,
                "needs --out FILE (.csv, .vts, .vtu or .obj)",
            )
        })?;
        let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
        let format = TessellationFormat::from_extension(ext).ok_or_else(|| {
            Error::option(
                "--out",
                out.display(),
                format!("unknown format `{ext}` (use .csv, .vts, .vtu or .obj)"),
            )
        })?;
        let n = match &geometry {
            Geometry::Surface(_) => parse_grid(grid, 2)?,
            Geometry::Curve(_) => {
                let mut n = parse_grid(grid.split(',').next().unwrap_or(grid), 1)?;
                n.push(1);
                n
            }
        };
        write_tessellation(out, &geometry, format, n[0], n[1])?;
    }
    if !args.at.is_empty() {
        print_json(&json!({"points": points}))?;
    }
    Ok(())
}
