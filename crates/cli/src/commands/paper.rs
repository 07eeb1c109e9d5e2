//! `nurbspring paper`: the paper's experiment (Section IV) with its built-in scene.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;

use crate::commands::derive::write_derivation;
use crate::convert;
use crate::progress::Progress;
use crate::{CmdResult, Context, Failure, prepare_out_dir};

/// The built-in scene: the same text as `examples/paper.toml`.
pub const PAPER_SCENE: &str = include_str!("../../../../examples/paper.toml");

/// Flags of `nurbspring paper`.
#[derive(Args, Debug)]
pub struct PaperArgs {
    /// Output folder.
    #[arg(long, default_value = "paper-output")]
    out: PathBuf,
}

/// Runs the paper's experiment and prints the reproduction table.
pub fn run(ctx: &Context, args: PaperArgs) -> CmdResult {
    let scene = nurbspring_io::scene::Scene::from_str(
        PAPER_SCENE,
        std::path::Path::new("<built-in paper scene>"),
    )
    .map_err(Failure::input)?;
    let config = convert::experiment(&scene)?;
    let out = prepare_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let (derivation, report) = nurbspring_derive::paper::reproduce(&config, &mut |done, total| {
        bar.set_total(total as u64);
        bar.set(done as u64);
    })
    .map_err(convert::derive_failure)?;
    bar.finish();
    let table = verdict_table(&report);
    write_derivation(
        &out,
        "built-in paper scene (examples/paper.toml)",
        &scene,
        &derivation,
        Some(&report),
        &table,
    )?;
    println!("{table}");
    println!("Outputs in {}", out.display());
    Ok(())
}

/// The human table of the reproduction: each paper number, what nurbspring obtains, the verdict.
pub fn verdict_table(report: &nurbspring_derive::paper::PaperReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Reproduction of Section IV (paper value | nurbspring | verdict)"
    );
    let _ = writeln!(s, "{}", "=".repeat(78));
    for v in &report.verdicts {
        let _ = writeln!(s, "{}", v.quantity);
        let _ = writeln!(s, "  paper:    {}", v.paper);
        let _ = writeln!(s, "  obtained: {}", v.obtained);
        let _ = writeln!(s, "  verdict:  {} - {}", v.verdict.label(), v.why);
    }
    let _ = writeln!(s, "{}", "-".repeat(78));
    let _ = writeln!(
        s,
        "Stiffness fit, every reading (net, dofs, norm, constraint: k_edge, k_diag, relative residual; the same at the paper's k)"
    );
    for f in &report.fits {
        let _ = writeln!(
            s,
            "  {:<8} {:<4} {:<9} {:<13} k_edge = {:>10.5}  k_diag = {:>10.5}  residual = {:.4}  (paper's k: {:.4})",
            f.net.name(),
            f.dofs.name(),
            f.norm,
            if f.nonnegative {
                "k >= 0"
            } else {
                "unconstrained"
            },
            f.result.k(nurbspring_msm::SpringKind::Structural),
            f.result.k(nurbspring_msm::SpringKind::Shear),
            f.result.relative_residual,
            f.residual_at_paper_values
        );
    }
    let _ = writeln!(
        s,
        "Side-by-side runs, central node z (net, rest shape, parameters, integrator, horizon: dt_crit, rel. RMS, periods D-NURBS/MSM)"
    );
    for d in &report.dynamics {
        let _ = writeln!(
            s,
            "  {:<8} rest={:<7} {:<7} {:<16} {:>4} s  dt_crit = {:.4}  rel.RMS = {:>9.4}  T = {} / {}{}",
            d.net.name(),
            d.rest_shape,
            d.parameters,
            d.integrator,
            d.t_end,
            d.dt_critical,
            d.relative_rms,
            d.dnurbs_period
                .map(|p| format!("{p:.3}"))
                .unwrap_or_else(|| "-".into()),
            d.msm_period
                .map(|p| format!("{p:.3}"))
                .unwrap_or_else(|| "-".into()),
            if d.msm_stopped.is_some() {
                "  (MSM run stopped: diverged)"
            } else {
                ""
            }
        );
    }
    s
}
