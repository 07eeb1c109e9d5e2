//! Simulations of a scene's D-NURBS or of an MSM, with their outputs: `trajectory.csv` (the
//! probes over time), `energy.csv`, and a ParaView series (`surface.pvd` / `lattice.pvd` with
//! one frame file per recorded frame).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_derive::{DeriveError, Omega, Recording, Trajectory, Watched, record};
use nurbspring_dnurbs::DnurbsModel;
use nurbspring_io::output::write_csv;
use nurbspring_io::vtk::PvdSeries;
use nurbspring_msm::MsmModel;
use nurbspring_sim::{
    IntegratorKind, RunOptions, RunSummary, Schedule, SimError, StabilityLimit, check_time,
    step_count,
};

use crate::export::{control_net_grid, write_geometry_frame_with, write_lattice_frame};
use crate::msm_file::MsmSetup;
use crate::spec::default_frame_every;
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
    /// Its steps per Δt (more than 1: an explicit scheme kept below its stability limit,
    /// [`explicit_schedule`]).
    pub substeps: usize,
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Probe positions and energies of every recorded sample.
    pub trajectory: Trajectory,
    /// The ParaView series: `surface.pvd`, `curve.pvd` or `lattice.pvd`.
    pub pvd: String,
    /// The ParaView frames written, `(t, file name)`.
    pub frames: Vec<(f64, String)>,
    /// The D-NURBS control-net frames (`control_net.pvd`), one per frame.
    pub control_net_frames: Vec<(f64, String)>,
    /// A frame was written every `vtk_every` samples.
    pub vtk_every: usize,
    /// True when `vtk_every > 1` was chosen by default (no `output.vtk_every`) to keep the
    /// frame count at most [`crate::spec::DEFAULT_MAX_FRAMES`].
    pub frames_capped: bool,
    /// The run's summary (steps taken, cancellation).
    pub summary: Option<RunSummary>,
    /// Warnings about the model (e.g. the quadrature's estimated error) or the run (an explicit
    /// integrator run in substeps or replaced by an implicit one, [`explicit_schedule`]).
    pub warnings: Vec<String>,
    /// An MSM's explicit stability limit at its initial state.
    pub stability: Option<StabilityLimit>,
    /// Where each probe is, as `trajectory.csv`'s header says it: `u=0.5;v=0.5` (a D-NURBS
    /// probe, at the scene's parameters), `node=12;u=0.5;v=0.5` (an MSM's probe node, at the
    /// node's own parameters), `node=12` (a node without parameters).
    pub probe_labels: Vec<String>,
}

impl Simulated {
    /// What `simulate --json` prints: the settings the run used and what it wrote (`model`:
    /// `dnurbs` or `msm`).
    pub fn summary_json(&self, model: &str, summary: &RunSummary, out: &Path) -> serde_json::Value {
        let mut v = serde_json::json!({
            "model": model,
            "integrator": self.integrator.name(),
            "substeps": self.substeps,
            "dt": self.dt,
            "t_end": self.t_end,
            "steps": summary.steps,
            "t_final": summary.t_final,
            "halved_steps": summary.halved_steps,
            "samples": self.trajectory.t.len(),
            "frames": self.frames.len(),
            "pvd": self.pvd,
            "vtk_every": self.vtk_every,
            "warnings": self.warnings,
            "out": out.display().to_string(),
        });
        if let (Some(s), serde_json::Value::Object(map)) = (self.stability, &mut v) {
            map.insert("omega_max".into(), serde_json::json!(s.omega_max));
            map.insert("dt_critical".into(), serde_json::json!(s.dt_critical));
        }
        v
    }

    /// The result line of `simulate` (`model`: `D-NURBS` or `MSM`).
    pub fn result_line(&self, model: &str, summary: &RunSummary, out: &Path) -> String {
        format!(
            "{model} run ({}, {} steps, {} samples, {} ParaView frames) written to {}",
            Schedule {
                integrator: self.integrator,
                substeps: self.substeps
            },
            summary.steps,
            self.trajectory.t.len(),
            self.frames.len(),
            out.display()
        )
    }
}

