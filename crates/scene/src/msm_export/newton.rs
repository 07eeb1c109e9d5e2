//! The Newton (NVIDIA's Warp-based engine) export: a Python script that builds the model with
//! Newton's `ModelBuilder` and steps it with its semi-implicit solver (docs/export.md).

#[allow(unused_imports)]
use super::*;

/// Newton's `edge_ke` for a hinge of stiffness `k w` at rest positions `x` (edge x0–x1, wings
/// x2, x3), used by the script's `--bending newton`: Newton's semi-implicit bending force is
/// `−edge_ke |e| (θ − θ0) d_i` with `d_i = |N_i| ∂θ/∂x_i` for the wings (the triangle's doubled
/// area times our gradient, the edge nodes mixing both), so with equal triangle areas it is
/// ours when `edge_ke = k w / (|e| |N|)`; the mean of the two areas is used.
pub fn newton_edge_ke(x: &[[f64; 3]; 4], kw: f64) -> f64 {
    use nurbspring_geom::{cross, norm};
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let e = sub(x[1], x[0]);
    let n1 = norm(cross(e, sub(x[2], x[0])));
    let n2 = norm(cross(sub(x[3], x[0]), e));
    kw / (norm(e) * 0.5 * (n1 + n2))
}

/// How Newton runs a model, or why it cannot: the substeps of Δt its semi-implicit solver
/// (symplectic Euler) takes, as `simulate` schedules symplectic Euler (below the lattice's
/// stability limit), and what the script does differently from the model's own run.
pub fn newton_plan(setup: &MsmSetup) -> Result<(usize, Vec<String>), String> {
    let lattice = setup.model.lattice();
    if !lattice.elements.is_empty() {
        return Err(format!(
            "the model has {} linear elements (energy 1/2 k w |sum_i c_i u_i|^2 on the \
             displacements), which Newton's particle model (springs, triangles, bending edges, \
             tetrahedra) cannot express; export it with --format npz",
            lattice.elements.len()
        ));
    }
    let dt = setup.run.dt;
    let (schedule, _) = nurbspring_sim::Schedule::stable(
        &setup.model,
        &setup.initial.q,
        IntegratorKind::SymplecticEuler,
        dt,
    )
    .map_err(|e| format!("its stability limit cannot be computed: {e}"))?;
    if schedule.integrator != IntegratorKind::SymplecticEuler {
        return Err(format!(
            "dt = {dt} is above the explicit stability limit of the model (or needs more than {} \
             substeps below it), and Newton's SolverSemiImplicit is explicit (symplectic Euler); \
             run it with a smaller simulation.dt",
            nurbspring_sim::MAX_SUBSTEPS
        ));
    }
    let mut notes = Vec::new();
    if setup.run.integrator != IntegratorKind::SymplecticEuler {
        notes.push(format!(
            "the model records the integrator {}; Newton's SolverSemiImplicit is symplectic \
             Euler, which the script runs ({} substeps per step of {dt})",
            setup.run.integrator.name(),
            schedule.substeps
        ));
    }
    Ok((schedule.substeps, notes))
}

