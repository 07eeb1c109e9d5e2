//! Scene sections → model types, and library errors → exit codes.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::anyhow;
use nurbspring_derive::{
    DeriveError, ExperimentConfig, FitMethod, FitOptions, FitResult, MassChoice, omega_matrix,
};
use nurbspring_dnurbs::{
    Constraints, DnurbsError, DnurbsModel, DnurbsOptions, Geometry, Integration, LinearConstraint,
    Loads, Material, PointLoad, RationalStepper, RestShape,
};
use nurbspring_io::scene::{self, GeometrySpec, Scene};
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{
    FixedNodes, LatticeFile, LatticeOptions, MsmError, MsmModel, ParameterGrid, SpringKind,
    SpringLattice,
};
use nurbspring_sim::{IntegratorKind, SimError, State};
use serde::Deserialize;

use crate::Failure;
use crate::commands::simulate::MsmOverrides;

/// Reads and validates a scene; every problem is bad input (exit 2).
pub fn load_scene(path: &Path) -> Result<Scene, Failure> {
    Scene::from_path(path).map_err(Failure::input)
}

/// The geometry of a scene.
pub fn geometry(scene: &Scene) -> Result<Geometry, Failure> {
    Ok(match &scene.geometry {
        GeometrySpec::Surface(s) => Geometry::Surface(s.to_surface().map_err(Failure::input)?),
        GeometrySpec::Curve(c) => Geometry::Curve(c.to_curve().map_err(Failure::input)?),
    })
}

/// `[material]`.
pub fn material(scene: &Scene) -> Material {
    let m = &scene.material;
    Material {
        mu: m.mu,
        gamma: m.gamma,
        alpha11: m.alpha11,
        alpha22: m.alpha22,
        beta11: m.beta11,
        beta12: m.beta12,
        beta22: m.beta22,
    }
}

/// `[loads]`.
pub fn loads(scene: &Scene) -> Loads {
    let l = &scene.loads;
    Loads {
        gravity: l.gravity,
        distributed: l.distributed,
        point: l
            .point
            .iter()
            .map(|p| PointLoad {
                u: p.u,
                v: p.v.unwrap_or(0.0),
                force: p.force,
            })
            .collect(),
    }
}

/// `[dnurbs]`.
pub fn dnurbs_options(scene: &Scene) -> DnurbsOptions {
    let d = &scene.dnurbs;
    DnurbsOptions {
        quadrature_points: d.quadrature_points,
        integration: match d.integrate_over {
            scene::IntegrationDomain::Parameter => Integration::Parameter,
            scene::IntegrationDomain::Area => Integration::Area,
        },
        weights_as_dofs: d.weights_as_dofs,
        rest_shape: match d.rest_shape {
            scene::RestShape::Initial => RestShape::Initial,
            scene::RestShape::Zero => RestShape::Zero,
        },
    }
}

/// Flat control point index of `[i, j]` (surfaces) or `[i]` (curves).
fn point_index(scene: &Scene, key: &str, p: &[usize]) -> Result<usize, Failure> {
    let (n_u, n_v) = scene.geometry.net_dims();
    let bad =
        |why: String| Failure::input(anyhow!("{}: {key} = {p:?}: {why}", scene.path.display()));
    match (p, scene.geometry.is_surface()) {
        ([i, j], true) if *i < n_u && *j < n_v => Ok(i * n_v + j),
        ([i], false) if *i < n_u * n_v.max(1) => Ok(*i),
        ([_, _], true) | ([_], false) => {
            Err(bad(format!("no such control point in a {n_u} × {n_v} net")))
        }
        _ => Err(bad(if scene.geometry.is_surface() {
            "expected [i, j]".to_string()
        } else {
            "expected [i]".to_string()
        })),
    }
}

/// `[constraints]`.
pub fn constraints(scene: &Scene) -> Result<Constraints, Failure> {
    let c = &scene.constraints;
    let dpp = if scene.dnurbs.weights_as_dofs { 4 } else { 3 };
    let fixed_points = c
        .fixed
        .iter()
        .enumerate()
        .map(|(n, p)| point_index(scene, &format!("constraints.fixed[{n}]"), p))
        .collect::<Result<Vec<_>, _>>()?;
    let mut linear = Vec::with_capacity(c.linear.len());
    for (r, row) in c.linear.iter().enumerate() {
        let mut terms = Vec::with_capacity(row.terms.len());
        for (t, term) in row.terms.iter().enumerate() {
            let key = format!("constraints.linear[{r}].terms[{t}].point");
            let k = point_index(scene, &key, &term.point)?;
            let offset = term.component.offset();
            if offset >= dpp {
                return Err(Failure::input(anyhow!(
                    "{}: constraints.linear[{r}].terms[{t}].component = \"w\": weights are not unknowns (set dnurbs.weights_as_dofs = true)",
                    scene.path.display()
                )));
            }
            terms.push((k * dpp + offset, term.coefficient));
        }
        linear.push(LinearConstraint {
            terms,
            rhs: row.rhs,
        });
    }
    Ok(Constraints {
        fixed_points,
        fixed_rings: c.fixed_rings,
        fixed_weights: c.fixed_weights,
        linear,
    })
}

