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

mod newton;
pub use newton::{newton_edge_ke, newton_plan, newton_script, write_msm_newton};

/// The rows `(a, b, k w, c, rest length)` of every spring of `lattice` as a Python list's body,
/// closed by `]` (the SOFA and Newton scripts list springs alike).
fn spring_rows(s: &mut String, lattice: &nurbspring_msm::SpringLattice) {
    for sp in &lattice.springs {
        let _ = writeln!(
            s,
            "    ({}, {}, {:?}, {:?}, {:?}),",
            sp.a,
            sp.b,
            sp.stiffness(),
            sp.damping,
            sp.rest_length
        );
    }
    s.push_str("]\n\n");
}

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
            NpyArray::f64(springs.iter().map(|s| s.stiffness()).collect()),
        ),
        (
            "spring_weight",
            NpyArray::f64(springs.iter().map(|s| s.weight).collect()),
        ),
        (
            "spring_damping",
            NpyArray::f64(springs.iter().map(|s| s.damping).collect()),
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
        (
            "hinges",
            matrix(
                NpyArray::i64(
                    lattice
                        .hinges
                        .iter()
                        .flat_map(|h| h.nodes.map(|a| a as i64))
                        .collect(),
                ),
                4,
                lattice.hinges.len(),
            ),
        ),
        (
            "hinge_k",
            NpyArray::f64(lattice.hinges.iter().map(|h| h.stiffness()).collect()),
        ),
        (
            "hinge_weight",
            NpyArray::f64(lattice.hinges.iter().map(|h| h.weight).collect()),
        ),
        (
            "hinge_rest_angle",
            NpyArray::f64(lattice.hinges.iter().map(|h| h.rest_angle).collect()),
        ),
        (
            "hinge_kind",
            NpyArray::strings(
                lattice
                    .hinges
                    .iter()
                    .map(|h| h.kind.name().to_string())
                    .collect(),
            ),
        ),
        (
            "triangles",
            matrix(
                NpyArray::i64(
                    lattice
                        .triangles
                        .iter()
                        .flat_map(|t| t.map(|a| a as i64))
                        .collect(),
                ),
                3,
                lattice.triangles.len(),
            ),
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

/// Largest rest angle of a hinge that SOFA's `FastTriangularBendingSprings` holds [rad]: its
/// energy has no rest angle, so only a flat rest shape is stress-free in it (the round-off of
/// a flat lattice's angles is ~1e-16).
pub const SOFA_FLAT_REST: f64 = 1e-9;

/// One `FastTriangularBendingSprings` of a SOFA scene: its `bendingStiffness` and the
/// triangles of its `MeshTopology`, whose interior edges are exactly its hinges.
#[derive(Clone, Debug, PartialEq)]
pub struct SofaBending {
    /// `bendingStiffness`.
    pub stiffness: f64,
    /// The triangles (pairs of each hinge's two triangles).
    pub triangles: Vec<[usize; 3]>,
    /// Indices of the model's hinges it holds.
    pub hinges: Vec<usize>,
}

/// The `bendingStiffness` `b` of SOFA's `FastTriangularBendingSprings` that gives a flat hinge
/// of stiffness `k w` (nodes at `x`: edge x0–x1, wings x2, x3) our energy `½ k w θ²` to second
/// order in θ: SOFA's energy is `½ λ |R|²` with `λ = (2/3) l b (h_A + h_B) / (h_A² h_B²)` and
/// `|R| = θ h_A h_B / (h_A + h_B) + O(θ²)` (Volino & Magnenat-Thalmann 2006; docs/export.md),
/// so `b = 3 k w (h_A + h_B) / (2 l)`.
///
/// ```
/// use nurbspring_scene::msm_export::sofa_bending_stiffness;
/// // A unit square cut along its diagonal: l = √2, h_A = h_B = 1/√2, so b = 3 k w / 2.
/// let x = [[0., 0., 0.], [1., 1., 0.], [1., 0., 0.], [0., 1., 0.]];
/// assert!((sofa_bending_stiffness(&x, 2.0) - 3.0).abs() < 1e-15);
/// ```
pub fn sofa_bending_stiffness(x: &[[f64; 3]; 4], kw: f64) -> f64 {
    use nurbspring_geom::{cross, norm};
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let e = sub(x[1], x[0]);
    let l = norm(e);
    let h_a = norm(cross(e, sub(x[2], x[0]))) / l;
    let h_b = norm(cross(sub(x[3], x[0]), e)) / l;
    1.5 * kw * (h_a + h_b) / l
}

/// The hinges of a lattice as SOFA `FastTriangularBendingSprings` components, or why SOFA
/// cannot hold them: a rest angle beyond [`SOFA_FLAT_REST`] (SOFA's energy has none). Each
/// component holds one bending stiffness and makes a bending spring on every edge that two of
/// the triangles of its topology share. Hinges with one converted stiffness
/// ([`sofa_bending_stiffness`], equal to 1e-12) share a component when the shared edges of
/// their triangles are exactly those hinges, and are otherwise split into components whose
/// hinges' triangles share no edge (each component's shared edges are then its hinges alone).
/// A model whose hinges all differ gets one component per hinge.
pub fn sofa_bending(lattice: &nurbspring_msm::SpringLattice) -> Result<Vec<SofaBending>, String> {
    use std::collections::HashMap;
    if let Some((i, h)) = lattice
        .hinges
        .iter()
        .enumerate()
        .find(|(_, h)| h.rest_angle.abs() > SOFA_FLAT_REST)
    {
        return Err(format!(
            "hinge {i} has the rest angle {:.6} rad: SOFA's FastTriangularBendingSprings (the \
             bending force field SOFA ships) has no rest angle, its energy 1/2 lambda |R|^2 \
             vanishes only when the two triangles are flat, so a curved rest shape would be \
             loaded at rest; export it with --format newton or npz",
            h.rest_angle
        ));
    }
    let stiffness: Vec<f64> = lattice
        .hinges
        .iter()
        .map(|h| sofa_bending_stiffness(&h.nodes.map(|a| lattice.positions[a]), h.stiffness()))
        .collect();
    // Groups of one stiffness (to 1e-12), in order of first appearance.
    let mut groups: Vec<(f64, Vec<usize>)> = Vec::new();
    for (i, &b) in stiffness.iter().enumerate() {
        match groups
            .iter_mut()
            .find(|(g, _)| (g - b).abs() <= 1e-12 * g.abs().max(b.abs()))
        {
            Some((_, members)) => members.push(i),
            None => groups.push((b, vec![i])),
        }
    }
    let triangles_of = |i: usize| {
        let [x0, x1, x2, x3] = lattice.hinges[i].nodes;
        [[x0, x1, x2], [x1, x0, x3]]
    };
    let key = |t: [usize; 3]| {
        let mut k = t;
        k.sort_unstable();
        k
    };
    let mut out = Vec::new();
    for (b, members) in groups {
        // The union of the group's triangles, and the edges two of them share.
        let mut triangles: Vec<[usize; 3]> = Vec::new();
        let mut seen = HashMap::new();
        for &i in &members {
            for t in triangles_of(i) {
                if seen.insert(key(t), ()).is_none() {
                    triangles.push(t);
                }
            }
        }
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        for t in &triangles {
            for c in 0..3 {
                let (p, q) = (t[c], t[(c + 1) % 3]);
                *edges.entry((p.min(q), p.max(q))).or_insert(0) += 1;
            }
        }
        let mut interior: Vec<(usize, usize)> = edges
            .iter()
            .filter(|(_, n)| **n >= 2)
            .map(|(e, _)| *e)
            .collect();
        interior.sort_unstable();
        let mut own: Vec<(usize, usize)> = members
            .iter()
            .map(|&i| {
                let [x0, x1, ..] = lattice.hinges[i].nodes;
                (x0.min(x1), x0.max(x1))
            })
            .collect();
        own.sort_unstable();
        if interior == own && edges.values().all(|&n| n <= 2) {
            out.push(SofaBending {
                stiffness: b,
                triangles,
                hinges: members,
            });
            continue;
        }
        // Colour the hinges so that no two of a colour share an edge of their triangles: then
        // every edge of a colour's triangles lies on one triangle, except the colour's hinges,
        // which lie on two, and SOFA finds exactly those hinges in the colour's topology.
        let edges_of = |i: usize| {
            let mut e: Vec<(usize, usize)> = triangles_of(i)
                .iter()
                .flat_map(|t| {
                    (0..3).map(move |c| (t[c].min(t[(c + 1) % 3]), t[c].max(t[(c + 1) % 3])))
                })
                .collect();
            e.sort_unstable();
            e.dedup();
            e
        };
        let mut colours: Vec<(HashMap<(usize, usize), ()>, SofaBending)> = Vec::new();
        for &i in &members {
            let edges = edges_of(i);
            let free = colours
                .iter_mut()
                .find(|(used, _)| edges.iter().all(|e| !used.contains_key(e)));
            let (used, component) = match free {
                Some(c) => c,
                None => {
                    colours.push((
                        HashMap::new(),
                        SofaBending {
                            stiffness: b,
                            triangles: Vec::new(),
                            hinges: Vec::new(),
                        },
                    ));
                    colours.last_mut().expect("pushed")
                }
            };
            for e in edges {
                used.insert(e, ());
            }
            component.triangles.extend(triangles_of(i));
            component.hinges.push(i);
        }
        out.extend(colours.into_iter().map(|(_, c)| c));
    }
    Ok(out)
}

/// What SOFA's components cannot hold of a model, said once for messages and the scene's header.
pub fn sofa_limitations(setup: &MsmSetup) -> Vec<String> {
    let lattice = setup.model.lattice();
    let mut out = Vec::new();
    if !lattice.hinges.is_empty() {
        out.push(format!(
            "the model's {} hinges are FastTriangularBendingSprings (Volino's linear bending, \
             energy 1/2 lambda |R|^2 of the bending vector R): bendingStiffness converted so \
             that it equals nurbspring's 1/2 k w theta^2 to second order about the flat rest \
             state; |R| follows the chord of a folded wing, not its angle, so SOFA's energy is \
             (2 sin(theta/2)/theta)^2 of ours (0.08 % less at 0.1 rad, 2.1 % at 0.5 rad, 8.1 % at \
             1 rad), and its bending vector also grows under in-plane motion of the nodes, which \
             ours does not (docs/export.md)",
            lattice.hinges.len()
        ));
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
/// with linear elements (SOFA's springs cannot express them), with node damping that varies
/// from node to node, or with hinges SOFA's bending cannot hold ([`sofa_bending`]).
pub fn sofa_scene(setup: &MsmSetup, source: &str, file_name: &str) -> Result<String, String> {
    let lattice = setup.model.lattice();
    if !lattice.elements.is_empty() {
        let mut classes: Vec<String> = lattice.elements.iter().map(|e| e.class().name()).collect();
        classes.sort();
        classes.dedup();
        return Err(format!(
            "the model has {} linear elements (classes {}; energy 1/2 k w |sum_i c_i u_i|^2 on \
             the displacements), which SOFA's spring components cannot express (a scalar rest \
             length, two nodes), and leaving them out would change the model; export it with \
             --format npz{}",
            lattice.elements.len(),
            classes.join(", "),
            if lattice.springs.is_empty() {
                ", or derive a spring model with `derive --derivation paper`"
            } else {
                ""
            }
        ));
    }
    let free = setup.model.free_nodes();
    if let Some(w) = free
        .windows(2)
        .find(|w| lattice.damping[w[0]] != lattice.damping[w[1]])
    {
        return Err(format!(
            "its node damping varies from node to node (gamma = {} at node {}, {} at node {}), \
             and SOFA's UniformVelocityDampingForceField holds one coefficient; export it with \
             --format newton or npz",
            lattice.damping[w[0]], w[0], lattice.damping[w[1]], w[1]
        ));
    }
    let bending = sofa_bending(lattice)?;
    let (x0, v0) = initial_nodes(setup);
    let fixed: Vec<usize> = (0..lattice.n_nodes())
        .filter(|&a| lattice.fixed[a])
        .collect();
    // One coefficient: the free nodes' (checked equal above).
    let damping = free.first().map_or(0.0, |&a| lattice.damping[a]);
    let limitations = sofa_limitations(setup);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\"\"\"SOFA scene of a nurbspring mass-spring model, written by `nurbspring export --format sofa`.\n\n\
         Source: {source}\n\
         {} nodes ({} fixed), {} springs, {} hinges. Run it with `runSofa {file_name}` (SOFA 24.06\n\
         or later with SofaPython3) or load it from Python with `Sofa.Simulation`.",
        lattice.n_nodes(),
        fixed.len(),
        lattice.springs.len(),
        lattice.hinges.len()
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
        "\nA spring's kd is nurbspring's axial damping c (the force -c ((v_a - v_b).n) n, as SOFA's\n\
         SpringForceField has it); the node damping -gamma v is UniformVelocityDampingForceField.\n\"\"\"\n\n",
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
    spring_rows(&mut s, lattice);
    s.push_str(
        "# FastTriangularBendingSprings components: bendingStiffness and the triangles of their\n\
         # MeshTopology (the interior edges of each topology are its hinges).\nBENDING = [\n",
    );
    for b in &bending {
        let _ = write!(s, "    ({:?}, [", b.stiffness);
        for (i, t) in b.triangles.iter().enumerate() {
            if i > 0 {
                s.push_str(", ");
            }
            let _ = write!(s, "[{}, {}, {}]", t[0], t[1], t[2]);
        }
        s.push_str("]),\n");
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
        "Sofa.Component.Topology.Container.Constant",
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
    if BENDING:
        # A topology of every node first, so that components looking for the node's topology
        # (the mass) find one of the right size; each bending component links its own.
        body.addObject("MeshTopology", name="topology", position=REST_POSITIONS,
                       triangles=sorted({tuple(t) for _, ts in BENDING for t in ts}))
    for c, (stiffness, triangles) in enumerate(BENDING):
        body.addObject("MeshTopology", name=f"bendingTopology{c}", triangles=triangles)
        body.addObject("FastTriangularBendingSprings", name=f"bending{c}",
                       bendingStiffness=stiffness, topology=f"@bendingTopology{c}")
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
    write_export(path, setup, "sofa", |file_name| {
        sofa_scene(setup, source, file_name)
    })?;
    Ok(sofa_limitations(setup))
}

/// Writes (atomically) the text `build(file name)` makes of an MSM for `--format format`; a
/// model the format cannot express is refused naming the flag and the model file.
fn write_export(
    path: &Path,
    setup: &MsmSetup,
    format: &str,
    build: impl FnOnce(&str) -> Result<String, String>,
) -> Result<(), Error> {
    let file_name = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let text = build(&file_name).map_err(|message| {
        Error::option(
            "--format",
            format,
            format!("{}: {message}", setup.path.display()),
        )
    })?;
    write_atomic_bytes(path, text.as_bytes())?;
    Ok(())
}
