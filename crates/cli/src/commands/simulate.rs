//! `nurbspring simulate SCENE --model dnurbs|msm --out DIR`.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use anyhow::anyhow;
use clap::{Args, ValueEnum};
use nurbspring_sim::{IntegratorKind, RunOptions, Sample, SimError, simulate};

use crate::convert;
use crate::progress::Progress;
use crate::{CmdResult, Context, Failure, prepare_out_dir};

/// Which model to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModelKind {
    /// The D-NURBS surface or curve.
    Dnurbs,
    /// The scene's mass-spring lattice (or an msm.json file).
    Msm,
}

/// MSM parameters that override the scene's `[msm]` section.
#[derive(Args, Debug, Default, Clone)]
pub struct MsmOverrides {
    /// Structural spring constant.
    #[arg(long)]
    pub k_edge: Option<f64>,
    /// Shear spring constant.
    #[arg(long)]
    pub k_diag: Option<f64>,
    /// Bending spring constant.
    #[arg(long)]
    pub k_bend: Option<f64>,
    /// Node mass.
    #[arg(long)]
    pub mass: Option<f64>,
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
    /// backward-euler, newmark (MSM). Default: the scene's.
    #[arg(long)]
    integrator: Option<String>,
    /// Run an explicit integrator above its stability limit anyway.
    #[arg(long)]
    force_unstable: bool,
    #[command(flatten)]
    overrides: MsmOverrides,
}

/// Collected samples of a run.
struct Recorder {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
    energy: Vec<Vec<f64>>,
    frames: Vec<(f64, String)>,
    frame_error: Option<Failure>,
}

impl Recorder {
    fn new(n_probes: usize) -> Self {
        let mut header = vec!["t".to_string()];
        for p in 0..n_probes {
            for c in ["x", "y", "z"] {
                header.push(format!("probe{p}_{c}"));
            }
        }
        Self {
            header,
            rows: Vec::new(),
            energy: Vec::new(),
            frames: Vec::new(),
            frame_error: None,
        }
    }

    fn finish(self, out: &Path, pvd: &str) -> Result<(), Failure> {
        let io = |e: nurbspring_io::OutputError| Failure::run(e);
        let header: Vec<&str> = self.header.iter().map(String::as_str).collect();
        nurbspring_io::output::write_csv(out.join("trajectory.csv"), &header, self.rows)
            .map_err(io)?;
        nurbspring_io::output::write_csv(
            out.join("energy.csv"),
            &["t", "kinetic", "elastic", "total"],
            self.energy,
        )
        .map_err(io)?;
        crate::output::write_pvd(&out.join(pvd), &self.frames).map_err(io)?;
        if let Some(e) = self.frame_error {
            return Err(e);
        }
        Ok(())
    }
}

/// Runs the simulation and writes trajectory.csv, energy.csv and a ParaView series.
pub fn run(ctx: &Context, args: SimulateArgs) -> CmdResult {
    let out = match args.model {
        ModelKind::Dnurbs => run_dnurbs(ctx, &args)?,
        ModelKind::Msm => run_msm(ctx, &args)?,
    };
    if ctx.cancel.load(Ordering::Relaxed) {
        return Err(Failure::run(anyhow!(
            "interrupted by Ctrl-C; the samples computed so far are in {}",
            out.display()
        )));
    }
    Ok(())
}

fn check_time(dt: f64, t_end: f64) -> Result<(), Failure> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(Failure::input(anyhow!(
            "--dt must be positive and finite, got {dt}"
        )));
    }
    if !(t_end > 0.0 && t_end.is_finite()) {
        return Err(Failure::input(anyhow!(
            "--t-end must be positive and finite, got {t_end}"
        )));
    }
    if t_end / dt > 1e8 {
        return Err(Failure::input(anyhow!(
            "--t-end {t_end} / --dt {dt} asks for more than 10^8 steps"
        )));
    }
    Ok(())
}

