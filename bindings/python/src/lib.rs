//! `nurbspring._native`: the scene crate's API for Python.
//!
//! This module is thin on purpose: it takes scene text, msm.json text and little-endian `f64`
//! buffers, and gives back buffers, JSON text and plain values; the Python package
//! (`python/nurbspring/__init__.py`) turns them into NumPy arrays, SciPy matrices and dicts.
//! Long calls run on a worker thread with the GIL released; the calling thread polls Python's
//! signal handlers and sets the library's cancel flag on Ctrl-C.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

use nurbspring_scene::export::DofsFile;
use nurbspring_scene::msm_file::{MsmSetup, msm_setup_from_text, read_msm_file};
use nurbspring_scene::report::{Report, derived_msm_file};
use nurbspring_scene::run::{
    RunRequest, Simulated, SteadyRequest, simulate_dnurbs, simulate_msm, steady_state,
};
use nurbspring_scene::{
    Derivation, Error, ErrorKind, IntegratorKind, Method, MsmOverrides, Trajectory,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

create_exception!(
    nurbspring,
    InputError,
    PyValueError,
    "Bad input: a scene or msm.json that cannot be read or is invalid, or a refused argument. \
     The message names the file, the key (or argument) and the value, as the CLI prints it."
);
create_exception!(
    nurbspring,
    RunError,
    PyRuntimeError,
    "A run failed: a solver that did not converge, a simulation that diverged, an output that \
     could not be written."
);

/// The Python exception of a library error.
fn py_err(e: Error) -> PyErr {
    match e.kind() {
        ErrorKind::Input => InputError::new_err(e.to_string()),
        ErrorKind::Run => RunError::new_err(e.to_string()),
        ErrorKind::Cancelled => PyKeyboardInterrupt::new_err("interrupted"),
    }
}

/// A refused argument, worded as the CLI words a refused option.
fn bad_argument(name: &str, value: impl std::fmt::Display, message: impl Into<String>) -> PyErr {
    py_err(Error::option(name, value, message))
}

/// Runs `job` on a worker thread with the GIL released. Every 50 ms the calling thread runs
/// Python's signal handlers; when one raises (Ctrl-C: `KeyboardInterrupt`), the cancel flag
/// given to `job` is set, the worker is waited for, and the exception is returned.
fn run_blocking<T: Send>(
    py: Python<'_>,
    job: impl FnOnce(Arc<AtomicBool>) -> T + Send,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&cancel);
    std::thread::scope(|s| {
        let (tx, rx) = channel();
        s.spawn(move || {
            let _ = tx.send(job(flag));
        });
        let mut rx = rx;
        loop {
            let (back, got) = py.allow_threads(move || {
                let got = rx.recv_timeout(Duration::from_millis(50));
                (rx, got)
            });
            rx = back;
            match got {
                Ok(value) => return Ok(value),
                // The worker panicked: the scope re-raises its panic when it ends.
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err("the worker thread panicked"));
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
            if let Err(e) = py.check_signals() {
                cancel.store(true, Ordering::Relaxed);
                py.allow_threads(move || {
                    let _ = rx.recv();
                });
                return Err(e);
            }
        }
    })
}

/// A progress callback: a percentage on stderr when `enabled`, nothing otherwise.
fn progress_printer(enabled: bool, label: &'static str) -> impl FnMut(usize, usize) + Send {
    let mut last = usize::MAX;
    move |done, total| {
        if !enabled || total == 0 {
            return;
        }
        let percent = done.min(total) * 100 / total;
        if percent != last {
            last = percent;
            eprint!("\r{label}: {percent:3}%");
            if percent == 100 {
                eprintln!();
            }
        }
    }
}

/// Little-endian `f64` bytes.
fn f64_bytes<'py>(py: Python<'py>, values: impl IntoIterator<Item = f64>) -> Bound<'py, PyBytes> {
    let mut bytes = Vec::new();
    for x in values {
        bytes.extend_from_slice(&x.to_le_bytes());
    }
    PyBytes::new(py, &bytes)
}

/// Little-endian `i64` bytes.
fn index_bytes<'py>(
    py: Python<'py>,
    values: impl IntoIterator<Item = usize>,
) -> Bound<'py, PyBytes> {
    let mut bytes = Vec::new();
    for i in values {
        bytes.extend_from_slice(&(i as i64).to_le_bytes());
    }
    PyBytes::new(py, &bytes)
}

