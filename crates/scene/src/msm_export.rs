//! Mass-spring models out to other simulators: a NumPy `.npz` archive with every array the
//! model needs (`docs/export.md` steps it with NumPy and reproduces `simulate`'s trajectory),
//! and a SOFA Python scene (springs, per-node masses, fixed nodes, gravity, uniform damping).
//!
//! Both start from an [`MsmSetup`], so they hold exactly what `simulate --model msm` runs: the
//! lattice, its initial state, time step, end time, integrator and probe nodes.

use std::fmt::Write as _;
use std::path::Path;

use nurbspring_io::atomic::write_atomic_bytes;
use nurbspring_io::output::{NpyArray, NpyData, write_npz};
use nurbspring_sim::IntegratorKind;

use crate::Error;
use crate::msm_file::MsmSetup;

/// Node positions and velocities of the initial state, all nodes (fixed ones at rest).
fn initial_nodes(setup: &MsmSetup) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let lattice = setup.model.lattice();
    let x = setup.model.full_positions(&setup.initial.q);
    let positions = x.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mut velocities = vec![[0.0; 3]; lattice.n_nodes()];
    for (k, &a) in setup.model.free_nodes().iter().enumerate() {
        velocities[a].copy_from_slice(&setup.initial.v[3 * k..3 * k + 3]);
    }
    (positions, velocities)
}

fn scalar_i64(x: usize) -> NpyArray {
    NpyArray {
        shape: Vec::new(),
        data: NpyData::I64(vec![x as i64]),
    }
}

/// The arrays of the `.npz` export, by name (docs/export.md lists them).
pub fn npz_arrays(setup: &MsmSetup) -> Vec<(&'static str, NpyArray)> {
    let lattice = setup.model.lattice();
    let n = lattice.n_nodes();
    let (x0, v0) = initial_nodes(setup);
    let forces = if lattice.forces.is_empty() {
        vec![[0.0; 3]; n]
    } else {
        lattice.forces.clone()
    };
    let springs = &lattice.springs;
    let width = lattice
        .elements
        .iter()
        .map(|e| e.nodes.len())
        .max()
        .unwrap_or(0)
        .max(2);
    let mut element_nodes = Vec::with_capacity(lattice.elements.len() * width);
    let mut element_coefficients = Vec::with_capacity(lattice.elements.len() * width);
    for e in &lattice.elements {
        for s in 0..width {
            element_nodes.push(e.nodes.get(s).map_or(-1, |&a| a as i64));
            element_coefficients.push(e.coefficients.get(s).copied().unwrap_or(0.0));
        }
    }
    let n_elements = lattice.elements.len();
    let matrix = |a: NpyArray, cols: usize, rows: usize| {
        a.reshaped(vec![rows, cols])
            .expect("the sizes are built to match")
    };
    let mut arrays = vec![
        ("positions", NpyArray::vec3(&lattice.positions)),
        ("masses", NpyArray::f64(lattice.masses.clone())),
        ("fixed", NpyArray::bool(lattice.fixed.clone())),
        ("damping", NpyArray::f64(lattice.damping.clone())),
        ("forces", NpyArray::vec3(&forces)),
        ("gravity", NpyArray::f64(lattice.gravity.to_vec())),
        ("initial_positions", NpyArray::vec3(&x0)),
        ("initial_velocities", NpyArray::vec3(&v0)),
        (
            "springs",
            matrix(
                NpyArray::i64(
                    springs
                        .iter()
                        .flat_map(|s| [s.a as i64, s.b as i64])
                        .collect(),
                ),
                2,
                springs.len(),
            ),
        ),
        (
            "spring_k",
            NpyArray::f64(springs.iter().map(|s| s.k).collect()),
        ),
        (
            "spring_rest_length",
            NpyArray::f64(springs.iter().map(|s| s.rest_length).collect()),
        ),
        (
            "spring_kind",
            NpyArray::strings(springs.iter().map(|s| s.kind.name().to_string()).collect()),
        ),
        (
            "element_nodes",
            matrix(NpyArray::i64(element_nodes), width, n_elements),
        ),
        (
            "element_coefficients",
            matrix(NpyArray::f64(element_coefficients), width, n_elements),
        ),
        (
            "element_k",
            NpyArray::f64(lattice.elements.iter().map(|e| e.k).collect()),
        ),
        (
            "element_weight",
            NpyArray::f64(lattice.elements.iter().map(|e| e.weight).collect()),
        ),
        (
            "element_kind",
            NpyArray::strings(
                lattice
                    .elements
                    .iter()
                    .map(|e| e.kind.name().to_string())
                    .collect(),
            ),
        ),
        (
            "element_class",
            NpyArray::strings(lattice.elements.iter().map(|e| e.class().name()).collect()),
        ),
        ("dt", NpyArray::scalar(setup.run.dt)),
        ("t_end", NpyArray::scalar(setup.run.t_end)),
        ("integrator", NpyArray::string(setup.run.integrator.name())),
        ("save_every", scalar_i64(setup.save_every)),
        (
            "probe_nodes",
            NpyArray::i64(setup.probe_nodes.iter().map(|&a| a as i64).collect()),
        ),
    ];
    if let Some(params) = &lattice.params {
        arrays.push((
            "uv",
            matrix(
                NpyArray::f64(params.iter().flat_map(|&(u, v)| [u, v]).collect()),
                2,
                n,
            ),
        ));
    }
    if let Some((n_u, n_v)) = lattice.grid {
        arrays.push(("grid", NpyArray::i64(vec![n_u as i64, n_v as i64])));
    }
    arrays
}

