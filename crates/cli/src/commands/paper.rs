//! `nurbspring paper`: the paper's experiment (Section IV) with its built-in scene.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Scene;
use nurbspring_scene::markdown::verdict_table;
use nurbspring_scene::report::{how_run, write_derived_files_with, write_reports};

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
    let config = scene.derivation_config(Some(nurbspring_derive::Method::Paper))?;
    let staged = stage_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let model_error = |e| nurbspring_scene::Error::model(&scene.path, None, e);
    let (main, main_setup) =
        nurbspring_derive::derive_msm(&config, Some(ctx.cancel.clone()), &mut |done, total| {
            bar.update(done, total)
        })
        .map_err(model_error)?;
    bar.finish();
    // The default derivation of the same scene, whose MSM the central node's figure shows
    // beside the paper's: what this project adds.
    let modal_config = scene.derivation_config(Some(nurbspring_derive::Method::Modal))?;
    let (modal, _) =
        nurbspring_derive::derive(&modal_config, Some(ctx.cancel.clone()), &mut |_, _| {})
            .map_err(model_error)?;
    let modal_curve = (
        format!(
            "MSM of the default (modal) derivation: {}",
            how_run(&modal.derived)
        ),
        &modal.msm_trajectory,
    );
    // The main derivation's files (plots among them) are written while the readings run.
    let label = "built-in paper scene (examples/paper.toml)";
    let (report, written) = rayon::join(
        || {
            nurbspring_derive::paper::readings(
                &config,
                &main,
                &main_setup,
                Some(ctx.cancel.clone()),
            )
        },
        || {
            write_derived_files_with(
                staged.path(),
                label,
                &scene,
                &main,
                std::slice::from_ref(&modal_curve),
            )
        },
    );
    written?;
    let report = report.map_err(model_error)?;
    let table = verdict_table(&report);
    write_reports(staged.path(), label, &scene, &main, Some(&report), &table)?;
    let out = commit_out_dir(staged)?;
    if args.json {
        return print_report(&out);
    }
    println!("{table}");
    println!("Outputs in {}", out.display());
    Ok(())
}
