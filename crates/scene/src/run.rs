//! Simulations of a scene's D-NURBS or of an MSM, with their outputs: `trajectory.csv` (the
//! probes over time), `energy.csv`, and a ParaView series (`surface.pvd` / `lattice.pvd` with
//! one frame file per recorded frame).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nurbspring_derive::{DeriveError, Omega, Recording, Trajectory, Watched, record};
use nurbspring_dnurbs::DnurbsModel;
use nurbspring_io::output::write_csv;
use nurbspring_io::vtk::PvdSeries;
use nurbspring_msm::MsmModel;
use nurbspring_sim::{IntegratorKind, RunOptions, RunSummary, SimError, check_time, step_count};

use crate::export::{write_geometry_frame, write_lattice_frame};
use crate::msm_file::MsmSetup;
use crate::{Error, Scene};

/// What to change of the scene's (or file's) run settings.
#[derive(Clone, Debug, Default)]
pub struct RunRequest {
    /// Time step [s].
    pub dt: Option<f64>,
    /// End time [s].
    pub t_end: Option<f64>,
    /// Integrator.
    pub integrator: Option<IntegratorKind>,
    /// Run an explicit integrator above its stability limit anyway.
    pub force_unstable: bool,
    /// Stops the run after the current step when set.
    pub cancel: Option<Arc<AtomicBool>>,
}

/// The settings a run used, and what it recorded.
#[derive(Debug)]
pub struct Simulated {
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Probe positions and energies of every recorded sample.
    pub trajectory: Trajectory,
    /// The ParaView frames written, `(t, file name)`.
    pub frames: Vec<(f64, String)>,
    /// The run's summary (steps taken, cancellation).
    pub summary: Option<RunSummary>,
    /// Warnings about the model (e.g. the quadrature's estimated error).
    pub warnings: Vec<String>,
}

/// Where a value of a run came from: a key of the scene or file, or an option.
fn origin(requested: bool, flag: &str, key: &str) -> String {
    if requested {
        flag.to_string()
    } else {
        key.to_string()
    }
}

/// Time step and end time after `request`, checked by `check_time`; errors name the option
/// (`--dt`) or the key (`simulation.dt`) the value came from.
fn resolve_time(
    path: &Path,
    dt: f64,
    t_end: f64,
    request: &RunRequest,
) -> Result<(f64, f64), Error> {
    let (dt, t_end) = (request.dt.unwrap_or(dt), request.t_end.unwrap_or(t_end));
    check_time(dt, t_end, 0.0).map_err(|e| {
        let key = match e {
            SimError::InvalidTimeStep { .. } => {
                origin(request.dt.is_some(), "--dt", "simulation.dt")
            }
            _ => origin(request.t_end.is_some(), "--t-end", "simulation.t_end"),
        };
        if request.dt.is_some() || request.t_end.is_some() {
            Error::option(&key, if key == "--dt" { dt } else { t_end }, e.to_string())
        } else {
            Error::model(path, Some(&key), e)
        }
    })?;
    Ok((dt, t_end))
}

/// An integrator that does not apply: named by `--integrator` when the request chose it, by
/// the file's `key` otherwise.
fn integrator_error(
    path: &Path,
    key: &str,
    request: &RunRequest,
    integrator: IntegratorKind,
    reason: String,
) -> Error {
    if request.integrator.is_some() {
        Error::option("--integrator", integrator, reason)
    } else {
        Error::model(
            path,
            Some(key),
            DeriveError::InvalidOption {
                name: "integrator",
                value: integrator.to_string(),
                reason,
            },
        )
    }
}

/// Sample and frame bookkeeping shared by both models.
struct Frames<'a> {
    out: Option<&'a Path>,
    stem: &'static str,
    every: usize,
    samples: usize,
    written: Vec<(f64, String)>,
    error: Option<Error>,
}

impl Frames<'_> {
    /// Called once per recorded sample; writes a frame every `every` samples.
    fn sample(&mut self, t: f64, write: impl FnOnce(&Path) -> Result<(), Error>) {
        let index = self.samples;
        self.samples += 1;
        let Some(out) = self.out else { return };
        if self.error.is_some() || !index.is_multiple_of(self.every) {
            return;
        }
        let ext = if self.stem == "surface" { "vts" } else { "vtu" };
        let name = format!("{}_{:06}.{ext}", self.stem, self.written.len());
        match write(&out.join(&name)) {
            Ok(()) => self.written.push((t, name)),
            Err(e) => self.error = Some(e),
        }
    }
}

