#!/usr/bin/env python3
"""One semi-implicit (symplectic Euler) step of the 256 x 256 spring + hinge cloth in NVIDIA
Newton, the Warp-based engine, on the CPU (f32: Warp's vec3): the peer of
`cloth/symplectic_euler_step/256x256` in crates/msm/benches/cloth.rs, on the same mesh and
elements, read from nurbspring's dump (crates/msm/examples/cloth_dump.rs):

- particles with the dump's masses (the fixed nodes inactive), gravity;
- Newton's springs: ke = k w, kd = 0, the dump's rest lengths;
- Newton's bending edges on the hinges: the dump's rest angles, edge_ke = k w / (|e| |N|)
  (|N| the mean doubled area of the two triangles at rest), which gives nurbspring's hinge
  force to first order about the rest state (docs/export.md, `--bending newton`);
- SolverSemiImplicit.step: springs, bending, the particle update (no contact: particle_grid
  None, no shapes, no triangles).

Agreement check before timing: Newton's velocities after 1 and 10 steps from the dumped
initial state against nurbspring's (relative to max |v|; f32, and Newton's bending is not the
gradient of nurbspring's hinge energy, so they agree to first order only).
Timing: median and minimum of 40 blocks of 20 steps after 50 warm-up steps (the statistic of
bench-peers/msm_step_warp.py). Warp runs CPU launches on one thread.

Run: PYTHON bench-peers/cloth_step_newton.py DIR  (DIR: written by cloth_dump)
"""
import importlib.metadata as md
import json
import os
import statistics
import sys
import time

import numpy as np
import warp as wp

wp.config.quiet = True
import newton  # noqa: E402

wp.init()
DT = 1e-5  # benches/support/lattices.rs


def load(d):
    m = json.load(open(os.path.join(d, "cloth.json")))
    read = lambda name: np.fromfile(os.path.join(d, name), dtype="<f8").reshape(-1, 3)  # noqa: E731
    return m, {k: read(f"{k}.f64") for k in ("x0", "v0", "x1", "v1", "x10", "v10")}


def edge_ke(x, kw):
    e = x[1] - x[0]
    n1 = np.linalg.norm(np.cross(e, x[2] - x[0]))
    n2 = np.linalg.norm(np.cross(x[3] - x[0], e))
    return kw / (np.linalg.norm(e) * 0.5 * (n1 + n2))


def build(m, x0, v0):
    nodes = m["nodes"]
    rest_x = np.array([n["position"] for n in nodes])
    builder = newton.ModelBuilder(gravity=tuple(m["gravity"]))
    for a, n in enumerate(nodes):
        fixed = n.get("fixed", False)
        builder.add_particle(pos=wp.vec3(*x0[a]), vel=wp.vec3(*v0[a]),
                             mass=0.0 if fixed else n["mass"],
                             flags=0 if fixed else int(newton.ParticleFlags.ACTIVE))
    for s in m["springs"]:
        builder.add_spring(s["a"], s["b"], s["k"] * s.get("weight", 1.0), 0.0, 0.0)
    for h in m["hinges"]:
        x0_, x1_, x2_, x3_ = h["nodes"]
        kw = h["k"] * h.get("weight", 1.0)
        # Newton's edge (i, j, k, l): wings i, j, edge k -> l (as the Newton export writes it).
        builder.add_edge(x2_, x3_, x0_, x1_, rest=h["rest_angle"],
                         edge_ke=edge_ke(rest_x[h["nodes"]], kw), edge_kd=0.0)
    model = builder.finalize(device="cpu")
    model.particle_grid = None
    model.particle_max_velocity = 1.0e30
    model.spring_rest_length.assign(
        np.array([s["rest_length"] for s in m["springs"]], dtype=np.float32))
    return model


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/nurbspring-cloth"
    m, ref = load(d)
    t0 = time.perf_counter()
    model = build(m, ref["x0"], ref["v0"])
    print(f"newton {md.version('newton')}, warp {md.version('warp-lang')} on cpu (f32): "
          f"{model.particle_count} particles, {model.spring_count} springs, "
          f"{model.edge_count} bending edges (built in {time.perf_counter() - t0:.1f} s)")
    solver = newton.solvers.SolverSemiImplicit(model)
    states = [model.state(), model.state()]

    def reset():
        states[0].particle_q.assign(ref["x0"].astype(np.float32))
        states[0].particle_qd.assign(ref["v0"].astype(np.float32))

    def step():
        states[0].clear_forces()
        solver.step(states[0], states[1], None, None, DT)
        states.reverse()

    for steps in (1, 10):
        reset()
        for _ in range(steps):
            step()
        wp.synchronize_device("cpu")
        v = states[0].particle_qd.numpy().astype(np.float64)
        x = states[0].particle_q.numpy().astype(np.float64)
        v_ref, x_ref = ref[f"v{steps}"], ref[f"x{steps}"]
        dv = np.abs(v - v_ref).max() / np.abs(v_ref).max()
        dx = np.abs(x - x_ref).max() / np.abs(x_ref - ref["x0"]).max()
        print(f"after {steps} step(s): max |v - v_nurbspring| / max |v_nurbspring| = {dv:.2e}, "
              f"max |x - x_nurbspring| / max |x_nurbspring - x0| = {dx:.2e}")
        if not dv < 0.05:
            sys.exit("Newton's cloth does not follow nurbspring's: not timed")
    reset()
    for _ in range(50):
        step()
    wp.synchronize_device("cpu")
    print(f"== timing, load average {os.getloadavg()}")
    block, blocks = 20, 40
    ts = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(block):
            step()
        wp.synchronize_device("cpu")
        ts.append((time.perf_counter() - t0) / block)
    med = statistics.median(ts)
    print(f"newton (cpu, f32) cloth step: median {med * 1e3:.3f} ms, min {min(ts) * 1e3:.3f} ms "
          f"({blocks} blocks of {block} steps)")
    print(f"== load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
