//! `nurbspring matrices SCENE --out DIR`: the D-NURBS matrices in Matrix Market form.

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

use crate::convert;
use crate::{CmdResult, Context, Failure, prepare_out_dir};

/// Flags of `nurbspring matrices`.
#[derive(Args, Debug)]
pub struct MatricesArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Assembles and writes M, D, K, f and the dof ordering.
pub fn run(ctx: &Context, args: MatricesArgs) -> CmdResult {
    let scene = convert::load_scene(&args.scene)?;
    let model = convert::dnurbs_model(&scene)?;
    let out = prepare_out_dir(&args.out)?;
    let io = |e: nurbspring_io::OutputError| Failure::run(e);
    let m = model.matrices();
    let ordering = if m.dofs_per_point == 4 {
        "interleaved per control point: x, y, z, w; control point k = i * n_v + j (i along u)"
    } else {
        "interleaved per control point: x, y, z; control point k = i * n_v + j (i along u)"
    };
    let comment = format!(
        "nurbspring D-NURBS matrix of {}; dof ordering: {ordering}",
        args.scene.display()
    );
    nurbspring_io::output::write_matrix_market(out.join("M.mtx"), &m.mass, &comment).map_err(io)?;
    nurbspring_io::output::write_matrix_market(out.join("D.mtx"), &m.damping, &comment)
        .map_err(io)?;
    nurbspring_io::output::write_matrix_market(out.join("K.mtx"), &m.stiffness, &comment)
        .map_err(io)?;
    nurbspring_io::output::write_matrix_market_vector(out.join("f.mtx"), &m.force, &comment)
        .map_err(io)?;
    let dof_map = model.dof_map();
    let dofs = json!({
        "ordering": ordering,
        "dofs_per_point": m.dofs_per_point,
        "n_control_points": model.geometry().n_control_points(),
        "n_dofs": dof_map.n_total(),
        "fixed_dofs": dof_map.fixed(),
        "free_dofs": dof_map.free(),
        "fixed_control_points": model.fixed_points(),
        "files": {"M": "M.mtx", "D": "D.mtx", "K": "K.mtx", "f": "f.mtx"},
        "matrices_cover": "all dofs, before constraints are applied",
    });
    nurbspring_io::output::write_json(out.join("dofs.json"), &dofs).map_err(io)?;
    if !ctx.global.quiet {
        println!(
            "wrote M, D, K ({} × {}, {} non-zeros in K), f and dofs.json to {}",
            m.stiffness.nrows(),
            m.stiffness.ncols(),
            m.stiffness.nnz(),
            out.display()
        );
    }
    Ok(())
}