/// The error of a finished run: `Ok` when it ran to its end or was cancelled.
fn outcome(
    path: &Path,
    key: &str,
    result: Result<RunSummary, DeriveError>,
) -> Result<RunSummary, Error> {
    result.map_err(|e| {
        let input = e.kind() == nurbspring_sim::ErrorKind::Input;
        Error::model(path, input.then_some(key), e)
    })
}

/// Runs the scene's D-NURBS, writing frames into `out` when given. `progress(step, steps)`.
pub fn simulate_dnurbs(
    scene: &Scene,
    request: &RunRequest,
    out: Option<&Path>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Simulated, Result<RunSummary, Error>), Error> {
    let model: DnurbsModel = scene.build_dnurbs()?;
    let time = scene.time_settings();
    let (dt, t_end) = resolve_time(&scene.path, time.dt, time.t_end, request)?;
    let integrator = request.integrator.unwrap_or(time.dnurbs_integrator);
    if let Some(reason) =
        nurbspring_dnurbs::integrator_problem(integrator, &scene.material, &scene.dnurbs)
    {
        return Err(integrator_error(
            &scene.path,
            "simulation.dnurbs_integrator",
            request,
            integrator,
            reason,
        ));
    }
    let probes = Omega::new(
        model.geometry(),
        &scene.probe_params()?,
        scene.dnurbs.weights_as_dofs,
    )
    .map_err(|e| Error::model(&scene.path, Some("simulation.probes"), e))?;
    let initial = scene.initial_conditions().state(&model);
    let mut opts = RunOptions::new(dt, t_end, integrator);
    opts.cancel = request.cancel.clone();
    let steps = step_count(0.0, t_end, dt);
    let mut frames = Frames {
        out,
        stem: "surface",
        every: scene.output.vtk_every.max(1),
        samples: 0,
        written: Vec::new(),
        error: None,
    };
    let dpp = model.matrices().dofs_per_point;
    let (trajectory, result) = record(
        Watched::Dnurbs {
            model: &model,
            probes: &probes,
        },
        initial,
        &opts,
        Recording {
            every: scene.simulation.save_every.max(1),
        },
        &mut |s, p| {
            progress(s.step, steps);
            frames.sample(s.t, |path| {
                write_geometry_frame(path, model.geometry(), p, dpp)
            });
        },
    );
    let (mut simulated, outcome) = finish(
        scene.path.clone(),
        "simulation.dt",
        integrator,
        dt,
        t_end,
        trajectory,
        frames,
        result,
    )?;
    simulated.warnings = model.quadrature().warning().into_iter().collect();
    Ok((simulated, outcome))
}

/// Runs an MSM (of a scene or an msm.json), writing frames into `out` when given.
pub fn simulate_msm(
    setup: &MsmSetup,
    request: &RunRequest,
    out: Option<&Path>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Simulated, Result<RunSummary, Error>), Error> {
    let (dt, t_end) = resolve_time(&setup.path, setup.run.dt, setup.run.t_end, request)?;
    let integrator = request.integrator.unwrap_or(setup.run.integrator);
    if let Some(reason) = MsmModel::integrator_problem(integrator) {
        return Err(integrator_error(
            &setup.path,
            "simulation.integrator",
            request,
            integrator,
            reason,
        ));
    }
    let mut opts = RunOptions::new(dt, t_end, integrator);
    opts.cancel = request.cancel.clone();
    opts.force_unstable = request.force_unstable;
    let steps = step_count(0.0, t_end, dt);
    let mut frames = Frames {
        out,
        stem: "lattice",
        every: setup.vtk_every,
        samples: 0,
        written: Vec::new(),
        error: None,
    };
    let lattice = setup.model.lattice();
    let (trajectory, result) = record(
        Watched::Msm {
            model: &setup.model,
            nodes: &setup.probe_nodes,
        },
        setup.initial.clone(),
        &opts,
        Recording {
            every: setup.save_every,
        },
        &mut |s, x| {
            progress(s.step, steps);
            frames.sample(s.t, |path| write_lattice_frame(path, lattice, x));
        },
    );
    let key = if request.dt.is_some() {
        "--dt"
    } else {
        "simulation.dt"
    };
    finish(
        setup.path.clone(),
        key,
        integrator,
        dt,
        t_end,
        trajectory,
        frames,
        result,
    )
}

