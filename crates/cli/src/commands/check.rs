//! `nurbspring check SCENE`: validate a scene and describe it without running a simulation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::summary::summary;

use crate::{CmdResult, Context, print_json};

/// Flags of `nurbspring check`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Validates every section and prints sizes, dofs, fixed dofs and stability limits.
pub fn run(_ctx: &Context, args: CheckArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    let report = summary(&scene)?;
    if args.json {
        return print_json(&report);
    }
    println!("{}: valid", args.scene.display());
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    let value = serde_json::to_value(&report).unwrap_or_default();
    print_tree(&value, 1);
    Ok(())
}

fn print_tree(v: &serde_json::Value, depth: usize) {
    if let serde_json::Value::Object(map) = v {
        for (k, val) in map {
            match val {
                serde_json::Value::Object(_) => {
                    println!("{}{k}:", "  ".repeat(depth));
                    print_tree(val, depth + 1);
                }
                other => println!("{}{k}: {other}", "  ".repeat(depth)),
            }
        }
    }
}
