//! `nurbspring check SCENE`: validate a scene and describe it without running a simulation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_dnurbs::Geometry;
use serde_json::json;

use crate::commands::simulate::MsmOverrides;
use crate::convert;
use crate::{CmdResult, Context, Failure};

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
    let scene = convert::load_scene(&args.scene)?;
    let model = convert::dnurbs_model(&scene)?;
    let sim = convert::simulation(&scene)?;
    let geometry = match model.geometry() {
        Geometry::Surface(s) => json!({
            "kind": "surface",
            "degree": [s.basis_u().degree(), s.basis_v().degree()],
            "control_points": [s.n_u(), s.n_v()],
            "knot_spans": [s.basis_u().knots().nonempty_spans().len(), s.basis_v().knots().nonempty_spans().len()],
            "rational": s.weights().iter().any(|&w| w != s.weights()[0]),
        }),
        Geometry::Curve(c) => json!({
            "kind": "curve",
            "degree": c.basis().degree(),
            "control_points": c.n_control_points(),
            "knot_spans": c.basis().knots().nonempty_spans().len(),
            "rational": c.weights().iter().any(|&w| w != c.weights()[0]),
        }),
    };
    let dof_map = model.dof_map();
    let mut report = json!({
        "scene": args.scene.display().to_string(),
        "geometry": geometry,
        "dnurbs": {
            "dofs_per_point": model.matrices().dofs_per_point,
            "dofs": dof_map.n_total(),
            "fixed_dofs": dof_map.n_total() - dof_map.n_free(),
            "free_dofs": dof_map.n_free(),
            "fixed_control_points": model.fixed_points().len(),
            "stiffness_nonzeros": model.matrices().stiffness.nnz(),
        },
        "simulation": {"dt": sim.dt, "t_end": sim.t_end, "steps": (sim.t_end / sim.dt).ceil(),
                       "dnurbs_integrator": sim.dnurbs_integrator.name(), "msm_integrator": sim.msm_integrator.name()},
    });
    if matches!(model.geometry(), Geometry::Surface(_)) {
        let (msm, _, _) = convert::msm_model(&args.scene, &MsmOverrides::default())?;
        let lattice = msm.lattice();
        let mut kinds = serde_json::Map::new();
        for kind in lattice.kinds_present() {
            kinds.insert(
                kind.name().to_string(),
                json!(lattice.springs.iter().filter(|s| s.kind == kind).count()),
            );
        }
        let stability = msm.stability().map_err(convert::msm_failure)?;
        report["msm"] = json!({
            "nodes": lattice.n_nodes(),
            "grid": lattice.grid,
            "fixed_nodes": lattice.fixed.iter().filter(|&&f| f).count(),
            "free_dofs": msm.dof_map().n_free(),
            "springs": kinds,
            "omega_max": stability.omega_max,
            "dt_critical": stability.dt_critical,
            "dt_exceeds_explicit_limit": sim.dt >= stability.dt_critical,
        });
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(Failure::run)?
        );
    } else {
        println!("{}: valid", args.scene.display());
        print_tree(&report, 1);
    }
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