/// Writes the `.npz` export of an MSM.
pub fn write_msm_npz(path: &Path, setup: &MsmSetup) -> Result<(), Error> {
    Ok(write_npz(path, &npz_arrays(setup))?)
}

/// What SOFA's components cannot hold of a model, said once for messages and the scene's header.
pub fn sofa_limitations(setup: &MsmSetup) -> Vec<String> {
    let lattice = setup.model.lattice();
    let mut out = Vec::new();
    if !lattice.elements.is_empty() {
        out.push(format!(
            "the model's {} linear elements (energy 1/2 k w |sum_i c_i u_i|^2 on the displacements \
             u = x - x(0)) are not in the SOFA scene: SOFA's spring components have a scalar rest \
             length, not a rest vector, and the bend and twist stencils couple 3 or 4 nodes; \
             use --format npz for the whole model",
            lattice.elements.len()
        ));
    }
    let free_damping: Vec<f64> = setup
        .model
        .free_nodes()
        .iter()
        .map(|&a| lattice.damping[a])
        .collect();
    if free_damping.windows(2).any(|w| w[0] != w[1]) {
        out.push(
            "the node damping varies from node to node; SOFA's UniformVelocityDampingForceField \
             holds one coefficient, so the scene uses their mean"
                .to_string(),
        );
    }
    if !matches!(
        setup.run.integrator,
        IntegratorKind::SymplecticEuler | IntegratorKind::Rk4 | IntegratorKind::BackwardEuler
    ) {
        out.push(format!(
            "SOFA has no {} solver used here; the scene uses {}",
            setup.run.integrator.name(),
            if setup.run.integrator == IntegratorKind::Newmark {
                "NewmarkImplicitSolver (beta 1/4, gamma 1/2)"
            } else {
                "EulerImplicitSolver (backward Euler)"
            }
        ));
    }
    out
}

fn py_list3(rows: &[[f64; 3]]) -> String {
    let mut s = String::from("[\n");
    for r in rows {
        let _ = writeln!(s, "    [{:?}, {:?}, {:?}],", r[0], r[1], r[2]);
    }
    s.push(']');
    s
}

fn py_floats(v: &[f64]) -> String {
    let mut s = String::from("[");
    for (k, x) in v.iter().enumerate() {
        if k > 0 {
            s.push_str(if k % 8 == 0 { ",\n    " } else { ", " });
        }
        let _ = write!(s, "{x:?}");
    }
    s.push(']');
    s
}

