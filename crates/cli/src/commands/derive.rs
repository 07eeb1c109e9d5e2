//! `nurbspring derive SCENE --out DIR`: the derived MSM and its validation.

use std::path::PathBuf;

use clap::Args;
use nurbspring_scene::Method;
use nurbspring_scene::Scene;
use nurbspring_scene::report::{constants_text, write_derivation};

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
    let choice = scene.choose_derivation(args.derivation.map(|m| (m, "--derivation")));
    ctx.check_resources(&scene, Job::Derive(choice.method), Some(&args.out))?;
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
        let d = &derivation.derived;
        // What was derived: an MSM, or the exact reduction (a linear model, not an MSM).
        let what = match derivation.method() {
            Method::Reduction => format!(
                "exact reduction onto {} free nodes (reduction.json: a linear node-space model, not an MSM; the reference an MSM is judged against)",
                derivation.reduction().map_or(0, |r| r.free.len())
            ),
            m => format!("derived MSM ({})", m.name()),
        };
        let mut parts = Vec::new();
        let constants = constants_text(&d.constants, 6);
        if !constants.is_empty() {
            parts.push(constants);
        }
        parts.push(mass_text(&derivation, d.m));
        println!(
            "{what}: {}; dt_critical = {:.5}; central node rel. RMS = {} over {:.3} s ({}), second excitation {:.4}",
            parts.join(", "),
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
    if let (Some(why), true) = (choice.fallback, ctx.verbose()) {
        eprintln!("note: {why}");
    }
    for w in &derivation.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// The node masses of a derivation's result: one `m` when every free node has it, else their
/// range and mean (the linear derivations fit one mass per node); the reduction's total.
fn mass_text(derivation: &nurbspring_scene::Derivation, m: f64) -> String {
    let free: Vec<f64> = match derivation.lattice() {
        Some(l) => l
            .masses
            .iter()
            .zip(&l.fixed)
            .filter(|(_, f)| !**f)
            .map(|(m, _)| *m)
            .collect(),
        None => {
            return format!(
                "free mass {:.6} (M_T, against the D-NURBS's {:.6})",
                derivation.mass.free_msm, derivation.mass.free_dnurbs
            );
        }
    };
    let (lo, hi) = free
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if free.is_empty() || lo == hi {
        format!("m = {m:.6}")
    } else {
        format!(
            "node masses {lo:.6} to {hi:.6} (mean {:.6} over {} free nodes)",
            free.iter().sum::<f64>() / free.len() as f64,
            free.len()
        )
    }
}