/// Which D-NURBS errors are bad input (exit 2) and which are failures of the run (exit 1).
pub fn dnurbs_failure(e: DnurbsError) -> Failure {
    match e {
        // A singular system (nothing fixed, no mass) is a property of the scene: bad input.
        DnurbsError::Linalg(_) | DnurbsError::NonFinite { .. } => Failure::run(e),
        DnurbsError::Sim(ref s)
            if !matches!(
                s,
                SimError::InvalidTimeStep { .. } | SimError::InvalidDuration { .. }
            ) =>
        {
            Failure::run(e)
        }
        _ => Failure::input(e),
    }
}

/// Which MSM errors are bad input.
pub fn msm_failure(e: MsmError) -> Failure {
    match e {
        MsmError::Linalg(_) | MsmError::Sim(_) => Failure::run(e),
        _ => Failure::input(e),
    }
}

/// Which derivation errors are bad input.
pub fn derive_failure(e: DeriveError) -> Failure {
    match e {
        DeriveError::Dnurbs(d) => dnurbs_failure(d),
        DeriveError::Msm(m) => msm_failure(m),
        DeriveError::Cancelled => Failure::run(anyhow!("interrupted by Ctrl-C")),
        other if other.is_input_error() => Failure::input(other),
        other => Failure::run(other),
    }
}

/// The constrained D-NURBS model of a scene.
pub fn dnurbs_model(scene: &Scene) -> Result<DnurbsModel, Failure> {
    let g = geometry(scene)?;
    let c = constraints(scene)?;
    DnurbsModel::new(g, material(scene), loads(scene), &c, dnurbs_options(scene))
        .map_err(|e| dnurbs_failure(e).context(&scene.path))
}

impl Failure {
    /// Prefixes the message with the scene file.
    pub fn context(self, path: &Path) -> Self {
        Self {
            code: self.code,
            error: self.error.context(path.display().to_string()),
        }
    }
}

/// `[simulation]` settings.
pub struct Simulation {
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// D-NURBS integrator.
    pub dnurbs_integrator: IntegratorKind,
    /// MSM integrator.
    pub msm_integrator: IntegratorKind,
    /// Record a sample every n steps.
    pub save_every: usize,
    /// Write a ParaView frame every n samples.
    pub vtk_every: usize,
}

/// `[simulation]`.
pub fn simulation(scene: &Scene) -> Result<Simulation, Failure> {
    let s = &scene.simulation;
    Ok(Simulation {
        dt: s.dt,
        t_end: s.t_end,
        dnurbs_integrator: s.dnurbs_integrator.kind(),
        msm_integrator: s.msm_integrator.kind(),
        save_every: s.save_every.max(1),
        vtk_every: scene.output.vtk_every.max(1),
    })
}

/// Probe parameters: `(0.5, 0.5)` (a curve: `0.5`) first, then the scene's.
pub fn probes(scene: &Scene) -> Vec<(f64, f64)> {
    let mut out = vec![(0.5, 0.5)];
    for p in &scene.simulation.probes {
        let q = (
            p.first().copied().unwrap_or(0.5),
            p.get(1).copied().unwrap_or(0.0),
        );
        if !out.contains(&q) {
            out.push(q);
        }
    }
    out
}

/// Rows `J(u, v)` stacked per probe: `probe_matrix · p` gives the probe positions.
pub fn probe_matrix(scene: &Scene, model: &DnurbsModel) -> Result<SparseMatrix, Failure> {
    let weights = model.matrices().dofs_per_point == 4;
    match model.geometry() {
        Geometry::Surface(s) => omega_matrix(s, &probes(scene), weights)
            .map_err(|e| Failure::input(anyhow!("simulation.probes: {e}"))),
        Geometry::Curve(c) => {
            let d = model.matrices().dofs_per_point;
            let mut triplets = Vec::new();
            let ps = probes(scene);
            for (n, &(u, _)) in ps.iter().enumerate() {
                let u = if n == 0 {
                    0.5 * (c.domain().0 + c.domain().1)
                } else {
                    u
                };
                let j = c
                    .jacobian(u, 0, weights)
                    .map_err(|e| Failure::input(anyhow!("simulation.probes: {e}")))?;
                for l in 0..j.n_local() {
                    for comp in 0..d {
                        let col = j.column(l, comp, nurbspring_geom::Deriv::Value);
                        for x in 0..3 {
                            if col[x] != 0.0 {
                                triplets.push((3 * n + x, j.dof(l, comp), col[x]));
                            }
                        }
                    }
                }
            }
            SparseMatrix::from_triplets(3 * ps.len(), d * c.n_control_points(), &triplets)
                .map_err(Failure::run)
        }
    }
}

