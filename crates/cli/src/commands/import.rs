//! `nurbspring import FILE --out SCENE.toml`: a scene from a geomdl JSON, IGES or OBJ file.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::geometry_file::{
    GeometrySource, imported_scene, read_geometry_file, relative_to_scene, write_text_file,
};
use nurbspring_scene::{Error, GeometrySpec, Scene};

use crate::{CmdResult, Context};

/// Flags of `nurbspring import`.
#[derive(Args, Debug)]
pub struct ImportArgs {
    /// Geometry file: .json (geomdl), .igs or .iges (IGES 126/128), .obj (OBJ free-form).
    file: PathBuf,
    /// The scene file to write (TOML).
    #[arg(long)]
    out: PathBuf,
    /// Import a curve (default: the file's first surface, or its first curve when it has none).
    #[arg(long)]
    curve: bool,
    /// Which surface (or curve) of the file, counted from 0.
    #[arg(long, default_value_t = 0)]
    index: usize,
    /// Write `file = "…"` (relative to the scene) instead of the control net inline.
    #[arg(long)]
    link: bool,
}

/// Reads the file, picks the shape, writes a commented scene and checks that it loads.
pub fn run(ctx: &Context, args: ImportArgs) -> CmdResult {
    let file = read_geometry_file(&args.file)?;
    let surface = !args.curve && file.shapes.iter().any(|s| s.as_surface().is_some());
    let shape = file.select(surface, args.index).map_err(|m| {
        Error::option(
            "--index",
            args.index,
            format!("{}: {m}", args.file.display()),
        )
    })?;
    let geometry = GeometrySpec::from_shape(shape);
    let source = if args.link {
        GeometrySource::Link {
            file: relative_to_scene(&args.file, &args.out),
            index: args.index,
        }
    } else {
        GeometrySource::Inline
    };
    let origin = format!("{} ({})", args.file.display(), file.format.name());
    let text = imported_scene(&geometry, &origin, &source);
    // The scene must load as written (with its path, so that a linked file resolves).
    let scene = Scene::from_str(&text, &args.out)?;
    write_text_file(&args.out, &text)?;
    if ctx.verbose() {
        for note in &file.notes {
            eprintln!("note: {note}");
        }
    }
    let (n_u, n_v) = scene.geometry.net_dims();
    let others = file.shapes.len() - 1;
    if others > 0 && ctx.verbose() {
        eprintln!(
            "note: the file holds {} shapes; imported {} {} (choose another with --index, --curve)",
            file.shapes.len(),
            scene.geometry.section(),
            args.index
        );
    }
    // The result line: kept under -q (only progress and notes are hidden).
    let size = if scene.geometry.is_surface() {
        format!("{n_u} x {n_v}")
    } else {
        n_u.to_string()
    };
    println!(
        "imported {} ({size} control points) from {}; scene written to {}",
        scene.geometry.section(),
        args.file.display(),
        args.out.display()
    );
    Ok(())
}
