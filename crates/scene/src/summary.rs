//! What `check` reports of a scene: sizes, dofs, fixed dofs and the MSM's stability limit,
//! without running anything.

use std::collections::BTreeMap;

use nurbspring_dnurbs::{DnurbsModel, Geometry, Material, QuadratureChoice};
use nurbspring_sim::{IntegratorKind, Schedule};
use serde::Serialize;

use crate::build::MsmOverrides;
use crate::{Error, Scene};

/// The geometry of a scene.
#[derive(Serialize)]
pub struct GeometrySummary {
    /// "surface" or "curve".
    pub kind: &'static str,
    /// Degrees `[p, q]` (a curve: `[p]`).
    pub degree: Vec<usize>,
    /// Control points `[n_u, n_v]` (a curve: `[n]`).
    pub control_points: Vec<usize>,
    /// Non-empty knot spans per direction.
    pub knot_spans: Vec<usize>,
    /// Whether the weights differ.
    pub rational: bool,
}

/// The D-NURBS of a scene.
#[derive(Serialize)]
pub struct DnurbsSummary {
    /// 3, or 4 with weights as unknowns.
    pub dofs_per_point: usize,
    /// All dofs.
    pub dofs: usize,
    /// Fixed dofs.
    pub fixed_dofs: usize,
    /// Free dofs.
    pub free_dofs: usize,
    /// Unknowns of every system solved: the free dofs less one per independent linear
    /// constraint (equal to `free_dofs` without linear constraints).
    pub reduced_dofs: usize,
    /// Fixed control points.
    pub fixed_control_points: usize,
    /// With free weights: `free` or `held`, the weights of the fixed control points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fixed_point_weights: Option<&'static str>,
    /// With free weights and none held: the weight fixed to remove the common scale of the
    /// weights (docs/math.md §4).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale_fixing_weight: Option<String>,
    /// The Gauss–Legendre rule and its estimated relative error.
    pub quadrature: QuadratureChoice,
    /// Non-zeros of K.
    pub stiffness_nonzeros: usize,
}

/// The time settings of a scene.
#[derive(Serialize)]
pub struct SimulationSummary {
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Steps.
    pub steps: u64,
    /// D-NURBS integrator.
    pub dnurbs_integrator: IntegratorKind,
    /// MSM integrator.
    pub msm_integrator: IntegratorKind,
}

/// The scene's own lattice of springs: what `simulate SCENE --model msm`, `stability` and
/// `export SCENE --format sofa|npz` run (the `[msm]` section as written, on the knots unless
/// `msm.grid` says otherwise), not the lattice a derivation makes ([`DeriveSummary`]).
#[derive(Serialize)]
pub struct MsmSummary {
    /// Where its nodes sit: `"knots"`, `"uniform"` or `"greville"`.
    pub lattice: &'static str,
    /// Nodes.
    pub nodes: usize,
    /// `[n_u, n_v]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid: Option<(usize, usize)>,
    /// Fixed nodes.
    pub fixed_nodes: usize,
    /// Free dofs.
    pub free_dofs: usize,
    /// Springs per class.
    pub springs: BTreeMap<String, usize>,
    /// The keys of `[msm]` the scene leaves out (its spring constants, `msm.mass`): without
    /// them the scene has no MSM of its own, and the stability fields below are absent.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub missing: Vec<String>,
    /// ω_max of the MSM at rest.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega_max: Option<f64>,
    /// 2/ω_max.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_critical: Option<f64>,
    /// Whether the scene's Δt exceeds it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_exceeds_explicit_limit: Option<bool>,
    /// How `simulate --model msm` runs the scene's integrator at its Δt: plain steps, substeps
    /// below the lattice's uniform stability limit, or Newmark ([`crate::run::explicit_schedule`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulate: Option<Schedule>,
}

/// The lattice `derive` makes for the scene's derivation (`fit.derivation`, default modal):
/// nodes on the Greville abscissae (one per control point) unless `msm.grid` says otherwise,
/// the paper's on the knots.
#[derive(Serialize)]
pub struct DeriveSummary {
    /// The derivation `derive SCENE` runs.
    pub derivation: &'static str,
    /// Why it is not the one the scene names, when so.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<&'static str>,
    /// Where its nodes sit: `"knots"`, `"uniform"` or `"greville"`.
    pub lattice: &'static str,
    /// Nodes.
    pub nodes: usize,
    /// `[n_u, n_v]` (`n_v = 1` on a curve).
    pub grid: (usize, usize),
}

