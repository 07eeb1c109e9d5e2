//! `nurbspring export SCENE --format geomdl-json|iges|obj --out FILE` (the scene's geometry) and
//! `nurbspring export msm.json --format sofa|newton|npz --out FILE` (a mass-spring model).

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use nurbspring_scene::Shape;
use nurbspring_scene::geometry_file::{
    GeometryFormat, write_geometry_file, write_tessellated_curve_obj, write_tessellated_obj,
};
use nurbspring_scene::msm_export::{write_msm_newton, write_msm_npz, write_msm_sofa};
use nurbspring_scene::msm_file::{is_msm_file, load_msm};
use nurbspring_scene::{Error, Scene};

use crate::commands::{MsmFlags, flag};
use crate::{CmdResult, Context};

/// What `export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExportFormat {
    /// The scene's geometry as geomdl JSON (`exchange.import_json` reads it).
    GeomdlJson,
    /// The scene's geometry as IGES 5.3 entity 126 (curve) or 128 (surface).
    Iges,
    /// The scene's geometry as OBJ free-form (`cstype bspline`), or with --tessellate a mesh.
    Obj,
    /// A mass-spring model (msm.json or a scene's MSM) as a SOFA Python scene.
    Sofa,
    /// A mass-spring model as a NumPy .npz archive (docs/export.md).
    Npz,
    /// A mass-spring model as a Python script that builds and steps it in NVIDIA Newton (the
    /// Warp-based engine; docs/export.md).
    Newton,
}

/// Flags of `nurbspring export`.
#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Scene file (TOML); for sofa, newton and npz also an msm.json written by `derive`.
    input: PathBuf,
    /// Output format.
    #[arg(long, value_enum)]
    format: ExportFormat,
    /// Output file.
    #[arg(long)]
    out: PathBuf,
    /// With --format obj: a tessellated mesh of N x N samples with normals and texture
    /// coordinates (a curve: N points) instead of free-form records.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=10_000))]
    tessellate: Option<u32>,
    #[command(flatten)]
    overrides: MsmFlags,
}

/// Writes the export.
pub fn run(_ctx: &Context, args: ExportArgs) -> CmdResult {
    if args.tessellate.is_some() && args.format != ExportFormat::Obj {
        return Err(Error::option(
            "--tessellate",
            args.tessellate.unwrap_or_default(),
            "applies to --format obj only",
        ));
    }
    let geometry_format = match args.format {
        ExportFormat::GeomdlJson => Some(GeometryFormat::GeomdlJson),
        ExportFormat::Iges => Some(GeometryFormat::Iges),
        ExportFormat::Obj => Some(GeometryFormat::ObjFreeForm),
        ExportFormat::Sofa | ExportFormat::Npz | ExportFormat::Newton => None,
    };
    let what = match geometry_format {
        Some(format) => {
            if is_msm_file(&args.input) {
                return Err(Error::option(
                    "--format",
                    format!("{:?}", args.format).to_lowercase(),
                    format!(
                        "exports a scene's geometry, but {} is an msm.json model (use --format sofa, newton or npz)",
                        args.input.display()
                    ),
                ));
            }
            let scene = Scene::from_path(&args.input)?;
            let shape = scene.shape()?;
            match (args.tessellate, &shape) {
                (Some(n), Shape::Surface(s)) => {
                    let n = n as usize;
                    write_tessellated_obj(
                        &args.out,
                        s,
                        n,
                        n,
                        &format!("nurbspring tessellation of {}", args.input.display()),
                    )?;
                    format!("tessellated surface ({n} x {n} vertices with normals and UVs)")
                }
                (Some(n), Shape::Curve(c)) => {
                    write_tessellated_curve_obj(
                        &args.out,
                        c,
                        n as usize,
                        &format!("nurbspring tessellation of {}", args.input.display()),
                    )?;
                    format!("tessellated curve ({n} points)")
                }
                (None, _) => {
                    write_geometry_file(&args.out, format, std::slice::from_ref(&shape))?;
                    format!("{} ({})", scene.geometry.section(), format.name())
                }
            }
        }
        None => {
            let setup = load_msm(&args.input, &args.overrides.overrides(), &flag)?;
            let lattice = setup.model.lattice();
            let counts = format!(
                "{} nodes, {} springs, {} hinges, {} linear elements",
                lattice.n_nodes(),
                lattice.springs.len(),
                lattice.hinges.len(),
                lattice.elements.len()
            );
            if args.format == ExportFormat::Npz {
                write_msm_npz(&args.out, &setup)?;
                format!("mass-spring model as NumPy arrays ({counts})")
            } else if args.format == ExportFormat::Newton {
                let source = args.input.display().to_string();
                for note in write_msm_newton(&args.out, &setup, &source)? {
                    eprintln!("warning: {note}");
                }
                format!("mass-spring model as a Newton script ({counts})")
            } else {
                let source = args.input.display().to_string();
                for limit in write_msm_sofa(&args.out, &setup, &source)? {
                    eprintln!("warning: {limit}");
                }
                format!("mass-spring model as a SOFA scene ({counts})")
            }
        }
    };
    // The result line: kept under -q (only progress and notes are hidden).
    println!("{what} written to {}", args.out.display());
    Ok(())
}
