//! `nurbspring paper`: the paper's experiment (Section IV) with its built-in scene.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;

use crate::progress::Progress;
use crate::{CmdResult, Context, commit_out_dir, print_report, stage_out_dir};

/// Flags of `nurbspring paper`.
#[derive(Args, Debug)]
pub struct PaperArgs {
    /// Output folder.
    #[arg(long, default_value = "paper-output")]
    out: PathBuf,
    /// Print report.json on stdout instead of the table.
    #[arg(long)]
    json: bool,
}

/// Runs the paper's experiment and prints the reproduction table.
pub fn run(ctx: &Context, args: PaperArgs) -> CmdResult {
    let scene = Scene::paper()?;
    let staged = stage_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let table = scene.write_paper_experiment(
        staged.path(),
        Some(ctx.cancel.clone()),
        &mut |done, total| bar.update(done, total),
        &mut || bar.finish(),
    )?;
    let out = commit_out_dir(staged)?;
    if args.json {
        return print_report(&out);
    }
    println!("{table}");
    println!("Outputs in {}", out.display());
    Ok(())
}
