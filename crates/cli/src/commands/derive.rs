//! `nurbspring derive SCENE --out DIR`: the derived MSM and its validation.

use std::path::{Path, PathBuf};

use clap::Args;
use nurbspring_scene::report::{derivation_line, write_derivation};
use nurbspring_scene::{DerivationChoice, Method, Scene};

use crate::progress::Progress;
use nurbspring_scene::resources::Job;

use crate::{CmdResult, Context, commit_out_dir, print_report, stage_out_dir};

/// Flags of `nurbspring derive`.
#[derive(Args, Debug)]
pub struct DeriveArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Derivation: modal, paper, excitation, reduction or springs (default: the scene's
    /// fit.derivation, else modal; springs for a Kirchhoff–Love scene, which takes every one
    /// but paper).
    #[arg(long, value_parser = parse_method)]
    derivation: Option<Method>,
    /// Print report.json on stdout instead of the result lines.
    #[arg(long)]
    json: bool,
}

fn parse_method(s: &str) -> Result<Method, String> {
    Method::parse(s).ok_or_else(|| {
        format!(
            "unknown derivation; expected one of {}",
            Method::ALL.map(Method::name).join(", ")
        )
    })
}

/// Derives the MSM of a scene and writes every output.
pub fn run(ctx: &Context, args: DeriveArgs) -> CmdResult {
    let scene = Scene::from_path(&args.scene)?;
    let choice = scene.choose_derivation(args.derivation.map(|m| (m, "--derivation")));
    ctx.check_resources(&scene, Job::Derive(choice.method), Some(&args.out))?;
    if scene.derives_from_shell(&choice) {
        return if choice.method == Method::Reduction {
            run_shell_reduction(ctx, &args, &scene, &choice)
        } else {
            run_springs(ctx, &args, &scene, &choice)
        };
    }
    let prepared = scene.prepare_derivation(choice)?;
    let staged = stage_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let (derivation, _) = prepared.run(Some(ctx.cancel.clone()), &mut |d, t| bar.update(d, t))?;
    bar.finish();
    let label = args.scene.display().to_string();
    write_derivation(staged.path(), &label, &scene, &derivation, None, "")?;
    let out = commit_out_dir(staged)?;
    if args.json {
        print_report(&out)?;
    } else {
        println!("{}", derivation_line(&derivation));
        println!("Outputs in {}", out.display());
    }
    if let (Some(why), true) = (choice.fallback, ctx.verbose()) {
        eprintln!("note: {why}");
    }
    for w in &derivation.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// The reduction of a Kirchhoff–Love scene's shell onto its lattice nodes (docs/math.md §11.4).
fn run_shell_reduction(
    ctx: &Context,
    args: &DeriveArgs,
    scene: &Scene,
    choice: &DerivationChoice,
) -> CmdResult {
    staged_run(ctx, args, "reduction of the shell", |out, _| {
        let r = nurbspring_scene::springs_report::reduce_shell(
            scene,
            choice,
            Some(ctx.cancel.clone()),
        )?;
        let label = args.scene.display().to_string();
        nurbspring_scene::springs_report::write_shell_reduction(out, &label, &r)?;
        Ok(r.verdict)
    })
}

/// The spring derivation of a Kirchhoff–Love scene (docs/math.md §11).
fn run_springs(
    ctx: &Context,
    args: &DeriveArgs,
    scene: &Scene,
    choice: &DerivationChoice,
) -> CmdResult {
    staged_run(ctx, args, "spring derivation", |out, bar| {
        let d = nurbspring_scene::springs_report::derive_springs(
            scene,
            choice,
            Some(ctx.cancel.clone()),
            &mut |stage| bar.set_message(&format!("spring derivation, {stage}")),
        )?;
        let label = args.scene.display().to_string();
        nurbspring_scene::springs_report::write_springs(out, &label, scene, &d)?;
        Ok(format!(
            "derived spring model ({}): {} nodes, {} springs, {} hinges; {}",
            d.method.name(),
            d.lattice.n_nodes(),
            d.lattice.springs.len(),
            d.lattice.hinges.len(),
            d.verdict
        ))
    })
}

/// Runs `work` into a staged output folder with a progress line named `what`, commits the
/// folder whole, then prints report.json (`--json`) or the summary line `work` returns.
fn staged_run(
    ctx: &Context,
    args: &DeriveArgs,
    what: &str,
    work: impl FnOnce(&Path, &Progress) -> Result<String, nurbspring_scene::Error>,
) -> CmdResult {
    let staged = stage_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, what, 1);
    let summary = work(staged.path(), &bar)?;
    bar.finish();
    let out = commit_out_dir(staged)?;
    if args.json {
        print_report(&out)?;
    } else {
        println!("{summary}");
        println!("Outputs in {}", out.display());
    }
    Ok(())
}
