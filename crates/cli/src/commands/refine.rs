//! `nurbspring refine SCENE --insert-u … --insert-v … --elevate P,Q --out SCENE.toml`.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::geometry_file::{Refinement, refine_scene, write_text_file};
use nurbspring_scene::{Error, Scene};

use crate::{CmdResult, Context};

/// Flags of `nurbspring refine`.
#[derive(Args, Debug)]
pub struct RefineArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Knots to insert along u, comma-separated (repeat a value to insert it more than once).
    #[arg(
        long,
        value_name = "U,…",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    insert_u: Vec<f64>,
    /// Knots to insert along v (surfaces).
    #[arg(
        long,
        value_name = "V,…",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    insert_v: Vec<f64>,
    /// Raise the degrees to P along u and Q along v (a curve: P); done before the insertions.
    #[arg(long, value_name = "P,Q")]
    elevate: Option<String>,
    /// The refined scene to write (TOML).
    #[arg(long)]
    out: PathBuf,
}

fn parse_degrees(s: &str) -> Result<(usize, Option<usize>), Error> {
    let bad = || {
        Error::option(
            "--elevate",
            s,
            "expected P,Q (a surface) or P (a curve): degrees ≥ 1",
        )
    };
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let degree = |p: &str| p.parse::<usize>().ok().filter(|&d| d >= 1).ok_or_else(bad);
    match parts.as_slice() {
        [p] => Ok((degree(p)?, None)),
        [p, q] => Ok((degree(p)?, Some(degree(q)?))),
        _ => Err(bad()),
    }
}

/// Refines the scene's geometry exactly and writes the scene with the finer net.
pub fn run(_ctx: &Context, args: RefineArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    let refinement = Refinement {
        insert_u: args.insert_u.clone(),
        insert_v: args.insert_v.clone(),
        degrees: args.elevate.as_deref().map(parse_degrees).transpose()?,
    };
    if refinement == Refinement::default() {
        return Err(Error::option(
            "--insert-u, --insert-v, --elevate",
            "",
            "nothing to do: give at least one of them",
        ));
    }
    let refined = refine_scene(&scene, &refinement)?;
    let mut ops = Vec::new();
    if let Some(e) = &args.elevate {
        ops.push(format!("--elevate {e}"));
    }
    for (name, v) in [
        ("--insert-u", &args.insert_u),
        ("--insert-v", &args.insert_v),
    ] {
        if !v.is_empty() {
            let list: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
            ops.push(format!("{name} {}", list.join(",")));
        }
    }
    let text = format!(
        "# Refined by `nurbspring refine` from {}\n# ({}): the same {} on a finer net,\n\
         # evaluating to the same points up to round-off.\n# Before: {}.\n# Now: {}.\n\n{}",
        args.scene.display(),
        ops.join(" "),
        scene.geometry.section(),
        scene.geometry.describe(),
        refined.geometry.describe(),
        refined.to_toml()
    );
    write_text_file(&args.out, &text)?;
    // The result line: kept under -q (only progress and notes are hidden).
    println!(
        "refined {}: {} -> {}; written to {}",
        scene.geometry.section(),
        scene.geometry.describe(),
        refined.geometry.describe(),
        args.out.display()
    );
    Ok(())
}
