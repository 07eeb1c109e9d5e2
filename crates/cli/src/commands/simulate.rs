//! `nurbspring simulate SCENE --model dnurbs|msm --out DIR`.

use std::path::PathBuf;
use std::sync::atomic::Ordering;

use clap::{Args, ValueEnum};
use nurbspring_scene::run::{RunRequest, simulate_dnurbs, simulate_msm, write_run};
use nurbspring_scene::{Error, Scene};
use nurbspring_sim::IntegratorKind;

use crate::commands::{MsmFlags, flag, parse_integrator};
use crate::progress::Progress;
use nurbspring_scene::resources::{Job, Timing};

use crate::{CmdResult, Context, commit_out_dir, stage_out_dir};

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
    #[arg(long)]
    dt: Option<f64>,
    /// End time [s] (default: the scene's).
    #[arg(long)]
    t_end: Option<f64>,
    /// Integrator: terzopoulos-qin, newmark, modal (D-NURBS); symplectic-euler, verlet, rk4,
    /// backward-euler, newmark, modal (MSM; modal: linear MSMs). Default: the scene's.
    #[arg(long, value_parser = parse_integrator)]
    integrator: Option<IntegratorKind>,
    /// Run an explicit integrator above its stability limit anyway.
    #[arg(long)]
    force_unstable: bool,
    #[command(flatten)]
    overrides: MsmFlags,
}

/// Runs the simulation and writes trajectory.csv, energy.csv and a ParaView series.
pub fn run(ctx: &Context, args: SimulateArgs) -> CmdResult {
    let request = RunRequest {
        dt: args.dt,
        t_end: args.t_end,
        integrator: args.integrator,
        force_unstable: args.force_unstable,
        cancel: Some(ctx.cancel.clone()),
    };
    let timing = Timing {
        dt: args.dt,
        t_end: args.t_end,
    };
    let bar = Progress::new(ctx.global.quiet, "", 1);
    let mut progress = |step: usize, steps: usize| bar.update(step, steps);
    let (staged, simulated, outcome, pvd, what) = match args.model {
        ModelKind::Dnurbs => {
            let scene = Scene::from_path(&args.scene)?;
            ctx.check_resources(&scene, Job::SimulateDnurbs(timing), Some(&args.out))?;
            let staged = stage_out_dir(&args.out)?;
            let (sim, outcome) =
                simulate_dnurbs(&scene, &request, Some(staged.path()), &mut progress)?;
            (staged, sim, outcome, "surface.pvd", "D-NURBS")
        }
        ModelKind::Msm => {
            let setup = ctx.load_msm(
                &args.scene,
                &args.overrides.overrides(),
                &flag,
                Some((&args.out, timing)),
            )?;
            let s = setup
                .model
                .stability()
                .map_err(|e| Error::model(&setup.path, None, e))?;
            let dt = args.dt.unwrap_or(setup.run.dt);
            let integrator = args.integrator.unwrap_or(setup.run.integrator);
            println!(
                "stability: omega_max = {:.6e} rad/s, dt_critical = {:.6e} s (dt = {dt}{})",
                s.omega_max,
                s.dt_critical,
                if integrator.is_explicit() && dt >= s.dt_critical {
                    ", above the explicit limit"
                } else {
                    ""
                }
            );
            let staged = stage_out_dir(&args.out)?;
            let (sim, outcome) =
                simulate_msm(&setup, &request, Some(staged.path()), &mut progress)?;
            (staged, sim, outcome, "lattice.pvd", "MSM")
        }
    };
    bar.finish();
    for w in &simulated.warnings {
        eprintln!("warning: {w}");
    }
    // A failed run leaves the previous one in place (the staged folder is dropped).
    outcome?;
    write_run(staged.path(), &simulated, pvd)?;
    if ctx.cancel.load(Ordering::Relaxed) {
        let kept = staged.keep_interrupted().map_err(Error::Output)?;
        eprintln!(
            "interrupted: {} is as it was; the samples computed so far are in {}",
            args.out.display(),
            kept.display()
        );
        return Err(Error::Cancelled);
    }
    let out = commit_out_dir(staged)?;
    if ctx.verbose() {
        println!(
            "{what} run ({}) written to {}",
            simulated.integrator,
            out.display()
        );
    }
    Ok(())
}
