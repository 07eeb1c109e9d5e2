//! `nurbspring check SCENE`: validate a scene and describe it without running a simulation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::resources::{Job, Timing, format_bytes};
use nurbspring_scene::summary::summary;
use serde_json::json;

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
    let (method, _) = scene.derivation();
    let mut resources = serde_json::Map::new();
    for (name, job) in [
        ("derive", Job::Derive(method)),
        ("simulate_dnurbs", Job::SimulateDnurbs(Timing::default())),
        ("simulate_msm", Job::SimulateMsm(Timing::default())),
        ("modes_steady", Job::Factorize),
    ] {
        let e = scene.estimate(job);
        resources.insert(
            name.to_string(),
            json!({
                "memory_bytes": e.memory,
                "memory": format_bytes(e.memory),
                "output_bytes": e.output,
                "frames": e.frames,
                "within_limits": e.memory <= ctx.limits.memory && e.output <= ctx.limits.output,
            }),
        );
    }
    resources.insert(
        "limits".to_string(),
        json!({"memory_bytes": ctx.limits.memory, "output_bytes": ctx.limits.output}),
    );
    let report = summary(&scene)?;
    let mut value = serde_json::to_value(&report).unwrap_or_default();
    if let serde_json::Value::Object(map) = &mut value {
        map.insert(
            "resources".to_string(),
            serde_json::Value::Object(resources),
        );
    }
    if args.json {
        return print_json(&value);
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