/// The material of a scene: its model, and for the shell the stiffnesses and mass per area it
/// implies (docs/math.md §10.1).
#[derive(Serialize)]
pub struct MaterialSummary {
    /// `"tension-plate"` or `"kirchhoff-love"`.
    pub model: &'static str,
    /// The shell's bending stiffness `D = E t³ / (12 (1 − ν²))` (force · length).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bending_stiffness: Option<f64>,
    /// The shell's membrane stiffness `E t / (1 − ν²)` (force / length).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub membrane_stiffness: Option<f64>,
    /// The shell's mass per area `ρ t`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_per_area: Option<f64>,
}

impl MaterialSummary {
    fn of(material: &nurbspring_dnurbs::MaterialModel) -> Self {
        let shell = material.shell();
        Self {
            model: material.name(),
            bending_stiffness: shell.map(|m| m.bending_stiffness()),
            membrane_stiffness: shell.map(|m| m.membrane_stiffness()),
            mass_per_area: shell.map(|m| m.mass_per_area()),
        }
    }
}

/// `check`'s report.
#[derive(Serialize)]
pub struct Summary {
    /// The scene file.
    pub scene: String,
    /// Geometry.
    pub geometry: GeometrySummary,
    /// Material.
    pub material: MaterialSummary,
    /// D-NURBS.
    pub dnurbs: DnurbsSummary,
    /// Time settings.
    pub simulation: SimulationSummary,
    /// The lattice `derive` makes.
    pub derive: DeriveSummary,
    /// The scene's own lattice of springs (`simulate --model msm`).
    pub msm: MsmSummary,
    /// Warnings: a quadrature rule with a large estimated error, zero stiffness, unconstrained
    /// rigid motion, a time step above the explicit limit of the MSM integrator
    /// ([`scene_warnings`]).
    pub warnings: Vec<String>,
}

/// Validates the scene, builds its models and describes them.
pub fn summary(scene: &Scene) -> Result<Summary, Error> {
    let model = scene.build_dnurbs()?;
    let time = scene.time_settings();
    let geometry = match model.geometry() {
        Geometry::Surface(s) => GeometrySummary {
            kind: "surface",
            degree: vec![s.basis_u().degree(), s.basis_v().degree()],
            control_points: vec![s.n_u(), s.n_v()],
            knot_spans: vec![
                s.basis_u().knots().nonempty_spans().len(),
                s.basis_v().knots().nonempty_spans().len(),
            ],
            rational: s.weights().iter().any(|&w| w != s.weights()[0]),
        },
        Geometry::Curve(c) => GeometrySummary {
            kind: "curve",
            degree: vec![c.basis().degree()],
            control_points: vec![c.n_control_points()],
            knot_spans: vec![c.basis().knots().nonempty_spans().len()],
            rational: c.weights().iter().any(|&w| w != c.weights()[0]),
        },
    };
    let dof_map = model.dof_map();
    let (derivation, note) = scene.derivation();
    let grid = crate::build::parameter_grid(&scene.msm, derivation);
    let derive = DeriveSummary {
        derivation: derivation.name(),
        note,
        lattice: scene.msm.grid_for(derivation).name(),
        nodes: 0,
        grid: crate::build::lattice_shape(&grid, model.geometry())
            .map_err(|e| Error::model(&scene.path, Some("msm.grid"), e))?,
    };
    let derive = DeriveSummary {
        nodes: derive.grid.0 * derive.grid.1,
        ..derive
    };
    let msm = {
        let overrides = MsmOverrides::default();
        let missing = scene.missing_msm_keys(&overrides);
        let setup = scene.msm_setup_unchecked(&overrides)?;
        let lattice = setup.model.lattice();
        // The stability of placeholder constants would describe no model.
        let stability = if missing.is_empty() {
            let s = setup
                .model
                .stability()
                .map_err(|e| Error::model(&scene.path, Some("msm"), e))?;
            let schedule = Schedule::stable(
                &setup.model,
                setup.model.initial_positions(),
                time.msm_integrator,
                time.dt,
            )
            .map_err(|e| Error::model(&scene.path, Some("msm"), e))?
            .0;
            Some((s, schedule))
        } else {
            None
        };
        MsmSummary {
            lattice: scene.msm.grid_for(nurbspring_derive::Method::Paper).name(),
            nodes: lattice.n_nodes(),
            grid: lattice.grid,
            fixed_nodes: lattice.fixed.iter().filter(|&&f| f).count(),
            free_dofs: setup.model.dof_map().n_free(),
            springs: lattice
                .classes()
                .into_iter()
                .map(|c| (c.name().to_string(), lattice.count(c)))
                .collect(),
            missing,
            omega_max: stability.map(|(s, _)| s.omega_max),
            dt_critical: stability.map(|(s, _)| s.dt_critical),
            dt_exceeds_explicit_limit: stability.map(|(s, _)| time.dt >= s.dt_critical),
            simulate: stability.map(|(_, schedule)| schedule),
        }
    };
    Ok(Summary {
        scene: scene.path.display().to_string(),
        geometry,
        material: MaterialSummary::of(&scene.material),
        dnurbs: DnurbsSummary {
            dofs_per_point: model.matrices().dofs_per_point,
            dofs: dof_map.n_total(),
            fixed_dofs: dof_map.n_total() - dof_map.n_free(),
            free_dofs: dof_map.n_free(),
            reduced_dofs: model.n_free(),
            fixed_control_points: model.fixed_points().len(),
            fixed_point_weights: (scene.dnurbs.weights_as_dofs && !scene.constraints.fixed_weights)
                .then(|| scene.constraints.fixed_point_weights.name()),
            scale_fixing_weight: scale_fixing_weight(&model),
            quadrature: *model.quadrature(),
            stiffness_nonzeros: model.matrices().stiffness.nnz(),
        },
        simulation: SimulationSummary {
            dt: time.dt,
            t_end: time.t_end,
            steps: nurbspring_sim::step_count(0.0, time.t_end, time.dt) as u64,
            dnurbs_integrator: time.dnurbs_integrator,
            msm_integrator: time.msm_integrator,
        },
        warnings: model
            .quadrature()
            .warning()
            .into_iter()
            .chain(scene_warnings(scene, &model, Some(&msm)))
            .collect(),
        derive,
        msm,
    })
}