/// `f64` values of little-endian bytes.
fn f64_values(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("chunks of 8 bytes")))
        .collect()
}

/// JSON text of a serializable value (non-finite numbers become `null`, as in the CLI's files).
fn json_text<T: serde::Serialize + ?Sized>(value: &T) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| RunError::new_err(e.to_string()))
}

/// The integrator named `name`, or the CLI's refusal.
fn integrator(name: Option<&str>) -> PyResult<Option<IntegratorKind>> {
    name.map(|s| {
        IntegratorKind::parse(s).ok_or_else(|| {
            bad_argument(
                "integrator",
                s,
                format!(
                    "unknown integrator; expected one of {}",
                    nurbspring_scene::integrator_names(&IntegratorKind::ALL)
                ),
            )
        })
    })
    .transpose()
}

/// A scene file, read and validated (`nurbspring._native.Scene`).
#[pyclass(frozen, module = "nurbspring._native")]
struct Scene {
    inner: nurbspring_scene::Scene,
}

#[pymethods]
impl Scene {
    /// Reads and validates a scene file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let inner = nurbspring_scene::Scene::from_path(&path).map_err(|e| py_err(e.into()))?;
        Ok(Self { inner })
    }

    /// Parses and validates scene text; `name` stands for the file in messages.
    #[staticmethod]
    fn from_toml(text: &str, name: &str) -> PyResult<Self> {
        let inner = nurbspring_scene::Scene::from_str(text, name).map_err(|e| py_err(e.into()))?;
        Ok(Self { inner })
    }

    /// Scene from JSON text of the same tables and keys as the TOML file.
    #[staticmethod]
    fn from_json(text: &str, name: &str) -> PyResult<Self> {
        let value: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| bad_argument("scene", "(dict)", e.to_string()))?;
        let toml_value = toml::Value::try_from(&value)
            .map_err(|e| bad_argument("scene", "(dict)", e.to_string()))?;
        let text = toml::to_string(&toml_value)
            .map_err(|e| bad_argument("scene", "(dict)", e.to_string()))?;
        Self::from_toml(&text, name)
    }

    /// The paper's scene (Section IV).
    #[staticmethod]
    fn paper() -> PyResult<Self> {
        let inner = nurbspring_scene::Scene::paper().map_err(|e| py_err(e.into()))?;
        Ok(Self { inner })
    }

    /// The file (or name) the scene came from.
    #[getter]
    fn path(&self) -> String {
        self.inner.path.display().to_string()
    }

    /// The scene as TOML text that reads back to an equal scene.
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    /// "surface" or "curve".
    #[getter]
    fn kind(&self) -> &'static str {
        match self.inner.geometry {
            nurbspring_scene::GeometrySpec::Surface(_) => "surface",
            nurbspring_scene::GeometrySpec::Curve(_) => "curve",
        }
    }

    /// Parameter domain: `((u0, u1), (v0, v1))` of a surface, `((u0, u1), (0, 0))` of a curve.
    fn domain(&self) -> PyResult<((f64, f64), (f64, f64))> {
        match self.inner.geometry {
            nurbspring_scene::GeometrySpec::Surface(_) => Ok(self
                .inner
                .to_surface()
                .map_err(|e| py_err(e.into()))?
                .domain()),
            nurbspring_scene::GeometrySpec::Curve(_) => {
                let c = self.inner.to_curve().map_err(|e| py_err(e.into()))?;
                Ok((c.domain(), (0.0, 0.0)))
            }
        }
    }

    /// Surface points and derivatives up to `order` at `(u[i], v[i])` (little-endian `f64`
    /// buffers): a list of `(name, buffer of N × 3)`, names `point`, `u`, `v`, `uu`, `uv`, `vv`.
    fn evaluate_surface<'py>(
        &self,
        py: Python<'py>,
        u: &[u8],
        v: &[u8],
        order: usize,
    ) -> PyResult<Vec<(&'static str, Bound<'py, PyBytes>)>> {
        if order > 2 {
            return Err(bad_argument("derivatives", order, "must be 0, 1 or 2"));
        }
        let surface = self.inner.to_surface().map_err(|e| py_err(e.into()))?;
        let params: Vec<(f64, f64)> = f64_values(u).into_iter().zip(f64_values(v)).collect();
        let d = py
            .allow_threads(|| surface.derivatives_batch(&params, order))
            .map_err(|e| bad_argument("(u, v)", "", e.to_string()))?;
        let names: &[&'static str] = match order {
            0 => &["point"],
            1 => &["point", "u", "v"],
            _ => &["point", "u", "v", "uu", "uv", "vv"],
        };
        Ok(names
            .iter()
            .map(|&name| {
                let pick = |x: &nurbspring_scene::SurfaceDerivatives| match name {
                    "point" => x.point,
                    "u" => x.u,
                    "v" => x.v,
                    "uu" => x.uu,
                    "uv" => x.uv,
                    _ => x.vv,
                };
                (name, f64_bytes(py, d.iter().flat_map(pick)))
            })
            .collect())
    }

    /// Curve points and derivatives up to `order` at `u[i]`: names `point`, `u`, `uu`.
    fn evaluate_curve<'py>(
        &self,
        py: Python<'py>,
        u: &[u8],
        order: usize,
    ) -> PyResult<Vec<(&'static str, Bound<'py, PyBytes>)>> {
        if order > 2 {
            return Err(bad_argument("derivatives", order, "must be 0, 1 or 2"));
        }
        let curve = self.inner.to_curve().map_err(|e| py_err(e.into()))?;
        let us = f64_values(u);
        let d = py
            .allow_threads(|| curve.derivatives_batch(&us, order))
            .map_err(|e| bad_argument("u", "", e.to_string()))?;
        let names: &[&'static str] = match order {
            0 => &["point"],
            1 => &["point", "u"],
            _ => &["point", "u", "uu"],
        };
        Ok(names
            .iter()
            .map(|&name| {
                let pick = |x: &nurbspring_scene::CurveDerivatives| match name {
                    "point" => x.point,
                    "u" => x.u,
                    _ => x.uu,
                };
                (name, f64_bytes(py, d.iter().flat_map(pick)))
            })
            .collect())
    }
}

