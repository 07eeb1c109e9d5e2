//! `nurbspring check SCENE`: validate a scene and describe it without running a simulation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::resources::Job;
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
pub fn run(ctx: &Context, args: CheckArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    // The estimates come from the scene's sizes alone: computed, and a scene too large for
    // `check` itself refused, before any model is built.
    ctx.check_resources(&scene, Job::Check, None)?;
    let resources = scene.resources_json(&ctx.limits);
    let report = summary(&scene)?;
    let mut value = serde_json::to_value(&report).unwrap_or_default();
    if let serde_json::Value::Object(map) = &mut value {
        map.insert("resources".to_string(), resources);
        map.insert("derive_time".to_string(), scene.runtime_json());
    }
    if args.json {
        return print_json(&value);
    }
    // The text shows each run-time estimate by its largest term; `--json` lists them all.
    if let Some(serde_json::Value::Object(times)) = value.get_mut("derive_time") {
        for estimate in times.values_mut() {
            if let serde_json::Value::Object(e) = estimate {
                e.remove("terms");
            }
        }
    }
    println!("{}: valid", args.scene.display());
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
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