/// Per-control-point initial velocities (`initial.velocities`, else `initial.velocity` for all).
fn initial_velocities(scene: &Scene) -> Vec<[f64; 3]> {
    match &scene.initial.velocities {
        Some(v) => v.clone(),
        None => vec![scene.initial.velocity],
    }
}

/// The D-NURBS initial state: velocities of free control points, and `initial.displacement`
/// added to every free control point.
pub fn dnurbs_initial_state(scene: &Scene, model: &DnurbsModel) -> Result<State, Failure> {
    let mut state = model.initial_state(&initial_velocities(scene), scene.initial.weight_velocity);
    let d = scene.initial.displacement;
    if d != [0.0; 3] {
        let dpp = model.matrices().dofs_per_point;
        let mut p = model.full_coordinates(&state.q);
        let fixed = model.fixed_points();
        for k in 0..model.geometry().n_control_points() {
            if !fixed.contains(&k) {
                for x in 0..3 {
                    p[dpp * k + x] += d[x];
                }
            }
        }
        state.q = model.reduced_coordinates(&p);
    }
    Ok(state)
}

/// Runs the weights-as-unknowns model with its own stepper (SPEC §3), calling `observe` at
/// t = 0 and after every step with `(step, t, p, kinetic, elastic)`.
pub fn run_rational(
    model: &DnurbsModel,
    initial: State,
    dt: f64,
    t_end: f64,
    cancel: &Arc<AtomicBool>,
    observe: &mut dyn FnMut(usize, f64, &[f64], f64, f64),
) -> Result<(), Failure> {
    let energy = |p: &[f64], v: &[f64]| {
        let vf = model.full_velocity(v);
        (
            0.5 * model.matrices().mass.quadratic_form(&vf),
            model.elastic_energy(p),
        )
    };
    let p0 = model.full_coordinates(&initial.q);
    let (k0, e0) = energy(&p0, &initial.v);
    observe(0, 0.0, &p0, k0, e0);
    let mut stepper = RationalStepper::new(model, initial, dt).map_err(dnurbs_failure)?;
    let mut step = 0;
    while stepper.state().t < t_end - 0.5 * dt {
        if cancel.load(Ordering::Relaxed) {
            break;
        }
        stepper.step().map_err(dnurbs_failure)?;
        step += 1;
        let p = stepper.full_coordinates().to_vec();
        let (k, e) = energy(&p, &stepper.state().v);
        observe(step, stepper.state().t, &p, k, e);
    }
    Ok(())
}

/// `[msm]` lattice options (k and mass possibly overridden).
fn lattice_options(
    scene: &Scene,
    overrides: &MsmOverrides,
    surface: &nurbspring_geom::NurbsSurface,
) -> Result<LatticeOptions, Failure> {
    let m = &scene.msm;
    let grid = match m.grid {
        scene::LatticeGrid::Knots => ParameterGrid::Knots,
        scene::LatticeGrid::Uniform => ParameterGrid::Uniform {
            nodes_u: m.nodes_u,
            nodes_v: m.nodes_v,
        },
        scene::LatticeGrid::Greville => ParameterGrid::Greville,
    };
    let fixed = match &m.fixed {
        scene::MsmFixed::Auto => FixedNodes::Auto,
        scene::MsmFixed::Nodes(list) => {
            let n_v = match m.grid {
                scene::LatticeGrid::Knots => surface.basis_v().knots().distinct().len(),
                scene::LatticeGrid::Uniform => m.nodes_v,
                scene::LatticeGrid::Greville => {
                    let mut g = surface.basis_v().knots().greville();
                    g.dedup();
                    g.len()
                }
            };
            let mut out = Vec::with_capacity(list.len());
            for (n, node) in list.iter().enumerate() {
                out.push(match node.as_slice() {
                    [a] => *a,
                    [i, j] if *j < n_v => i * n_v + j,
                    _ => {
                        return Err(Failure::input(anyhow!(
                            "{}: msm.fixed[{n}] = {node:?}: expected [i, j] with j < {n_v} or a node index [a]",
                            scene.path.display()
                        )));
                    }
                });
            }
            FixedNodes::List(out)
        }
    };
    let check = |name: &str, v: Option<f64>, positive: bool| -> Result<(), Failure> {
        match v {
            Some(x) if !x.is_finite() || x < 0.0 || (positive && x == 0.0) => {
                Err(Failure::input(anyhow!(
                    "--{name} {x}: must be {} and finite",
                    if positive { "positive" } else { "non-negative" }
                )))
            }
            _ => Ok(()),
        }
    };
    check("k-edge", overrides.k_edge, false)?;
    check("k-diag", overrides.k_diag, false)?;
    check("k-bend", overrides.k_bend, false)?;
    check("mass", overrides.mass, true)?;
    Ok(LatticeOptions {
        grid,
        structural: m.structural,
        shear: m.shear,
        bending: m.bending,
        k_edge: overrides.k_edge.unwrap_or(m.k_edge),
        k_diag: overrides.k_diag.unwrap_or(m.k_diag),
        k_bend: overrides.k_bend.unwrap_or(m.k_bend),
        mass: overrides.mass.unwrap_or(m.mass),
        damping: m.damping,
        pre_strain: m.pre_strain,
        fixed,
        gravity: scene.loads.gravity,
    })
}