/// CSC of `a` transposed, that is CSR of `a`: `(nrows, ncols, indptr, indices, data)`.
fn csr<'py>(
    py: Python<'py>,
    a: &nurbspring_scene::SparseMatrix,
) -> Bound<'py, pyo3::types::PyTuple> {
    let t = a.transpose();
    pyo3::types::PyTuple::new(
        py,
        [
            a.nrows().into_pyobject(py).expect("int").into_any(),
            a.ncols().into_pyobject(py).expect("int").into_any(),
            index_bytes(py, t.col_ptr().iter().copied()).into_any(),
            index_bytes(py, t.row_idx().iter().copied()).into_any(),
            f64_bytes(py, t.values().iter().copied()).into_any(),
        ],
    )
    .expect("a tuple of five")
}

/// The scene's D-NURBS matrices: `{"M", "D", "K": (nrows, ncols, indptr, indices, data) of
/// CSR, "f": buffer, "dofs": JSON text of dofs.json}`.
#[pyfunction]
fn matrices<'py>(py: Python<'py>, scene: &Scene) -> PyResult<Bound<'py, PyDict>> {
    let model = run_blocking(py, |_| scene.inner.build_dnurbs())?.map_err(py_err)?;
    let m = model.matrices();
    let dofs = DofsFile::of(&model);
    let out = PyDict::new(py);
    out.set_item("M", csr(py, &m.mass))?;
    out.set_item("D", csr(py, &m.damping))?;
    out.set_item("K", csr(py, &m.stiffness))?;
    out.set_item("f", f64_bytes(py, m.force.iter().copied()))?;
    out.set_item("dofs", json_text(&dofs)?)?;
    out.set_item(
        "warnings",
        model.quadrature().warning().into_iter().collect::<Vec<_>>(),
    )?;
    Ok(out)
}

/// The lowest `count` angular frequencies [rad/s] of the constrained D-NURBS.
#[pyfunction]
fn modes<'py>(py: Python<'py>, scene: &Scene, count: usize) -> PyResult<Bound<'py, PyBytes>> {
    if count == 0 {
        return Err(bad_argument("count", 0, "must be at least 1"));
    }
    let scene = &scene.inner;
    let omega = run_blocking(py, |_| -> Result<Vec<f64>, Error> {
        let model = scene.build_dnurbs()?;
        let modes = model
            .modes(count)
            .map_err(|e| Error::model(&scene.path, None, e))?;
        Ok(modes.omega)
    })?
    .map_err(py_err)?;
    Ok(f64_bytes(py, omega))
}