#[allow(clippy::too_many_arguments)]
fn finish(
    path: PathBuf,
    key: &str,
    integrator: IntegratorKind,
    dt: f64,
    t_end: f64,
    trajectory: Trajectory,
    frames: Frames<'_>,
    result: Result<RunSummary, DeriveError>,
) -> Result<(Simulated, Result<RunSummary, Error>), Error> {
    if let Some(e) = frames.error {
        return Err(e);
    }
    let outcome = outcome(&path, key, result);
    Ok((
        Simulated {
            integrator,
            dt,
            t_end,
            summary: outcome.as_ref().ok().cloned(),
            trajectory,
            frames: frames.written,
            warnings: Vec::new(),
        },
        outcome,
    ))
}

/// Writes `trajectory.csv`, `energy.csv` and the `.pvd` series (`pvd` is its file name).
pub fn write_run(out: &Path, run: &Simulated, pvd: &str) -> Result<(), Error> {
    let traj = &run.trajectory;
    let mut header = vec!["t".to_string()];
    for p in 0..traj.probes.len() {
        for c in ["x", "y", "z"] {
            header.push(format!("probe{p}_{c}"));
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let rows = (0..traj.t.len()).map(|s| {
        let mut row = vec![traj.t[s]];
        for probe in &traj.probes {
            row.extend_from_slice(&probe[s]);
        }
        row
    });
    write_csv(out.join("trajectory.csv"), &header, rows)?;
    write_csv(
        out.join("energy.csv"),
        &["t", "kinetic", "elastic", "total"],
        traj.t
            .iter()
            .zip(&traj.energy)
            .map(|(t, e)| vec![*t, e[0], e[1], e[0] + e[1]]),
    )?;
    let mut series = PvdSeries::default();
    for (t, f) in &run.frames {
        series.push(*t, f.as_str());
    }
    series.write(out.join(pvd))?;
    Ok(())
}

/// One probe of [`steady_state`]: its parameters, the surface point at rest and its
/// displacement from the initial surface.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SteadyProbe {
    /// Parameter u.
    pub u: f64,
    /// Parameter v.
    pub v: f64,
    /// `c(p_steady)` at `(u, v)`.
    pub point: [f64; 3],
    /// `c(p_steady) − c(p(0))` at `(u, v)`.
    pub displacement: [f64; 3],
}

/// The scene's D-NURBS at rest (paper eq. (8), docs/math.md §3).
#[derive(Clone, Debug)]
pub struct Steady {
    /// The model.
    pub model: DnurbsModel,
    /// Full generalized coordinates at rest.
    pub p: Vec<f64>,
    /// Warnings about the model (e.g. the quadrature's estimated error).
    pub warnings: Vec<String>,
    /// Iterates of the nonlinear solve (1: one linear solve, constant weights).
    pub iterations: usize,
    /// Relative residual of `K(p)(p − p_rest) = f_p(p)` at `p` (0 for constant weights).
    pub residual: f64,
    /// The probes, the centre of the parameter domain first.
    pub probes: Vec<SteadyProbe>,
}

/// Solves the steady state of the scene's D-NURBS: one linear solve with constant weights, the
/// nonlinear equilibrium `K(p)(p − p_rest) = f_p(p)` with weights as unknowns
/// ([`DnurbsModel::steady_state_with`]); probe points are the surface evaluated at that state.
pub fn steady_state(scene: &Scene) -> Result<Steady, Error> {
    let model = scene.build_dnurbs()?;
    let solved = model
        .steady_state_with(nurbspring_dnurbs::SteadySettings::default())
        .map_err(|e| Error::model(&scene.path, None, e))?;
    let params = scene.probe_params()?;
    let omega = Omega::new(model.geometry(), &params, scene.dnurbs.weights_as_dofs)
        .map_err(|e| Error::model(&scene.path, Some("simulation.probes"), e))?;
    let points = |p: &[f64]| {
        omega
            .positions(p)
            .map_err(|e| Error::model(&scene.path, None, e))
    };
    let (now, before) = (points(&solved.p)?, points(model.p0())?);
    let probes = params
        .iter()
        .zip(now.iter().zip(&before))
        .map(|(&(u, v), (at, b))| SteadyProbe {
            u,
            v,
            point: *at,
            displacement: [at[0] - b[0], at[1] - b[1], at[2] - b[2]],
        })
        .collect();
    Ok(Steady {
        warnings: model.quadrature().warning().into_iter().collect(),
        model,
        p: solved.p,
        iterations: solved.iterations,
        residual: solved.residual,
        probes,
    })
}