/// The label of a probe at `(u, v)` (`v` left out on a curve, `node` for an MSM's node).
pub fn probe_label(node: Option<usize>, uv: Option<(f64, f64)>, curve: bool) -> String {
    let mut parts = Vec::new();
    if let Some(a) = node {
        parts.push(format!("node={a}"));
    }
    if let Some((u, v)) = uv {
        parts.push(format!("u={u}"));
        if !curve {
            parts.push(format!("v={v}"));
        }
    }
    parts.join(";")
}

/// The columns of `trajectory.csv`: `t`, then `probeP_c[LABEL]` for each probe `P` and
/// coordinate `c` (the label says where the probe is, [`Simulated::probe_labels`]).
pub fn trajectory_header(labels: &[String]) -> Vec<String> {
    let mut header = vec!["t".to_string()];
    for (p, label) in labels.iter().enumerate() {
        for c in ["x", "y", "z"] {
            if label.is_empty() {
                header.push(format!("probe{p}_{c}"));
            } else {
                header.push(format!("probe{p}_{c}[{label}]"));
            }
        }
    }
    header
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
        Error::refused(path, Some(key), "integrator", integrator, reason)
    }
}

/// Samples a run of `steps` steps records, keeping every `save_every`-th (and step 0).
fn samples(steps: usize, save_every: usize) -> usize {
    steps / save_every.max(1) + 1
}

/// Sample and frame bookkeeping shared by both models.
struct Frames<'a> {
    out: Option<&'a Path>,
    /// `surface` (`.vts`), `curve` or `lattice` (`.vtu`).
    stem: &'static str,
    /// Also a `control_net_NNNNNN.vtu` frame per frame (D-NURBS).
    control_net: bool,
    control_net_written: Vec<(f64, String)>,
    every: usize,
    /// `every` was chosen to write at most [`crate::spec::DEFAULT_MAX_FRAMES`] frames.
    capped: bool,
    samples: usize,
    written: Vec<(f64, String)>,
    error: Option<Error>,
}

