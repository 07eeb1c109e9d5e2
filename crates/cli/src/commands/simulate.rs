//! `nurbspring simulate SCENE --model dnurbs|msm --out DIR`.

use std::path::PathBuf;
use std::sync::atomic::Ordering;

use clap::{Args, ValueEnum};
use nurbspring_scene::run::{RunRequest, simulate_dnurbs, simulate_msm, write_run};
use nurbspring_scene::{DEFAULT_MAX_FRAMES, Error, IntegratorKind, Scene};

use crate::commands::{IntegratorChoice, MsmFlags, flag};
use crate::progress::Progress;
use nurbspring_scene::resources::{Job, Timing};

use crate::{CmdResult, Context, commit_out_dir, print_json, stage_out_dir};

/// Which model to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModelKind {
    /// The D-NURBS surface or curve.
    Dnurbs,
    /// The scene's mass-spring lattice (or an msm.json file).
    Msm,
}

/// Flags of `nurbspring simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Scene file (TOML), or with --model msm an msm.json lattice written by `derive`.
    scene: PathBuf,
    /// Which model.
    #[arg(long, value_enum)]
    model: ModelKind,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Time step [s] (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    dt: Option<f64>,
    /// End time [s] (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    t_end: Option<f64>,
    /// Integrator (default: the scene's). D-NURBS: terzopoulos-qin, newmark, modal; MSM:
    /// symplectic-euler, verlet, rk4, backward-euler, newmark, modal (linear MSMs). A scene's
    /// explicit MSM integrator above its stability limit runs in substeps below the lattice's
    /// uniform limit (newmark when more than 4096 would be needed), with a warning.
    #[arg(long, value_enum)]
    integrator: Option<IntegratorChoice>,
    /// Run an explicit integrator above its stability limit anyway.
    #[arg(long)]
    force_unstable: bool,
    /// Print the run's summary as JSON on stdout instead of the result line.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    overrides: MsmFlags,
}

/// Runs the simulation and writes trajectory.csv, energy.csv and a ParaView series.
pub fn run(ctx: &Context, args: SimulateArgs) -> CmdResult {
    let integrator = args.integrator.map(IntegratorKind::from);
    let request = RunRequest {
        dt: args.dt,
        t_end: args.t_end,
        integrator,
        force_unstable: args.force_unstable,
        cancel: Some(ctx.cancel.clone()),
    };
    let timing = Timing {
        dt: args.dt,
        t_end: args.t_end,
    };
    let bar = Progress::new(ctx.global.quiet, "", 1);
    let mut progress = |step: usize, steps: usize| bar.update(step, steps);
    let (staged, simulated, outcome, what) = match args.model {
        ModelKind::Dnurbs => {
            let scene = Scene::from_path(&args.scene)?;
            ctx.check_resources(&scene, Job::SimulateDnurbs(timing), Some(&args.out))?;
            let staged = stage_out_dir(&args.out)?;
            let (sim, outcome) =
                simulate_dnurbs(&scene, &request, Some(staged.path()), &mut progress)?;
            (staged, sim, outcome, ModelKind::Dnurbs)
        }
        ModelKind::Msm => {
            let setup = ctx.load_msm(
                &args.scene,
                &args.overrides.overrides(),
                &flag,
                Some((&args.out, timing)),
            )?;
            let staged = stage_out_dir(&args.out)?;
            let (sim, outcome) =
                simulate_msm(&setup, &request, Some(staged.path()), &mut progress)?;
            (staged, sim, outcome, ModelKind::Msm)
        }
    };
    bar.finish();
    for w in &simulated.warnings {
        eprintln!("warning: {w}");
    }
    if let (Some(s), true) = (simulated.stability, ctx.verbose()) {
        eprintln!(
            "stability: omega_max = {:.6e} rad/s, dt_critical = {:.6e} s (dt = {}, {})",
            s.omega_max, s.dt_critical, simulated.dt, simulated.integrator
        );
    }
    // A failed run leaves the previous one in place (the staged folder is dropped).
    let summary = outcome?;
    if summary.halved_steps > 0 && ctx.verbose() {
        eprintln!(
            "note: {} of the run's steps were taken in halves after Newton failed on them \
             (the implicit integrators' step halving, docs/math.md §5)",
            summary.halved_steps
        );
    }
    write_run(staged.path(), &simulated)?;
    if summary.cancelled || ctx.cancel.load(Ordering::Relaxed) {
        let kept = staged.keep_interrupted().map_err(Error::Output)?;
        return Err(Error::CancelledKept {
            out: args.out.clone(),
            kept,
        });
    }
    let out = commit_out_dir(staged)?;
    if ctx.verbose() && simulated.frames_capped {
        eprintln!(
            "note: a ParaView frame every {} samples (at most {DEFAULT_MAX_FRAMES} by default); \
             set output.vtk_every = 1 in the scene for every sample",
            simulated.vtk_every
        );
    }
    if args.json {
        return print_json(&simulated.summary_json(what.name(), &summary, &out));
    }
    println!("{}", simulated.result_line(what.label(), &summary, &out));
    Ok(())
}

impl ModelKind {
    fn label(self) -> &'static str {
        match self {
            ModelKind::Dnurbs => "D-NURBS",
            ModelKind::Msm => "MSM",
        }
    }

    fn name(self) -> &'static str {
        match self {
            ModelKind::Dnurbs => "dnurbs",
            ModelKind::Msm => "msm",
        }
    }
}