fn parse_integrator(name: &str, allowed: &[IntegratorKind]) -> Result<IntegratorKind, Failure> {
    let kind = IntegratorKind::parse(name);
    match kind {
        Some(k) if allowed.contains(&k) => Ok(k),
        _ => Err(Failure::input(anyhow!(
            "--integrator {name}: expected one of {}",
            allowed
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// Outcome of `simulate`: divergence and instability are failures of the run (exit 1) after
/// the samples so far are written.
fn run_outcome(result: Result<nurbspring_sim::RunSummary, SimError>) -> Result<(), Failure> {
    match result {
        Ok(_) => Ok(()),
        Err(e @ SimError::Unstable { .. }) => Err(Failure::run(anyhow!(
            "{e} (pass --force-unstable to run anyway)"
        ))),
        Err(e @ (SimError::InvalidTimeStep { .. } | SimError::InvalidDuration { .. })) => {
            Err(Failure::input(e))
        }
        Err(e) => Err(Failure::run(e)),
    }
}

fn run_dnurbs(ctx: &Context, args: &SimulateArgs) -> Result<PathBuf, Failure> {
    let scene = convert::load_scene(&args.scene)?;
    let model = convert::dnurbs_model(&scene)?;
    let sim = convert::simulation(&scene)?;
    let dt = args.dt.unwrap_or(sim.dt);
    let t_end = args.t_end.unwrap_or(sim.t_end);
    check_time(dt, t_end)?;
    let integrator = match &args.integrator {
        Some(name) => parse_integrator(
            name,
            &[
                IntegratorKind::TerzopoulosQin,
                IntegratorKind::Newmark,
                IntegratorKind::Modal,
            ],
        )?,
        None => sim.dnurbs_integrator,
    };
    let out = prepare_out_dir(&args.out)?;
    let probes = convert::probe_matrix(&scene, &model)?;
    let n_probes = probes.nrows() / 3;
    let initial = convert::dnurbs_initial_state(&scene, &model)?;
    let mut rec = Recorder::new(n_probes);
    let n_steps = (t_end / dt).ceil() as u64;
    let bar = Progress::new(ctx.global.quiet, "D-NURBS", n_steps);
    let mut pos = vec![0.0; probes.nrows()];
    let (save_every, frame_every) = (sim.save_every, sim.vtk_every);
    let mut observe = |step: usize, t: f64, p: &[f64], kinetic: f64, potential: f64| {
        bar.set(step as u64);
        if !step.is_multiple_of(save_every) {
            return;
        }
        probes.mul_vec(p, &mut pos);
        let mut row = vec![t];
        row.extend_from_slice(&pos);
        rec.rows.push(row);
        rec.energy
            .push(vec![t, kinetic, potential, kinetic + potential]);
        if (rec.rows.len() - 1).is_multiple_of(frame_every) && rec.frame_error.is_none() {
            let name = format!("surface_{:06}.vts", rec.frames.len());
            match crate::output::write_geometry_frame(
                &out.join(&name),
                model.geometry(),
                p,
                model.matrices().dofs_per_point,
            ) {
                Ok(()) => rec.frames.push((t, name)),
                Err(e) => rec.frame_error = Some(e),
            }
        }
    };
    let result = if model.matrices().dofs_per_point == 4 {
        convert::run_rational(&model, initial, dt, t_end, &ctx.cancel, &mut observe)
    } else {
        let mut opts = RunOptions::new(dt, t_end, integrator);
        opts.cancel = Some(ctx.cancel.clone());
        let mut obs = |s: &Sample<'_>| {
            let p = model.full_coordinates(s.q);
            observe(s.step, s.t, &p, s.kinetic, s.potential);
        };
        run_outcome(simulate(&model, initial, &opts, &mut obs))
    };
    bar.finish();
    rec.finish(&out, "surface.pvd")?;
    result?;
    if !ctx.global.quiet {
        println!(
            "D-NURBS run ({}) written to {}",
            integrator.name(),
            out.display()
        );
    }
    Ok(out)
}

fn run_msm(ctx: &Context, args: &SimulateArgs) -> Result<PathBuf, Failure> {
    let (model, initial, setup) = convert::msm_model(&args.scene, &args.overrides)?;
    let dt = args.dt.unwrap_or(setup.dt);
    let t_end = args.t_end.unwrap_or(setup.t_end);
    check_time(dt, t_end)?;
    let integrator = match &args.integrator {
        Some(name) => parse_integrator(
            name,
            &[
                IntegratorKind::SymplecticEuler,
                IntegratorKind::VelocityVerlet,
                IntegratorKind::Rk4,
                IntegratorKind::BackwardEuler,
                IntegratorKind::Newmark,
            ],
        )?,
        None => setup.integrator,
    };
    let stability = model.stability().map_err(convert::msm_failure)?;
    println!(
        "stability: omega_max = {:.6e} rad/s, dt_critical = {:.6e} s (dt = {dt}{})",
        stability.omega_max,
        stability.dt_critical,
        if integrator.is_explicit() && dt >= stability.dt_critical {
            ", above the explicit limit"
        } else {
            ""
        }
    );
    let out = prepare_out_dir(&args.out)?;
    let n_probes = setup.probe_nodes.len();
    let mut rec = Recorder::new(n_probes);
    let n_steps = (t_end / dt).ceil() as u64;
    let bar = Progress::new(ctx.global.quiet, "MSM", n_steps);
    let mut opts = RunOptions::new(dt, t_end, integrator);
    opts.cancel = Some(ctx.cancel.clone());
    opts.force_unstable = args.force_unstable;
    let (save_every, frame_every) = (setup.save_every, setup.vtk_every);
    let lattice = model.lattice().clone();
    let mut obs = |s: &Sample<'_>| {
        bar.set(s.step as u64);
        if !s.step.is_multiple_of(save_every) {
            return;
        }
        let x = model.full_positions(s.q);
        let mut row = vec![s.t];
        for &a in &setup.probe_nodes {
            row.extend_from_slice(&x[3 * a..3 * a + 3]);
        }
        rec.rows.push(row);
        rec.energy
            .push(vec![s.t, s.kinetic, s.potential, s.kinetic + s.potential]);
        if (rec.rows.len() - 1).is_multiple_of(frame_every) && rec.frame_error.is_none() {
            let name = format!("lattice_{:06}.vtu", rec.frames.len());
            match crate::output::write_lattice_frame(&out.join(&name), &lattice, &x) {
                Ok(()) => rec.frames.push((s.t, name)),
                Err(e) => rec.frame_error = Some(e),
            }
        }
    };
    let result = run_outcome(simulate(&model, initial, &opts, &mut obs));
    bar.finish();
    rec.finish(&out, "lattice.pvd")?;
    result?;
    if !ctx.global.quiet {
        println!(
            "MSM run ({}) written to {}",
            integrator.name(),
            out.display()
        );
    }
    Ok(out)
}