impl Frames<'_> {
    /// Called once per recorded sample; writes a frame every `every` samples:
    /// `write(frame path, control-net frame path)` (the second is used with `control_net`).
    fn sample(&mut self, t: f64, write: impl FnOnce(&Path, &Path) -> Result<(), Error>) {
        let index = self.samples;
        self.samples += 1;
        let Some(out) = self.out else { return };
        if self.error.is_some() || !index.is_multiple_of(self.every) {
            return;
        }
        let ext = if self.stem == "surface" { "vts" } else { "vtu" };
        let name = format!("{}_{:06}.{ext}", self.stem, self.written.len());
        let net = format!("control_net_{:06}.vtu", self.written.len());
        match write(&out.join(&name), &out.join(&net)) {
            Ok(()) => {
                self.written.push((t, name));
                if self.control_net {
                    self.control_net_written.push((t, net));
                }
            }
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
    let probe_params = scene.probe_params()?;
    let probes = Omega::new(
        model.geometry(),
        &probe_params,
        scene.dnurbs.weights_as_dofs,
    )
    .map_err(|e| Error::model(&scene.path, Some("simulation.probes"), e))?;
    let initial = scene.initial_conditions().state(&model);
    let mut opts = RunOptions::new(dt, t_end, integrator);
    opts.cancel = request.cancel.clone();
    opts.rho_infinity = scene.simulation.rho_infinity;
    let steps = step_count(0.0, t_end, dt);
    let save_every = scene.simulation.save_every.max(1);
    let curve = matches!(model.geometry(), nurbspring_dnurbs::Geometry::Curve(_));
    let mut frames = Frames {
        out,
        stem: if curve { "curve" } else { "surface" },
        control_net: true,
        control_net_written: Vec::new(),
        every: scene.output.frame_every(samples(steps, save_every)),
        capped: scene.output.vtk_every.is_none(),
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
        Recording { every: save_every },
        &mut |s, p| {
            progress(s.step, steps);
            frames.sample(s.t, |path, net| {
                let v = model.full_velocity(s.v);
                write_geometry_frame_with(path, model.geometry(), p, Some(&v), dpp)?;
                Ok(control_net_grid(model.geometry(), p, &v, model.p0(), dpp).write(net)?)
            });
        },
    );
    let (mut simulated, outcome) = finish(
        scene.path.clone(),
        "simulation.dt",
        Schedule::plain(integrator),
        dt,
        t_end,
        trajectory,
        frames,
        result,
    )?;
    simulated.warnings = model.quadrature().warning().into_iter().collect();
    simulated
        .warnings
        .extend(energy_warning(&simulated.trajectory));
    simulated.probe_labels = probe_params
        .iter()
        .map(|&uv| probe_label(None, Some(uv), curve))
        .collect();
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
    let requested = request.integrator.unwrap_or(setup.run.integrator);
    let stability = setup
        .model
        .stability()
        .map_err(|e| Error::model(&setup.path, None, e))?;
    let mut warnings = Vec::new();
    let (schedule, limit) =
        explicit_schedule(&setup.model, &setup.initial.q, requested, dt, request)
            .map_err(|e| Error::model(&setup.path, None, e))?;
    if let Some(w) = schedule_warning(requested, dt, stability.dt_critical, schedule) {
        warnings.push(w);
    }
    let integrator = schedule.integrator;
    if let Some(reason) = MsmModel::integrator_problem(integrator) {
        return Err(integrator_error(
            &setup.path,
            "simulation.integrator",
            request,
            integrator,
            reason,
        ));
    }
    let mut opts = RunOptions::scheduled(dt, t_end, schedule, limit);
    opts.cancel = request.cancel.clone();
    opts.force_unstable = request.force_unstable;
    let steps = step_count(0.0, t_end, dt);
    let mut frames = Frames {
        out,
        stem: "lattice",
        control_net: false,
        control_net_written: Vec::new(),
        every: setup
            .vtk_every
            .unwrap_or_else(|| default_frame_every(samples(steps, setup.save_every))),
        capped: setup.vtk_every.is_none(),
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
            frames.sample(s.t, |path, _| write_lattice_frame(path, lattice, x));
        },
    );
    let key = if request.dt.is_some() {
        "--dt"
    } else {
        "simulation.dt"
    };
    let (mut simulated, outcome) = finish(
        setup.path.clone(),
        key,
        schedule,
        dt,
        t_end,
        trajectory,
        frames,
        result,
    )?;
    simulated.stability = Some(stability);
    simulated.warnings = warnings;
    let curve = lattice.grid.is_some_and(|(_, n_v)| n_v == 1);
    simulated.probe_labels = setup
        .probe_nodes
        .iter()
        .map(|&a| probe_label(Some(a), lattice.params.as_ref().map(|p| p[a]), curve))
        .collect();
    Ok((simulated, outcome))
}

/// How an MSM run with `requested` at `dt` from the positions `q` is integrated, with the
/// stability limit that holds for it: an explicit scheme from the file (not asked for with `--integrator`, no
/// `--force-unstable`) runs in the fewest substeps below the lattice's uniform limit, or with
/// [`nurbspring_sim::IMPLICIT_FALLBACK`] when that needs more than
/// [`nurbspring_sim::MAX_SUBSTEPS`] ([`Schedule::stable`]); everything else as asked, with
/// plain steps.
pub fn explicit_schedule(
    model: &MsmModel,
    q: &[f64],
    requested: IntegratorKind,
    dt: f64,
    request: &RunRequest,
) -> Result<(Schedule, Option<StabilityLimit>), nurbspring_sim::SimError> {
    if request.integrator.is_some() || request.force_unstable {
        return Ok((Schedule::plain(requested), None));
    }
    Schedule::stable(model, q, requested, dt)
}