/// How to run an MSM: from a scene's `[simulation]` or from msm.json's `simulation` block.
pub struct MsmRun {
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Integrator.
    pub integrator: IntegratorKind,
    /// Probe nodes, the node nearest (0.5, 0.5) first.
    pub probe_nodes: Vec<usize>,
    /// Record a sample every n steps.
    pub save_every: usize,
    /// Write a ParaView frame every n samples.
    pub vtk_every: usize,
}

/// msm.json as written by `derive`: the lattice plus optional run settings.
#[derive(Deserialize)]
struct MsmFileIn {
    #[serde(flatten)]
    lattice: LatticeFile,
    #[serde(default)]
    #[allow(dead_code)]
    scene: Option<String>,
    #[serde(default)]
    initial_velocities: Option<Vec<[f64; 3]>>,
    #[serde(default)]
    simulation: Option<SimulationIn>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulationIn {
    dt: f64,
    t_end: f64,
    integrator: String,
}

/// The MSM of a scene (lattice from the surface, node velocities `Ω ṗ(0)`, eq. 18), or of an
/// msm.json file; with its initial state and run settings.
pub fn msm_model(
    path: &Path,
    overrides: &MsmOverrides,
) -> Result<(MsmModel, State, MsmRun), Failure> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return msm_from_json(path, overrides);
    }
    let scene = load_scene(path)?;
    msm_model_from_scene(&scene, overrides)
}

/// The MSM of a parsed scene (see [`msm_model`]).
pub fn msm_model_from_scene(
    scene: &Scene,
    overrides: &MsmOverrides,
) -> Result<(MsmModel, State, MsmRun), Failure> {
    let path = scene.path.as_path();
    let scene = scene.clone();
    let model = dnurbs_model(&scene)?;
    let Geometry::Surface(surface) = model.geometry() else {
        return Err(Failure::input(anyhow!(
            "{}: the mass-spring model needs a [surface] scene, this one has a [curve]",
            path.display()
        )));
    };
    let options = lattice_options(&scene, overrides, surface)?;
    let lattice = SpringLattice::from_surface(surface, &options, model.fixed_points())
        .map_err(msm_failure)?;
    let params = lattice.params.clone().unwrap_or_default();
    let omega = omega_matrix(surface, &params, model.matrices().dofs_per_point == 4)
        .map_err(derive_failure)?;
    let initial = dnurbs_initial_state(&scene, &model)?;
    let pdot = model.full_velocity(&initial.v);
    let mut xdot = vec![0.0; omega.nrows()];
    omega.mul_vec(&pdot, &mut xdot);
    let velocities: Vec<[f64; 3]> = xdot.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    let probe_nodes = probes(&scene)
        .iter()
        .map(|&(u, v)| lattice.node_nearest(u, v))
        .collect();
    let sim = simulation(&scene)?;
    let msm = MsmModel::new(lattice).map_err(msm_failure)?;
    let state = msm.initial_state(&velocities);
    Ok((
        msm,
        state,
        MsmRun {
            dt: sim.dt,
            t_end: sim.t_end,
            integrator: sim.msm_integrator,
            probe_nodes,
            save_every: sim.save_every,
            vtk_every: sim.vtk_every,
        },
    ))
}