/// The equilibrium under the scene's loads (`nurbspring steady`): `load_steps` recorded
/// levels along the path (the shell's Newton path), the linearization at rest with `linear`.
#[pyfunction]
#[pyo3(signature = (scene, load_steps=1, linear=false, progress=false))]
fn steady<'py>(
    py: Python<'py>,
    scene: &Scene,
    load_steps: usize,
    linear: bool,
    progress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let scene = &scene.inner;
    let steady = run_blocking(py, |cancel| {
        let request = SteadyRequest {
            load_steps,
            linear,
            cancel: Some(cancel),
        };
        let mut bar = progress_printer(progress, "steady");
        let mut on_level = |lambda: f64| bar((lambda * 100.0).round() as usize, 100);
        steady_state(scene, &request, &mut on_level)
    })?
    .map_err(py_err)?;
    let out = PyDict::new(py);
    out.set_item("p", f64_bytes(py, steady.p.iter().copied()))?;
    out.set_item("dofs_per_point", steady.model.matrices().dofs_per_point)?;
    out.set_item("probes", json_text(&steady.probes)?)?;
    out.set_item("path", json_text(&steady.path)?)?;
    out.set_item("equations", steady.equations)?;
    out.set_item("iterations", steady.iterations)?;
    out.set_item("increments", steady.increments)?;
    out.set_item("relative_residual", steady.residual)?;
    out.set_item("warnings", steady.warnings.clone())?;
    Ok(out)
}

/// A run's samples as a dict of buffers and values.
fn run_dict<'py>(py: Python<'py>, run: &Simulated) -> PyResult<Bound<'py, PyDict>> {
    let traj: &Trajectory = &run.trajectory;
    let out = PyDict::new(py);
    out.set_item("t", f64_bytes(py, traj.t.iter().copied()))?;
    out.set_item("n_probes", traj.probes.len())?;
    let samples = traj.t.len();
    out.set_item(
        "probes",
        f64_bytes(
            py,
            (0..samples).flat_map(|s| traj.probes.iter().flat_map(move |p| p[s])),
        ),
    )?;
    out.set_item("kinetic", f64_bytes(py, traj.energy.iter().map(|e| e[0])))?;
    out.set_item("elastic", f64_bytes(py, traj.energy.iter().map(|e| e[1])))?;
    // `+ 0.0` as energy.csv writes it: an unloaded model's `−0` load potential is 0.
    out.set_item(
        "external",
        f64_bytes(py, traj.energy.iter().map(|e| e[2] + 0.0)),
    )?;
    out.set_item(
        "total",
        f64_bytes(py, traj.energy.iter().map(|e| e[0] + e[1] + e[2])),
    )?;
    out.set_item("integrator", run.integrator.to_string())?;
    out.set_item("substeps", run.substeps)?;
    out.set_item("dt", run.dt)?;
    out.set_item("t_end", run.t_end)?;
    out.set_item("stopped", traj.stopped.clone())?;
    out.set_item("halved_steps", traj.halved_steps)?;
    out.set_item("warnings", run.warnings.clone())?;
    Ok(out)
}

/// Simulates the scene's D-NURBS (`model = "dnurbs"`) or its MSM (`"msm"`).
#[pyfunction]
#[pyo3(signature = (scene, model, integrator=None, dt=None, t_end=None, force_unstable=false, progress=false))]
fn simulate_scene<'py>(
    py: Python<'py>,
    scene: &Scene,
    model: &str,
    integrator: Option<&str>,
    dt: Option<f64>,
    t_end: Option<f64>,
    force_unstable: bool,
    progress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let integrator = self::integrator(integrator)?;
    let scene = &scene.inner;
    let msm = match model {
        "dnurbs" => false,
        "msm" => true,
        other => {
            return Err(bad_argument(
                "model",
                other,
                "unknown model; expected one of dnurbs, msm",
            ));
        }
    };
    let simulated = run_blocking(py, |cancel| -> Result<Simulated, Error> {
        let request = RunRequest {
            dt,
            t_end,
            integrator,
            force_unstable,
            cancel: Some(cancel),
        };
        let mut bar = progress_printer(progress, "simulate");
        let (sim, outcome) = if msm {
            let setup = scene.msm_setup(&MsmOverrides::default())?;
            simulate_msm(&setup, &request, None, &mut bar)?
        } else {
            simulate_dnurbs(scene, &request, None, &mut bar)?
        };
        outcome?;
        Ok(sim)
    })?
    .map_err(py_err)?;
    run_dict(py, &simulated)
}

