//! `nurbspring derive SCENE --out DIR`: the derived MSM and its validation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_derive::Method;
use nurbspring_scene::report::{constants_text, write_derivation};
use nurbspring_scene::{Error, Scene};

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
    /// Derivation: modal (default), paper, excitation or reduction (default: the scene's
    /// fit.derivation).
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
    let (method, fallback) = match args.derivation {
        Some(m) => (m, None),
        None => scene.derivation(),
    };
    ctx.check_resources(&scene, Job::Derive(method), Some(&args.out))?;
    let config = scene.derivation_config(Some(method))?;
    let staged = stage_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let cancel = Some(ctx.cancel.clone());
    let key = if args.derivation.is_some() {
        "--derivation"
    } else {
        "fit.derivation"
    };
    let result = match config.method {
        Method::Paper => {
            nurbspring_derive::derive_msm(&config, cancel, &mut |d, t| bar.update(d, t))
        }
        _ => nurbspring_derive::derive_linear(&config, cancel),
    };
    let (derivation, _) = result.map_err(|e| {
        // An option error names its own key; other input errors are the derivation's.
        let named = matches!(e, nurbspring_derive::DeriveError::InvalidOption { .. });
        let input = e.kind() == nurbspring_sim::ErrorKind::Input;
        Error::model(&scene.path, (input && !named).then_some(key), e)
    })?;
    bar.finish();
    let label = args.scene.display().to_string();
    write_derivation(staged.path(), &label, &scene, &derivation, None, "")?;
    let out = commit_out_dir(staged)?;
    if args.json {
        print_report(&out)?;
    } else {
        let d = &derivation.derived;
        println!(
            "derived MSM ({}): {}, m = {:.6}; dt_critical = {:.5}; central node rel. RMS = {} over {:.3} s ({}), second excitation {:.4}",
            derivation.method.name(),
            constants_text(&d.constants, 6),
            d.m,
            d.dt_critical,
            if d.validation.relative_rms.is_nan() {
                "n/a".to_string()
            } else {
                format!("{:.4}", d.validation.relative_rms)
            },
            d.validation.horizon,
            d.validation.integrator,
            derivation.second_excitation.relative_rms
        );
        println!("Outputs in {}", out.display());
    }
    if let (Some(why), true) = (fallback, ctx.verbose()) {
        eprintln!("note: {why}");
    }
    for w in &derivation.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}
