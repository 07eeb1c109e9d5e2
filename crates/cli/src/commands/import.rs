//! `nurbspring import FILE --out SCENE.toml`: a scene from a geomdl JSON, IGES or OBJ file.

use std::path::{Component, Path, PathBuf};

use clap::Args;
use nurbspring_scene::geometry_file::{
    GeometrySource, imported_scene, read_geometry_file, write_text_file,
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

/// The path of `file` as a scene at `scene` should write it: relative to the scene's folder
/// when both can be resolved, else absolute.
fn relative_to_scene(file: &Path, scene: &Path) -> String {
    let absolute = |p: &Path| std::path::absolute(p).ok();
    let dir = scene
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let (Some(file_abs), Some(dir_abs)) = (absolute(file), absolute(dir)) else {
        return file.display().to_string();
    };
    fn normal(p: &Path) -> Vec<Component<'_>> {
        p.components()
            .filter(|c| !matches!(c, Component::CurDir))
            .collect()
    }
    let (f, d) = (normal(&file_abs), normal(&dir_abs));
    if f.iter()
        .chain(&d)
        .any(|c| matches!(c, Component::ParentDir))
    {
        return file_abs.display().to_string();
    }
    let common = f.iter().zip(&d).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return file_abs.display().to_string();
    }
    let mut rel = PathBuf::new();
    for _ in common..d.len() {
        rel.push("..");
    }
    for c in &f[common..] {
        rel.push(c.as_os_str());
    }
    rel.to_string_lossy().replace('\\', "/")
}