/// A mass-spring model ready to run (`nurbspring._native.MassSpring`).
#[pyclass(frozen, module = "nurbspring._native")]
struct MassSpring {
    setup: MsmSetup,
}

#[pymethods]
impl MassSpring {
    /// Reads an msm.json file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let setup = read_msm_file(&path, &MsmOverrides::default()).map_err(py_err)?;
        Ok(Self { setup })
    }

    /// msm.json text; `name` stands for the file in messages.
    #[staticmethod]
    fn from_json(text: &str, name: &str) -> PyResult<Self> {
        let setup =
            msm_setup_from_text(text, Path::new(name), &MsmOverrides::default()).map_err(py_err)?;
        Ok(Self { setup })
    }

    /// The MSM of a scene's `[msm]` section.
    #[staticmethod]
    fn from_scene(scene: &Scene) -> PyResult<Self> {
        let setup = scene
            .inner
            .msm_setup(&MsmOverrides::default())
            .map_err(py_err)?;
        Ok(Self { setup })
    }

    /// The model as msm.json text (nodes, springs, elements, gravity, grid).
    fn to_json(&self) -> PyResult<String> {
        json_text(&self.setup.model.lattice().to_file())
    }

    /// Probe nodes, the node nearest the centre first.
    #[getter]
    fn probe_nodes(&self) -> Vec<usize> {
        self.setup.probe_nodes.clone()
    }

    /// `(dt, t_end, integrator)` the model runs with by default.
    #[getter]
    fn run_settings(&self) -> (f64, f64, String) {
        let r = &self.setup.run;
        (r.dt, r.t_end, r.integrator.to_string())
    }

    /// Largest angular frequency [rad/s] and the explicit integrators' critical step [s].
    fn stability(&self) -> PyResult<(f64, f64)> {
        let s = self
            .setup
            .model
            .stability()
            .map_err(|e| py_err(Error::model(&self.setup.path, None, e)))?;
        Ok((s.omega_max, s.dt_critical))
    }

    /// Simulates the model.
    #[pyo3(signature = (integrator=None, dt=None, t_end=None, force_unstable=false, progress=false))]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        integrator: Option<&str>,
        dt: Option<f64>,
        t_end: Option<f64>,
        force_unstable: bool,
        progress: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let integrator = self::integrator(integrator)?;
        let setup = &self.setup;
        let simulated = run_blocking(py, |cancel| -> Result<Simulated, Error> {
            let request = RunRequest {
                dt,
                t_end,
                integrator,
                force_unstable,
                cancel: Some(cancel),
            };
            let mut bar = progress_printer(progress, "simulate");
            let (sim, outcome) = simulate_msm(setup, &request, None, &mut bar)?;
            outcome?;
            Ok(sim)
        })?
        .map_err(py_err)?;
        run_dict(py, &simulated)
    }
}

/// The samples of both central nodes: `(t, dnurbs, msm)` buffers, `T × 3` each.
fn central_node<'py>(
    py: Python<'py>,
    d: &Derivation,
) -> (
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
) {
    let t = &d.dnurbs_trajectory.t;
    let (a, b) = (&d.dnurbs_trajectory.probes[0], &d.msm_trajectory.probes[0]);
    let n = t.len().min(a.len()).min(b.len());
    (
        f64_bytes(py, t[..n].iter().copied()),
        f64_bytes(py, a[..n].iter().flat_map(|p| *p)),
        f64_bytes(py, b[..n].iter().flat_map(|p| *p)),
    )
}

/// The outputs of a derivation: report.json and msm.json as JSON text, the central node.
fn derivation_dict<'py>(
    py: Python<'py>,
    label: &str,
    scene: &nurbspring_scene::Scene,
    d: &Derivation,
    paper: Option<&nurbspring_scene::PaperReport>,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("report", json_text(&Report::new(label, scene, d, paper))?)?;
    let msm = derived_msm_file(label, scene, d)
        .map(|f| json_text(&f))
        .transpose()?;
    out.set_item("msm", msm)?;
    out.set_item("central_node", central_node(py, d))?;
    out.set_item("warnings", d.warnings.clone())?;
    Ok(out)
}