/// The Newton script (NVIDIA Newton, the Warp-based engine: `pip install newton`) of an MSM:
/// it builds the model with Newton's `ModelBuilder` (particles, springs, and for `--bending
/// newton` bending edges), steps it with `SolverSemiImplicit` on the CPU (or a named device) and
/// writes the probes' trajectory as `trajectory.csv` does (docs/export.md).
pub fn newton_script(setup: &MsmSetup, source: &str, file_name: &str) -> Result<String, String> {
    let lattice = setup.model.lattice();
    let (substeps, notes) = newton_plan(setup)?;
    let (x0, v0) = initial_nodes(setup);
    let fixed: Vec<bool> = lattice.fixed.clone();
    let curve = lattice.grid.is_some_and(|(_, n_v)| n_v == 1);
    let labels: Vec<String> = setup
        .probe_nodes
        .iter()
        .map(|&a| crate::run::probe_label(Some(a), lattice.params.as_ref().map(|p| p[a]), curve))
        .collect();
    let header = crate::run::trajectory_header(&labels).join(",");
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\"\"\"Newton scene of a nurbspring mass-spring model, written by `nurbspring export --format newton`.\n\n\
         Source: {source}\n\
         {} nodes ({} fixed), {} springs, {} hinges. NVIDIA Newton (the Warp-based physics engine,\n\
         `pip install newton`; written for newton 1.8 with warp-lang 1.19) builds it with its\n\
         ModelBuilder and steps it with SolverSemiImplicit (symplectic Euler, nurbspring's\n\
         `symplectic-euler`), Δt = DT in SUBSTEPS substeps, on the CPU unless --device says otherwise.\n\n\
         usage: python3 {file_name} [trajectory.csv] [--device cpu|cuda:0] [--bending nurbspring|newton]\n\n\
         It writes the probe nodes' trajectory in the format of nurbspring's trajectory.csv.\n\n\
         Newton's own components: particles (fixed nodes without the ACTIVE flag), springs (ke = k w,\n\
         kd = the spring's axial damping c, rest lengths the model's), gravity, the semi-implicit\n\
         solver. Added by this script as Warp kernels that add to the particle forces before each\n\
         step (docs/export.md): the node damping -gamma v and node forces (Newton's particles have\n\
         neither), and by default the hinges with nurbspring's force k w (theta - theta0) dtheta/dx,\n\
         the gradient of 1/2 k w (theta - theta0)^2. `--bending newton` runs the hinges as Newton's\n\
         own bending edges instead, edge_ke converted at rest: Newton's bending force is not the\n\
         gradient of an energy (it scales each wing's term by its triangle's current area and the\n\
         edge's current length), so it equals nurbspring's only to first order about the rest state\n\
         and for triangles of equal area. Newton works in single precision (float32).",
        lattice.n_nodes(),
        fixed.iter().filter(|&&f| f).count(),
        lattice.springs.len(),
        lattice.hinges.len()
    );
    if !notes.is_empty() {
        s.push_str("\nNot as nurbspring runs it:\n");
        for n in &notes {
            let _ = writeln!(s, "- {n}.");
        }
    }
    s.push_str("\"\"\"\nimport argparse\nimport math\n\nimport numpy as np\n\n");
    let _ = writeln!(s, "GRAVITY = {}", py_floats(&lattice.gravity));
    let _ = writeln!(s, "DT = {:?}", setup.run.dt);
    let _ = writeln!(s, "SUBSTEPS = {substeps}");
    let _ = writeln!(s, "T_END = {:?}", setup.run.t_end);
    let _ = writeln!(s, "SAVE_EVERY = {}", setup.save_every);
    let _ = writeln!(
        s,
        "PROBES = [{}]",
        setup
            .probe_nodes
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(s, "HEADER = {header:?}\n");
    let _ = writeln!(s, "POSITIONS = {}\n", py_list3(&x0));
    let _ = writeln!(s, "VELOCITIES = {}\n", py_list3(&v0));
    let _ = writeln!(s, "MASSES = {}\n", py_floats(&lattice.masses));
    let _ = writeln!(
        s,
        "FIXED = [{}]\n",
        fixed
            .iter()
            .map(|&f| if f { "True" } else { "False" })
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(s, "NODE_DAMPING = {}\n", py_floats(&lattice.damping));
    if lattice.forces.is_empty() {
        s.push_str("FORCES = None\n\n");
    } else {
        let _ = writeln!(s, "FORCES = {}\n", py_list3(&lattice.forces));
    }
    s.push_str(
        "# One spring per row: node a, node b, ke = k w, kd = c, rest length.\nSPRINGS = [\n",
    );
    spring_rows(&mut s, lattice);
    s.push_str(
        "# One hinge per row: edge x0, x1, wing x2 of (x0, x1, x2), wing x3 of (x1, x0, x3),\n\
         # k w, rest angle theta0, Newton's edge_ke for --bending newton.\nHINGES = [\n",
    );
    for h in &lattice.hinges {
        let x = h.nodes.map(|a| lattice.positions[a]);
        let _ = writeln!(
            s,
            "    ({}, {}, {}, {}, {:?}, {:?}, {:?}),",
            h.nodes[0],
            h.nodes[1],
            h.nodes[2],
            h.nodes[3],
            h.stiffness(),
            h.rest_angle,
            newton_edge_ke(&x, h.stiffness())
        );
    }
    s.push_str("]\n");
    s.push_str(NEWTON_RUNNER);
    Ok(s)
}

/// The code of the Newton script after its data.
const NEWTON_RUNNER: &str = r#"

def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="trajectory_newton.csv")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--bending", choices=["nurbspring", "newton"], default="nurbspring")
    args = parser.parse_args()

    import warp as wp

    wp.config.quiet = True
    import newton

    wp.init()

    @wp.kernel
    def node_forces(v: wp.array(dtype=wp.vec3), gamma: wp.array(dtype=float),
                    force: wp.array(dtype=wp.vec3), f: wp.array(dtype=wp.vec3)):
        # f += f_node - gamma v (nurbspring's node damping and node forces).
        i = wp.tid()
        f[i] = f[i] + force[i] - gamma[i] * v[i]

    @wp.kernel
    def hinge_forces(x: wp.array(dtype=wp.vec3), nodes: wp.array2d(dtype=int),
                     kw: wp.array(dtype=float), rest: wp.array(dtype=float),
                     f: wp.array(dtype=wp.vec3)):
        # The elastic force -k w (theta - theta0) dtheta/dx_i of a hinge (docs/math.md §5.2).
        h = wp.tid()
        i0 = nodes[h, 0]
        i1 = nodes[h, 1]
        i2 = nodes[h, 2]
        i3 = nodes[h, 3]
        e = x[i1] - x[i0]
        a = x[i2] - x[i0]
        b = x[i3] - x[i0]
        n1 = wp.cross(e, a)
        n2 = wp.cross(b, e)
        l2 = wp.dot(e, e)
        l = wp.sqrt(l2)
        theta = wp.atan2(wp.dot(e, wp.cross(n1, n2)), l * wp.dot(n1, n2))
        d = theta - rest[h]
        if d > wp.pi:
            d = d - 2.0 * wp.pi
        if d <= -wp.pi:
            d = d + 2.0 * wp.pi
        g2 = n1 * (-l / wp.dot(n1, n1))
        g3 = n2 * (-l / wp.dot(n2, n2))
        t2 = wp.dot(a, e) / l2
        t3 = wp.dot(b, e) / l2
        s = -kw[h] * d
        wp.atomic_add(f, i0, (g2 * (t2 - 1.0) + g3 * (t3 - 1.0)) * s)
        wp.atomic_add(f, i1, (g2 * (-t2) - g3 * t3) * s)
        wp.atomic_add(f, i2, g2 * s)
        wp.atomic_add(f, i3, g3 * s)

    builder = newton.ModelBuilder(gravity=tuple(GRAVITY))
    for a, (x, v) in enumerate(zip(POSITIONS, VELOCITIES)):
        builder.add_particle(pos=wp.vec3(*x), vel=wp.vec3(*v),
                             mass=0.0 if FIXED[a] else MASSES[a],
                             flags=0 if FIXED[a] else int(newton.ParticleFlags.ACTIVE))
    for a, b, ke, kd, rest in SPRINGS:
        builder.add_spring(a, b, ke, kd, 0.0)
    if args.bending == "newton":
        # Newton's edge (i, j, k, l): wings i, j, edge k -> l; triangles (i, k, l), (j, l, k).
        for x0, x1, x2, x3, kw, rest, edge_ke in HINGES:
            builder.add_edge(x2, x3, x0, x1, rest=rest, edge_ke=edge_ke, edge_kd=0.0)
    model = builder.finalize(device=args.device)
    model.particle_grid = None  # no particle-particle contact
    model.particle_max_velocity = 1.0e30
    if SPRINGS:
        # The model's rest lengths (Newton's builder takes the initial distances).
        model.spring_rest_length.assign(np.array([sp[4] for sp in SPRINGS], dtype=np.float32))
    gamma = wp.array(np.array(NODE_DAMPING, dtype=np.float32), dtype=float, device=args.device)
    force = wp.array(np.array(FORCES if FORCES is not None else [[0.0] * 3] * len(POSITIONS),
                              dtype=np.float32), dtype=wp.vec3, device=args.device)
    own_hinges = args.bending == "nurbspring" and len(HINGES) > 0
    if own_hinges:
        nodes = wp.array(np.array([h[:4] for h in HINGES], dtype=np.int32), dtype=int,
                         device=args.device)
        kw = wp.array(np.array([h[4] for h in HINGES], dtype=np.float32), dtype=float,
                      device=args.device)
        rest = wp.array(np.array([h[5] for h in HINGES], dtype=np.float32), dtype=float,
                        device=args.device)

    solver = newton.solvers.SolverSemiImplicit(model)
    state, other = model.state(), model.state()
    control = model.control()
    h = DT / SUBSTEPS
    # As many steps as nurbspring takes: T_END / DT, rounded when within 1e-9, else up.
    r = T_END / DT
    steps = int(round(r)) if abs(r - round(r)) <= 1e-9 * max(round(r), 1.0) else int(math.ceil(r))
    rows = [[0.0] + [float(c) for p in PROBES for c in state.particle_q.numpy()[p]]]
    for step in range(1, steps + 1):
        for _ in range(SUBSTEPS):
            state.clear_forces()
            wp.launch(node_forces, dim=model.particle_count,
                      inputs=[state.particle_qd, gamma, force], outputs=[state.particle_f],
                      device=args.device)
            if own_hinges:
                wp.launch(hinge_forces, dim=len(HINGES), inputs=[state.particle_q, nodes, kw, rest],
                          outputs=[state.particle_f], device=args.device)
            solver.step(state, other, control, None, h)
            state, other = other, state
        if step % SAVE_EVERY == 0:
            q = state.particle_q.numpy()
            rows.append([step * DT] + [float(c) for p in PROBES for c in q[p]])
    np.savetxt(args.out, np.array(rows), delimiter=",", header=HEADER, comments="",
               fmt="%.9g")


if __name__ == "__main__":
    main()
"#;

/// Writes the Newton script of an MSM (atomically); returns what the script does differently
/// from the model's own run, for a warning.
pub fn write_msm_newton(path: &Path, setup: &MsmSetup, source: &str) -> Result<Vec<String>, Error> {
    write_export(path, setup, "newton", |file_name| {
        newton_script(setup, source, file_name)
    })?;
    Ok(newton_plan(setup)
        .map(|(_, notes)| notes)
        .unwrap_or_default())
}