/// The SOFA scene (SofaPython3 `createScene`) of an MSM, or why SOFA cannot hold it: a model
/// whose only elastic forces are linear elements has nothing SOFA's springs can express.
pub fn sofa_scene(setup: &MsmSetup, source: &str, file_name: &str) -> Result<String, String> {
    let lattice = setup.model.lattice();
    if lattice.springs.is_empty() && !lattice.elements.is_empty() {
        return Err(format!(
            "the model has no springs, only {} linear elements (energy 1/2 k w |sum_i c_i u_i|^2 on \
             the displacements), which SOFA's spring components cannot express (a scalar rest \
             length, two nodes); export it with --format npz, or derive a spring model with \
             `derive --derivation paper`",
            lattice.elements.len()
        ));
    }
    let (x0, v0) = initial_nodes(setup);
    let fixed: Vec<usize> = (0..lattice.n_nodes())
        .filter(|&a| lattice.fixed[a])
        .collect();
    let free = setup.model.free_nodes();
    let damping = if free.is_empty() {
        0.0
    } else {
        free.iter().map(|&a| lattice.damping[a]).sum::<f64>() / free.len() as f64
    };
    let limitations = sofa_limitations(setup);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\"\"\"SOFA scene of a nurbspring mass-spring model, written by `nurbspring export --format sofa`.\n\n\
         Source: {source}\n\
         {} nodes ({} fixed), {} springs. Run it with `runSofa {file_name}` (SOFA 24.06 or later\n\
         with SofaPython3) or load it from Python with `Sofa.Simulation`.",
        lattice.n_nodes(),
        fixed.len(),
        lattice.springs.len()
    );
    if limitations.is_empty() {
        s.push_str("\nSOFA holds every part of this model.\n");
    } else {
        s.push_str("\nNot expressed in SOFA (see docs/export.md):\n");
        for l in &limitations {
            let _ = writeln!(s, "- {l}.");
        }
    }
    s.push_str(
        "\nnurbspring's springs have no damping of their own (kd = 0 below); its damping is a force\n\
         -gamma v on every free node (UniformVelocityDampingForceField).\n\"\"\"\n\n",
    );
    let _ = writeln!(s, "GRAVITY = {}", py_floats(&lattice.gravity));
    let _ = writeln!(s, "DT = {:?}", setup.run.dt);
    let _ = writeln!(s, "T_END = {:?}", setup.run.t_end);
    let _ = writeln!(
        s,
        "INTEGRATOR = \"{}\"  # nurbspring's name",
        setup.run.integrator.name()
    );
    let _ = writeln!(s, "NODE_DAMPING = {damping:?}");
    let _ = writeln!(
        s,
        "# SOFA 24.06 renamed FixedConstraint; write \"FixedConstraint\" here for older versions."
    );
    s.push_str("FIXED_CONSTRAINT = \"FixedProjectiveConstraint\"\n\n");
    let _ = writeln!(s, "POSITIONS = {}\n", py_list3(&x0));
    let _ = writeln!(
        s,
        "# Rest positions of the lattice (fixed nodes are held here).\nREST_POSITIONS = {}\n",
        py_list3(&lattice.positions)
    );
    let _ = writeln!(s, "VELOCITIES = {}\n", py_list3(&v0));
    let _ = writeln!(s, "MASSES = {}\n", py_floats(&lattice.masses));
    let _ = writeln!(
        s,
        "FIXED = [{}]\n",
        fixed
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !lattice.forces.is_empty() {
        let _ = writeln!(s, "FORCES = {}\n", py_list3(&lattice.forces));
    } else {
        s.push_str("FORCES = None\n\n");
    }
    s.push_str("# One spring per row: node a, node b, stiffness k, damping kd, rest length.\nSPRINGS = [\n");
    for sp in &lattice.springs {
        let _ = writeln!(
            s,
            "    ({}, {}, {:?}, 0.0, {:?}),",
            sp.a, sp.b, sp.k, sp.rest_length
        );
    }
    s.push_str("]\n\n");
    s.push_str(
        r#"
def add_solver(node):
    """The SOFA counterpart of nurbspring's integrator."""
    if INTEGRATOR == "symplectic-euler":
        # v += dt M^-1 f(x, v), then x += dt v: nurbspring's symplectic Euler.
        node.addObject("EulerExplicitSolver", name="solver", symplectic=True)
    elif INTEGRATOR == "rk4":
        node.addObject("RungeKutta4Solver", name="solver")
    else:
        if INTEGRATOR == "newmark":
            node.addObject("NewmarkImplicitSolver", name="solver", rayleighMass=0.0,
                           rayleighStiffness=0.0)
        else:
            node.addObject("EulerImplicitSolver", name="solver", rayleighMass=0.0,
                           rayleighStiffness=0.0)
        node.addObject("CGLinearSolver", name="linear", iterations=1000, tolerance=1e-12,
                       threshold=1e-20)


def createScene(root):
    root.gravity = GRAVITY
    root.dt = DT
    root.addObject("RequiredPlugin", pluginName=[
        "Sofa.Component.ODESolver.Forward", "Sofa.Component.ODESolver.Backward",
        "Sofa.Component.LinearSolver.Iterative", "Sofa.Component.StateContainer",
        "Sofa.Component.Mass", "Sofa.Component.SolidMechanics.Spring",
        "Sofa.Component.Constraint.Projective", "Sofa.Component.MechanicalLoad",
    ])
    root.addObject("DefaultAnimationLoop")
    body = root.addChild("msm")
    add_solver(body)
    body.addObject("MechanicalObject", name="dofs", template="Vec3d", position=POSITIONS,
                   rest_position=REST_POSITIONS, velocity=VELOCITIES)
    body.addObject("DiagonalMass", name="mass", vertexMass=MASSES)
    if SPRINGS:
        body.addObject("SpringForceField", name="springs", template="Vec3d",
                       spring=" ".join(" ".join(str(x) for x in s) for s in SPRINGS))
    if FIXED:
        body.addObject(FIXED_CONSTRAINT, name="fixed", indices=FIXED)
    if NODE_DAMPING > 0.0:
        body.addObject("UniformVelocityDampingForceField", name="damping",
                       dampingCoefficient=NODE_DAMPING)
    if FORCES is not None:
        body.addObject("ConstantForceField", name="forces", forces=FORCES)
    return root
"#,
    );
    Ok(s)
}

/// Writes the SOFA scene of an MSM (atomically); returns what SOFA could not hold, for a warning.
pub fn write_msm_sofa(path: &Path, setup: &MsmSetup, source: &str) -> Result<Vec<String>, Error> {
    let file_name = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let text = sofa_scene(setup, source, &file_name).map_err(|message| {
        Error::option(
            "--format",
            "sofa",
            format!("{}: {message}", setup.path.display()),
        )
    })?;
    write_atomic_bytes(path, text.as_bytes())?;
    Ok(sofa_limitations(setup))
}