/// What `check` warns about a valid scene: a material without stiffness, a body free to move
/// rigidly, and a time step above the explicit limit of the scene's MSM integrator.
pub fn scene_warnings(scene: &Scene, model: &DnurbsModel, msm: Option<&MsmSummary>) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some(m) = scene.material.tension_plate() {
        zero_stiffness_warning(m, model, &mut warnings);
    }
    rigid_and_stability_warnings(scene, model, msm, &mut warnings);
    warnings
}

/// The tension plate without stiffness: a warning.
fn zero_stiffness_warning(m: &Material, model: &DnurbsModel, warnings: &mut Vec<String>) {
    let names: &[(&str, f64)] = match model.geometry() {
        Geometry::Surface(_) => &[
            ("alpha11", m.alpha11),
            ("alpha22", m.alpha22),
            ("beta11", m.beta11),
            ("beta12", m.beta12),
            ("beta22", m.beta22),
        ],
        Geometry::Curve(_) => &[("alpha11", m.alpha11), ("beta11", m.beta11)],
    };
    if names.iter().all(|(_, k)| *k == 0.0) {
        let list: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
        warnings.push(format!(
            "material: zero stiffness ({} all 0): K = 0, nothing resists deformation and every \
             derived spring constant is 0",
            list.join(", ")
        ));
    }
}

/// A body free to move rigidly, a time step above the MSM's explicit limit: warnings.
fn rigid_and_stability_warnings(
    scene: &Scene,
    model: &DnurbsModel,
    msm: Option<&MsmSummary>,
    warnings: &mut Vec<String>,
) {
    if model.fixed_points().is_empty()
        && scene.constraints.linear.is_empty()
        && scene.constraints.edge.is_empty()
    {
        warnings.push(
            "constraints: no fixed control points, no linear constraints and no edge \
             conditions: the body is free to translate and rotate (K is singular; `steady` \
             refuses it)"
                .to_string(),
        );
    }
    let time = scene.time_settings();
    if let Some(msm) = msm
        && let (Some(schedule), Some(dt_critical)) = (msm.simulate, msm.dt_critical)
        && !schedule.is_plain(time.msm_integrator)
    {
        let how = if schedule.integrator == time.msm_integrator {
            format!(
                "runs it in {n} substeps of dt/{n} per step",
                n = schedule.substeps
            )
        } else {
            format!("runs {} instead", schedule.integrator)
        };
        warnings.push(format!(
            "simulation.dt = {} is above the explicit limit of simulation.msm_integrator = {} \
             (dt_critical = {:.4e} s): `simulate --model msm` {how}; choose dt below \
             dt_critical or an implicit integrator",
            time.dt, time.msm_integrator, dt_critical,
        ));
    }
}

/// `weight of control point [i, j] (dof d) held at w = …` for the gauge weight, if any.
pub fn scale_fixing_weight(model: &DnurbsModel) -> Option<String> {
    let dof = model.gauge_weight()?;
    let k = dof / 4;
    let point = match model.geometry() {
        Geometry::Surface(s) => format!("[{}, {}]", k / s.n_v(), k % s.n_v()),
        Geometry::Curve(_) => format!("[{k}]"),
    };
    Some(format!(
        "weight of control point {point} (dof {dof}) held at w = {}",
        model.p0()[dof]
    ))
}