/// The warning of a D-NURBS run whose total energy rose more than its dynamics can make it
/// ([`nurbspring_sim::EnergyWatch`]: its loads are dead and its damping only removes energy).
fn energy_warning(trajectory: &nurbspring_derive::Trajectory) -> Option<String> {
    let mut watch = nurbspring_sim::EnergyWatch::default();
    for &[kinetic, elastic, external] in &trajectory.energy {
        watch.observe(kinetic, elastic + external);
    }
    watch.unstable().then(|| {
        format!(
            "the run gains energy ({:.3} of its largest kinetic energy; its loads are dead and \
             its damping only removes energy): the integrator is unstable at this step, so the \
             motion is not the model's; lower simulation.rho_infinity (0.5 damps what the step \
             cannot resolve) or simulation.dt",
            watch.gain()
        )
    })
}

/// The warning of a run whose schedule differs from plain steps of the requested integrator.
pub fn schedule_warning(
    requested: IntegratorKind,
    dt: f64,
    dt_critical: f64,
    schedule: Schedule,
) -> Option<String> {
    if schedule.is_plain(requested) {
        return None;
    }
    let how = if schedule.integrator == requested {
        format!(
            "running it in {n} substeps of dt/{n}, below the limit on every configuration of \
             the lattice",
            n = schedule.substeps
        )
    } else {
        format!("running {} instead", schedule.integrator)
    };
    Some(format!(
        "{requested} is unstable at dt = {dt} s (dt_critical = {dt_critical:.4e} s); {how} \
         (--integrator {requested} --force-unstable runs plain steps anyway, --integrator \
         chooses another)"
    ))
}

#[allow(clippy::too_many_arguments)]
fn finish(
    path: PathBuf,
    key: &str,
    schedule: Schedule,
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
            integrator: schedule.integrator,
            substeps: schedule.substeps,
            dt,
            t_end,
            summary: outcome.as_ref().ok().cloned(),
            trajectory,
            vtk_every: frames.every,
            frames_capped: frames.capped && frames.every > 1,
            pvd: format!("{}.pvd", frames.stem),
            frames: frames.written,
            control_net_frames: frames.control_net_written,
            warnings: Vec::new(),
            stability: None,
            probe_labels: Vec::new(),
        },
        outcome,
    ))
}

/// The columns of `energy.csv`: time, kinetic energy, elastic energy (the springs' or the
/// surface's, without the load), the load's potential (`external`, zero at the initial state of
/// an MSM) and their sum.
pub const ENERGY_COLUMNS: [&str; 5] = ["t", "kinetic", "elastic", "external", "total"];

/// Writes `trajectory.csv`, `energy.csv`, the `.pvd` series ([`Simulated::pvd`]) and, for a
/// D-NURBS, `control_net.pvd`.
pub fn write_run(out: &Path, run: &Simulated) -> Result<(), Error> {
    let traj = &run.trajectory;
    let mut labels = run.probe_labels.clone();
    labels.resize(traj.probes.len(), String::new());
    let header = trajectory_header(&labels);
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
        &ENERGY_COLUMNS,
        traj.t
            .iter()
            .zip(&traj.energy)
            // `+ 0.0` writes an unloaded model's `−0` load potential as 0.
            .map(|(t, e)| vec![*t, e[0], e[1], e[2] + 0.0, e[0] + e[1] + e[2]]),
    )?;
    let mut series = PvdSeries::default();
    for (t, f) in &run.frames {
        series.push(*t, f.as_str());
    }
    series.write(out.join(&run.pvd))?;
    if !run.control_net_frames.is_empty() {
        let mut net = PvdSeries::default();
        for (t, f) in &run.control_net_frames {
            net.push(*t, f.as_str());
        }
        net.write(out.join("control_net.pvd"))?;
    }
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

