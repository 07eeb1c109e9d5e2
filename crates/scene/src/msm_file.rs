//! `msm.json` ↔ runnable mass-spring models, and the MSM of a scene: everything
//! `simulate --model msm` and `stability` start from. The file's schema is
//! [`nurbspring_msm::MsmFile`], the one definition of the format.

use std::path::{Path, PathBuf};

use nurbspring_derive::{Method, Omega};
use nurbspring_dnurbs::Geometry;
use nurbspring_msm::{FileSimulation, MsmFile, MsmModel, SpringLattice};
use nurbspring_sim::{IntegratorKind, State};

use crate::build::MsmOverrides;
use crate::resources::{Job, Limits, Timing, format_bytes};
use crate::text_file::read_text;
use crate::{Error, Scene};

/// Largest `msm.json` read (256 MiB: a lattice of a few million nodes).
pub const MAX_MSM_FILE_BYTES: u64 = 256 << 20;

/// Run settings of an MSM when its file gives none.
pub const DEFAULT_RUN: FileSimulation = FileSimulation {
    dt: 0.01,
    t_end: 1.0,
    integrator: IntegratorKind::BackwardEuler,
};

/// An MSM ready to run: the model, its initial state, how to run it and what to watch.
#[derive(Debug)]
pub struct MsmSetup {
    /// The scene or msm.json it came from.
    pub path: PathBuf,
    /// True when it came from an msm.json file (its keys are then the file's).
    pub from_file: bool,
    /// The model.
    pub model: MsmModel,
    /// The initial state: rest positions (moved by the scene's initial displacement) and the
    /// initial velocities (`Ω ṗ(0)`, paper eq. (18), or the file's).
    pub initial: State,
    /// Time step, end time and integrator.
    pub run: FileSimulation,
    /// Probe nodes, the node nearest the centre of the parameter domain first.
    pub probe_nodes: Vec<usize>,
    /// Record a sample every n steps.
    pub save_every: usize,
    /// Write a ParaView frame every n samples; `None`: at most
    /// [`crate::spec::DEFAULT_MAX_FRAMES`] frames.
    pub vtk_every: Option<usize>,
}

/// True when `path` names an msm.json file (by its extension).
pub fn is_msm_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// The MSM of an msm.json file (by extension) or of a scene, with `overrides` applied.
pub fn load_msm(
    path: &Path,
    overrides: &MsmOverrides,
    flag: &dyn Fn(&str) -> String,
) -> Result<MsmSetup, Error> {
    overrides.validate(flag)?;
    if is_msm_file(path) {
        read_msm_file(path, overrides)
    } else {
        Scene::from_path(path)?.msm_setup(overrides)
    }
}

/// [`load_msm`], refused before anything is allocated when its estimate exceeds `limits`:
/// an msm.json by its size, a scene by its [`Job::SimulateMsm`] estimate (`run`: the output
/// folder and the timing of a simulation).
pub fn load_msm_within(
    path: &Path,
    overrides: &MsmOverrides,
    flag: &dyn Fn(&str) -> String,
    limits: &Limits,
    run: Option<(&Path, Timing)>,
) -> Result<MsmSetup, Error> {
    if is_msm_file(path) {
        // The model of an msm.json is built from the parsed file: its peak is proportional
        // to the file's size (31 bytes a byte measured on a 10⁶-node chain; 40 allowed).
        if let Ok(meta) = std::fs::metadata(path) {
            let need = (64u64 << 20).saturating_add(meta.len().saturating_mul(40));
            if need > limits.memory {
                return Err(Error::Resources {
                    path: path.to_path_buf(),
                    key: "(file size)".to_string(),
                    message: format!(
                        "a model of {} of msm.json needs an estimated {} of memory, above the limit of {} (raise it with --max-memory)",
                        format_bytes(meta.len()),
                        format_bytes(need),
                        format_bytes(limits.memory)
                    ),
                });
            }
        }
        return load_msm(path, overrides, flag);
    }
    overrides.validate(flag)?;
    let scene = Scene::from_path(path)?;
    let (out, timing) = run.map_or((None, Timing::default()), |(o, t)| (Some(o), t));
    scene.check_resources(Job::SimulateMsm(timing), limits, out)?;
    scene.msm_setup(overrides)
}

/// Reads an msm.json file (a regular file of at most [`MAX_MSM_FILE_BYTES`]).
pub fn read_msm_file(path: &Path, overrides: &MsmOverrides) -> Result<MsmSetup, Error> {
    let text = read_text(path, MAX_MSM_FILE_BYTES, "msm.json")?;
    msm_setup_from_text(&text, path, overrides)
}