fn msm_from_json(
    path: &Path,
    overrides: &MsmOverrides,
) -> Result<(MsmModel, State, MsmRun), Failure> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        Failure::input(anyhow!(
            "{}: cannot read the lattice file: {e}",
            path.display()
        ))
    })?;
    let file: MsmFileIn = serde_json::from_str(&text).map_err(|e| {
        Failure::input(anyhow!(
            "{}: not a valid lattice file at line {}, column {}: {e}",
            path.display(),
            e.line(),
            e.column()
        ))
    })?;
    let mut lattice =
        SpringLattice::from_json(&file.lattice).map_err(|e| msm_failure(e).context(path))?;
    for (kind, k) in [
        (SpringKind::Structural, overrides.k_edge),
        (SpringKind::Shear, overrides.k_diag),
        (SpringKind::Bend, overrides.k_bend),
    ] {
        if let Some(k) = k {
            if !(k.is_finite() && k >= 0.0) {
                return Err(Failure::input(anyhow!(
                    "--k-{} {k}: must be non-negative and finite",
                    kind.name()
                )));
            }
            lattice.set_stiffness(kind, k);
        }
    }
    if let Some(m) = overrides.mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(Failure::input(anyhow!(
                "--mass {m}: must be positive and finite"
            )));
        }
        lattice.set_mass(m);
    }
    let (dt, t_end, integrator) = match &file.simulation {
        Some(s) => (
            s.dt,
            s.t_end,
            IntegratorKind::parse(&s.integrator).ok_or_else(|| {
                Failure::input(anyhow!(
                    "{}: simulation.integrator = {:?}: unknown integrator",
                    path.display(),
                    s.integrator
                ))
            })?,
        ),
        None => (0.01, 1.0, IntegratorKind::BackwardEuler),
    };
    let centre = if lattice.params.is_some() || lattice.grid.is_some() {
        lattice.node_nearest(0.5, 0.5)
    } else {
        0
    };
    let velocities = file.initial_velocities.clone().unwrap_or_default();
    let msm = MsmModel::new(lattice).map_err(|e| msm_failure(e).context(path))?;
    let state = msm.initial_state(&velocities);
    Ok((
        msm,
        state,
        MsmRun {
            dt,
            t_end,
            integrator,
            probe_nodes: vec![centre],
            save_every: 1,
            vtk_every: 1,
        },
    ))
}

/// A derivation experiment from a scene (the scene's `[msm]` constants and mass are kept as
/// the "given" parameters and evaluated beside the derived ones).
pub fn experiment(scene: &Scene) -> Result<ExperimentConfig, Failure> {
    let model_geometry = geometry(scene)?;
    let Geometry::Surface(surface) = model_geometry else {
        return Err(Failure::input(anyhow!(
            "{}: deriving a mass-spring model needs a [surface] scene, this one has a [curve]",
            scene.path.display()
        )));
    };
    let sim = simulation(scene)?;
    let lattice = lattice_options(scene, &MsmOverrides::default(), &surface)?;
    let fit = &scene.fit;
    let given = FitResult {
        k_edge: scene.msm.structural.then_some(scene.msm.k_edge),
        k_diag: scene.msm.shear.then_some(scene.msm.k_diag),
        k_bend: scene.msm.bending.then_some(scene.msm.k_bend),
        relative_residual: f64::NAN,
    };
    let mut probes = probes(scene);
    probes.remove(0);
    Ok(ExperimentConfig {
        surface,
        material: material(scene),
        loads: loads(scene),
        constraints: constraints(scene)?,
        dnurbs: dnurbs_options(scene),
        lattice,
        initial_velocity: initial_velocities(scene),
        dt: sim.dt,
        t_end: sim.t_end,
        dnurbs_integrator: sim.dnurbs_integrator,
        msm_integrator: sim.msm_integrator,
        fit: FitOptions {
            dofs: match fit.dofs {
                scene::FitDofs::All => nurbspring_derive::FitDofs::All,
                scene::FitDofs::Free => nurbspring_derive::FitDofs::Free,
            },
            nonnegative: fit.nonnegative,
            method: match fit.method {
                scene::FitMethod::ClosedForm => FitMethod::ClosedForm,
                scene::FitMethod::TrustRegion => FitMethod::TrustRegion,
            },
            mass: match fit.mass {
                scene::MassMethod::EigenvalueScan => MassChoice::EigenvalueScan,
                scene::MassMethod::Fixed => MassChoice::Fixed(scene.msm.mass),
            },
            max_candidates: fit.max_candidates,
        },
        probes,
        given: Some((given, scene.msm.mass)),
    })
}