/// One recorded load level of [`steady_state`]'s path: the load factor and the probes'
/// displacements (in the order of [`Steady::probes`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct LoadLevelProbes {
    /// The load factor λ (1: the scene's loads).
    pub lambda: f64,
    /// `c(p(λ)) − c(p(0))` at each probe.
    pub displacements: Vec<[f64; 3]>,
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
    /// Newton iterations, or iterates of the weights' fixed-point iteration (1: one linear
    /// solve).
    pub iterations: usize,
    /// Relative residual of the equilibrium at `p` (0 for one linear solve).
    pub residual: f64,
    /// Load increments of the equilibrium path (1 for one solve).
    pub increments: usize,
    /// Which equations were solved.
    pub equations: &'static str,
    /// The probes, the centre of the parameter domain first.
    pub probes: Vec<SteadyProbe>,
    /// The recorded load levels (`load_steps` of them; the last is λ = 1).
    pub path: Vec<LoadLevelProbes>,
}

/// How [`steady_state`] solves: load levels recorded, and for the shell whether to solve the
/// linearization at rest instead of the nonlinear equilibrium.
#[derive(Clone, Debug)]
pub struct SteadyRequest {
    /// Equal load levels recorded along the path (≥ 1; more than 1 with weights as unknowns is
    /// refused).
    pub load_steps: usize,
    /// Solve `K_T(p(0)) Δp = f` (the shell's tangent at rest) instead of the nonlinear
    /// equilibrium.
    pub linear: bool,
    /// Set to stop between Newton iterations (Ctrl-C).
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Default for SteadyRequest {
    fn default() -> Self {
        Self {
            load_steps: 1,
            linear: false,
            cancel: None,
        }
    }
}

/// Solves the steady state of the scene's D-NURBS (docs/math.md §3, §10.5): one linear solve
/// for the tension plate with constant weights, the nonlinear equilibrium
/// `K(p)(p − p_rest) = f_p(p)` with weights as unknowns
/// ([`DnurbsModel::steady_state_with`]), the shell's equilibrium path `f_int(p) = λ f` by
/// Newton with load increments ([`DnurbsModel::equilibrium_path`]; its linearization at rest
/// with `request.linear`). `progress(λ)` follows the path. Probe points are the surface
/// evaluated at each recorded level.
pub fn steady_state(
    scene: &Scene,
    request: &SteadyRequest,
    progress: &mut dyn FnMut(f64),
) -> Result<Steady, Error> {
    if request.load_steps == 0 {
        return Err(Error::Option {
            name: "--load-steps".into(),
            value: "0".into(),
            message: "at least one load level".into(),
        });
    }
    let model = scene.build_dnurbs()?;
    let shell = model.shell().is_some();
    if request.linear && !shell {
        return Err(Error::Option {
            name: "--linear".into(),
            value: "true".into(),
            message: format!(
                "applies to Kirchhoff–Love scenes; {} with material.model = \"{}\" is already {}",
                scene.path.display(),
                scene.material.name(),
                if scene.dnurbs.weights_as_dofs {
                    "solved by its own nonlinear iteration"
                } else {
                    "linear"
                }
            ),
        });
    }
    if scene.dnurbs.weights_as_dofs && request.load_steps > 1 {
        return Err(Error::Option {
            name: "--load-steps".into(),
            value: request.load_steps.to_string(),
            message: "with weights as unknowns (dnurbs.weights_as_dofs = true) the steady state \
                     is one fixed-point iteration at the full load; leave --load-steps out"
                .into(),
        });
    }
    let model_error = |e| Error::model(&scene.path, None, e);
    let (levels, iterations, residual, increments, equations): (Vec<(f64, Vec<f64>)>, _, _, _, _) =
        if scene.dnurbs.weights_as_dofs {
            let solved = model
                .steady_state_with(nurbspring_dnurbs::SteadySettings::default())
                .map_err(model_error)?;
            (
                vec![(1.0, solved.p)],
                solved.iterations,
                solved.residual,
                1,
                "nonlinear: K(p)(p - p_rest) = f(p), M, K, f at the solution",
            )
        } else if request.linear {
            let p = model.linearized_steady_state().map_err(model_error)?;
            let n = request.load_steps;
            let p0 = model.p0();
            let levels = (1..=n)
                .map(|l| {
                    let lambda = l as f64 / n as f64;
                    let p: Vec<f64> = p
                        .iter()
                        .zip(p0)
                        .map(|(a, b)| b + lambda * (a - b))
                        .collect();
                    (lambda, p)
                })
                .collect();
            (
                levels,
                1,
                0.0,
                1,
                "linear: K_T(p0) (p - p0) = f (the tangent at rest)",
            )
        } else {
            let cancel = request.cancel.clone();
            let stop = move || cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed));
            let path = model
                .equilibrium_path(
                    &nurbspring_dnurbs::PathSettings {
                        levels: request.load_steps,
                        ..Default::default()
                    },
                    &stop,
                    progress,
                )
                .map_err(|e| match e {
                    nurbspring_dnurbs::DnurbsError::Cancelled => Error::Cancelled,
                    e => model_error(e),
                })?;
            let residual = path.levels.last().map_or(0.0, |l| l.residual);
            (
                path.levels.into_iter().map(|l| (l.lambda, l.p)).collect(),
                path.iterations,
                residual,
                path.increments,
                if shell {
                    "nonlinear: f_int(p) = f (Kirchhoff-Love shell, Newton with load increments)"
                } else {
                    "linear: K (p - p_rest) = f"
                },
            )
        };
    let params = scene.probe_params()?;
    let omega = Omega::new(model.geometry(), &params, scene.dnurbs.weights_as_dofs)
        .map_err(|e| Error::model(&scene.path, Some("simulation.probes"), e))?;
    let points = |p: &[f64]| {
        omega
            .positions(p)
            .map_err(|e| Error::model(&scene.path, None, e))
    };
    let before = points(model.p0())?;
    let displacements = |now: &[[f64; 3]]| -> Vec<[f64; 3]> {
        now.iter()
            .zip(&before)
            .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
            .collect()
    };
    let mut path = Vec::with_capacity(levels.len());
    for (lambda, p) in &levels {
        path.push(LoadLevelProbes {
            lambda: *lambda,
            displacements: displacements(&points(p)?),
        });
    }
    let p = levels.last().expect("at least one level").1.clone();
    let now = points(&p)?;
    let probes = params
        .iter()
        .zip(now.iter().zip(displacements(&now)))
        .map(|(&(u, v), (at, d))| SteadyProbe {
            u,
            v,
            point: *at,
            displacement: d,
        })
        .collect();
    Ok(Steady {
        warnings: model.quadrature().warning().into_iter().collect(),
        model,
        p,
        iterations,
        residual,
        increments,
        equations,
        probes,
        path,
    })
}

/// `load_path.csv`: the load factor λ and each probe's displacement at every recorded level of
/// a steady state's path, columns `lambda, probe<k>_dx[u=…;v=…], …_dy, …_dz`.
pub fn write_load_path(out: &Path, steady: &Steady) -> Result<(), Error> {
    let mut header = vec!["lambda".to_string()];
    for (k, probe) in steady.probes.iter().enumerate() {
        for c in ["dx", "dy", "dz"] {
            header.push(format!(
                "probe{k}_{c}[u={};v={}]",
                nurbspring_io::output::format_f64(probe.u),
                nurbspring_io::output::format_f64(probe.v)
            ));
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let rows = steady.path.iter().map(|level| {
        std::iter::once(level.lambda)
            .chain(level.displacements.iter().flat_map(|d| d.iter().copied()))
            .collect::<Vec<f64>>()
    });
    write_csv(out.join("load_path.csv"), &header, rows)?;
    Ok(())
}