/// The MSM of msm.json text; `path` names it in messages.
pub fn msm_setup_from_text(
    text: &str,
    path: &Path,
    overrides: &MsmOverrides,
) -> Result<MsmSetup, Error> {
    let bad = |source| Error::MsmFile {
        path: path.to_path_buf(),
        source: Box::new(source),
    };
    let file = MsmFile::from_json_str(text).map_err(|e| {
        if is_reduction_file(text) {
            return Error::Option {
                name: path.display().to_string(),
                value: "(reduction.json)".to_string(),
                message: REDUCTION_FILE.to_string(),
            };
        }
        bad(e)
    })?;
    let mut lattice = SpringLattice::from_file(&file).map_err(bad)?;
    lattice.set_constants(&overrides.constants);
    if let Some(m) = overrides.mass {
        lattice.set_mass(m);
    }
    let velocities = file.velocities().map_err(bad)?;
    let probe_nodes = match &file.probe_nodes {
        Some(nodes) if !nodes.is_empty() => {
            if let Some((k, &a)) = nodes
                .iter()
                .enumerate()
                .find(|&(_, &a)| a >= lattice.n_nodes())
            {
                return Err(bad(nurbspring_msm::MsmError::MissingNode {
                    of: "probe",
                    index: k,
                    node: a,
                    n_nodes: lattice.n_nodes(),
                }));
            }
            nodes.clone()
        }
        _ => vec![lattice_centre(&lattice)],
    };
    let model = MsmModel::new(lattice).map_err(bad)?;
    let initial = model.initial_state(&velocities);
    Ok(MsmSetup {
        path: path.to_path_buf(),
        from_file: true,
        model,
        initial,
        run: file.simulation.clone().unwrap_or(DEFAULT_RUN),
        probe_nodes,
        save_every: 1,
        vtk_every: None,
    })
}

/// Why `simulate` and `export` do not take a reduction.json, and what to do instead.
pub const REDUCTION_FILE: &str = "this is the `reduction` derivation's reduction.json, the exact \
     reduction of the D-NURBS onto the nodes (dense node-space matrices M_T, K_T: a linear model, \
     not a mass-spring model), which `simulate --model msm` and `export --format sofa|npz` do \
     not run. `derive` has already simulated it: its central_node.csv and report.json hold its \
     run against the D-NURBS (the reference any MSM is judged against). For a model to simulate \
     or export, derive an MSM: `nurbspring derive SCENE --out DIR` (modal) or `--derivation \
     paper` (springs), and use DIR/msm.json";

/// True when `text` is a reduction.json (`"kind": "…"` beside `"stiffness"` at the top level).
fn is_reduction_file(text: &str) -> bool {
    #[derive(serde::Deserialize)]
    struct Probe {
        kind: Option<serde::de::IgnoredAny>,
        stiffness: Option<serde::de::IgnoredAny>,
    }
    serde_json::from_str::<Probe>(text).is_ok_and(|p| p.kind.is_some() && p.stiffness.is_some())
}

/// The node nearest the centre of the nodes' parameters (or of the grid, or of the nodes'
/// bounding box), ties to the lowest index.
fn lattice_centre(lattice: &SpringLattice) -> usize {
    match &lattice.params {
        Some(params) => {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for &(u, v) in params {
                lo = [lo[0].min(u), lo[1].min(v)];
                hi = [hi[0].max(u), hi[1].max(v)];
            }
            lattice.node_nearest(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]))
        }
        None if lattice.grid.is_some() => lattice.node_nearest(0.5, 0.5),
        None => 0,
    }
}

impl Scene {
    /// The scene's MSM: the lattice sampled from its surface (`[msm]` with `overrides`), its
    /// initial state mapped by Ω (paper eqs. (11), (18)), the scene's run settings.
    ///
    /// The lattice's constants and node mass are the scene's (`[msm]`) or the overrides': a
    /// scene that leaves one out is refused ([`Scene::missing_msm_keys`]), since a lattice of
    /// placeholder constants is no model of anything.
    pub fn msm_setup(&self, overrides: &MsmOverrides) -> Result<MsmSetup, Error> {
        self.refuse_placeholders(overrides)?;
        self.msm_setup_unchecked(overrides)
    }