/// Derives the MSM of a scene (`derivation`: modal, paper, excitation or reduction; default:
/// the scene's `fit.derivation`).
#[pyfunction]
#[pyo3(signature = (scene, derivation=None, progress=false))]
fn derive<'py>(
    py: Python<'py>,
    scene: &Scene,
    derivation: Option<&str>,
    progress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let scene = &scene.inner;
    let requested = derivation
        .map(|s| {
            Method::parse(s).ok_or_else(|| {
                bad_argument(
                    "derivation",
                    s,
                    format!(
                        "unknown derivation; expected one of {}",
                        Method::ALL.map(Method::name).join(", ")
                    ),
                )
            })
        })
        .transpose()?;
    let choice = scene.choose_derivation(requested.map(|m| (m, "derivation")));
    if scene.derives_from_shell(&choice) {
        return derive_springs(py, scene, &choice);
    }
    let derived = run_blocking(py, |cancel| -> Result<Derivation, Error> {
        let mut bar = progress_printer(progress, "mass scan");
        Ok(scene.derive(choice, Some(cancel), &mut bar)?.0)
    })?
    .map_err(py_err)?;
    let label = scene.path.display().to_string();
    derivation_dict(py, &label, scene, &derived, None)
}

/// The derivation of a Kirchhoff–Love scene: report.json and msm.json as the CLI writes them
/// (a reduction: report.json, no msm.json) (no central-node series: its runs compare every node).
fn derive_springs<'py>(
    py: Python<'py>,
    scene: &nurbspring_scene::Scene,
    choice: &nurbspring_scene::DerivationChoice,
) -> PyResult<Bound<'py, PyDict>> {
    use nurbspring_scene::springs_report::{
        ShellReductionReport, SpringsReport, reduce_shell, springs_msm_file,
    };
    let label = scene.path.display().to_string();
    let out = PyDict::new(py);
    if choice.method == Method::Reduction {
        let r = run_blocking(py, |cancel| reduce_shell(scene, choice, Some(cancel)))?
            .map_err(py_err)?;
        out.set_item("report", json_text(&ShellReductionReport::new(&label, &r))?)?;
        // A node reduction has no msm.json (as the tension plate's).
        out.set_item("msm", py.None())?;
    } else {
        let d = run_blocking(py, |cancel| {
            nurbspring_scene::springs_report::derive_springs(
                scene,
                choice,
                Some(cancel),
                &mut |_| {},
            )
        })?
        .map_err(py_err)?;
        out.set_item("report", json_text(&SpringsReport::new(&label, &d))?)?;
        out.set_item("msm", json_text(&springs_msm_file(&label, scene, &d))?)?;
    }
    let empty = || f64_bytes(py, std::iter::empty());
    out.set_item("central_node", (empty(), empty(), empty()))?;
    out.set_item("warnings", Vec::<String>::new())?;
    Ok(out)
}

/// The paper's experiment (Section IV) with its built-in scene.
#[pyfunction]
#[pyo3(signature = (progress=false))]
fn paper(py: Python<'_>, progress: bool) -> PyResult<Bound<'_, PyDict>> {
    let scene = nurbspring_scene::Scene::paper().map_err(|e| py_err(e.into()))?;
    let (derivation, report) = run_blocking(py, |cancel| {
        let mut bar = progress_printer(progress, "mass scan");
        scene.reproduce_paper(Some(cancel), &mut bar)
    })?
    .map_err(py_err)?;
    derivation_dict(
        py,
        nurbspring_scene::paper::PAPER_LABEL,
        &scene,
        &derivation,
        Some(&report),
    )
}

/// The native module of the `nurbspring` package.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<MassSpring>()?;
    m.add_function(wrap_pyfunction!(matrices, m)?)?;
    m.add_function(wrap_pyfunction!(modes, m)?)?;
    m.add_function(wrap_pyfunction!(steady, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_scene, m)?)?;
    m.add_function(wrap_pyfunction!(derive, m)?)?;
    m.add_function(wrap_pyfunction!(paper, m)?)?;
    Ok(())
}