    /// The keys of `[msm]` that neither the scene nor `overrides` gives for its own lattice
    /// (`msm.k_edge`, `msm.k_diag`, `msm.k_bend` of the spring kinds it has, `msm.mass`).
    pub fn missing_msm_keys(&self, overrides: &MsmOverrides) -> Vec<String> {
        use nurbspring_msm::{Class, SpringKind};
        let kinds = [SpringKind::Structural, SpringKind::Shear, SpringKind::Bend];
        let mut out: Vec<String> = self
            .msm
            .spring_keys()
            .into_iter()
            .zip(kinds)
            .filter(|&((_, on, k), kind)| {
                on && k.is_none() && !overrides.constants.contains(Class::Spring(kind))
            })
            .map(|((key, _, _), _)| format!("msm.{key}"))
            .collect();
        if self.msm.mass.is_none() && overrides.mass.is_none() {
            out.push("msm.mass".to_string());
        }
        out
    }

    /// Refuses the scene's own lattice when `[msm]` (with `overrides`) leaves out a constant
    /// or the node mass, naming the keys and the command that derives them.
    pub fn refuse_placeholders(&self, overrides: &MsmOverrides) -> Result<(), Error> {
        let missing = self.missing_msm_keys(overrides);
        if missing.is_empty() {
            return Ok(());
        }
        let flags: Vec<String> = missing
            .iter()
            .map(|k| format!("--{}", k.trim_start_matches("msm.").replace('_', "-")))
            .collect();
        Err(Error::Missing {
            path: self.path.clone(),
            keys: missing.join(", "),
            message: format!(
                "not given, so the scene has no mass-spring model of its own (nurbspring \
                 writes none from placeholder constants). Derive one: `nurbspring derive {scene} \
                 --out DIR` (the {method} derivation; `--derivation paper` for a lattice of \
                 springs) writes DIR/msm.json, which `simulate DIR/msm.json --model msm` and \
                 `export DIR/msm.json --format sofa|npz` take; or set {keys} in [msm] (or {flags})",
                scene = self.path.display(),
                method = self.derivation().0.name(),
                keys = missing.join(", "),
                flags = flags.join(", "),
            ),
        })
    }

    /// [`Scene::msm_setup`] without the refusal of placeholder constants (`check` describes
    /// the lattice's shape with them).
    pub(crate) fn msm_setup_unchecked(&self, overrides: &MsmOverrides) -> Result<MsmSetup, Error> {
        let model = self.build_dnurbs()?;
        let options = self.lattice_options(Method::Paper, overrides)?;
        let lattice = match model.geometry() {
            Geometry::Surface(surface) => {
                SpringLattice::from_surface(surface, &options, model.fixed_points())
            }
            Geometry::Curve(curve) => {
                SpringLattice::from_curve(curve, &options, model.fixed_points())
            }
        }
        .map_err(|e| self.model_error(Some("msm"), e))?;
        let params = lattice.params.clone().unwrap_or_default();
        let omega = Omega::new(model.geometry(), &params, self.dnurbs.weights_as_dofs)
            .map_err(|e| self.model_error(None, e))?;
        let nodes = omega.node_state(&model, &self.initial_conditions().state(&model));
        let probe_nodes = self
            .probe_params()?
            .iter()
            .map(|&(u, v)| lattice.node_nearest(u, v))
            .collect();
        let msm = MsmModel::new(lattice).map_err(|e| self.model_error(Some("msm"), e))?;
        let initial = msm.initial_state_displaced(&nodes.velocities, &nodes.displacements);
        let time = self.time_settings();
        Ok(MsmSetup {
            path: self.path.clone(),
            from_file: false,
            model: msm,
            initial,
            run: FileSimulation {
                dt: time.dt,
                t_end: time.t_end,
                integrator: time.msm_integrator,
            },
            probe_nodes,
            save_every: self.simulation.save_every.max(1),
            vtk_every: self.output.vtk_every,
        })
    }
}

/// The msm.json of a derived lattice: the lattice, where it came from, its initial velocities
/// and how it was validated.
pub fn msm_file(
    lattice: &SpringLattice,
    scene_label: &str,
    initial_velocities: &[[f64; 3]],
    run: FileSimulation,
    probe_nodes: &[usize],
) -> MsmFile {
    MsmFile {
        scene: Some(scene_label.to_string()),
        initial_velocities: Some(initial_velocities.to_vec()),
        simulation: Some(run),
        probe_nodes: Some(probe_nodes.to_vec()),
        ..lattice.to_file()
    }
}
