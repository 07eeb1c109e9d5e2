#!/usr/bin/env python3
"""One symplectic-Euler step of the 256 x 256 spring lattice in NVIDIA Warp on the CPU, f32
(Warp's vec3 is float32), the peer of `msm/symplectic_euler_step/256x256` in
crates/msm/benches/step.rs. Lattice, state and step: bench-peers/msm_lattice.py. Per step:
zero the forces, one launch over springs with atomic adds to both nodes, one launch over nodes
for the update. Warp runs CPU launches on one thread.

Run: /tmp/peers2/bin/python bench-peers/msm_step_warp.py [DIR]  (DIR: nurbspring's dump)
"""
import importlib.metadata as md
import os
import statistics
import sys
import time

import numpy as np
import warp as wp

import msm_lattice as L
from results import record

wp.config.quiet = True
wp.init()


@wp.kernel
def spring_forces(x: wp.array(dtype=wp.vec3), sa: wp.array(dtype=wp.int32),
                  sb: wp.array(dtype=wp.int32), sk: wp.array(dtype=wp.float32),
                  sl: wp.array(dtype=wp.float32), f: wp.array(dtype=wp.vec3)):
    e = wp.tid()
    i = sa[e]
    j = sb[e]
    d = x[i] - x[j]
    r = wp.length(d)
    fa = sk[e] * (sl[e] / r - 1.0) * d
    wp.atomic_add(f, i, fa)
    wp.atomic_sub(f, j, fa)


@wp.kernel
def integrate(x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
              f: wp.array(dtype=wp.vec3), inv_m: wp.array(dtype=wp.float32),
              g: wp.array(dtype=wp.vec3), dt: wp.float32):
    i = wp.tid()
    v[i] = v[i] + dt * (f[i] * inv_m[i] + g[i])
    x[i] = x[i] + dt * v[i]


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/nurbspring-agree"
    dev = "cpu"
    x0, a, b, k, rest = L.lattice()
    n, s = x0.shape[0], a.size
    print(f"warp {md.version('warp-lang')} on {dev} (f32): {n} nodes, {s} springs")
    im, gg = L.per_node_constants()
    sa = wp.array(a, dtype=wp.int32, device=dev)
    sb = wp.array(b, dtype=wp.int32, device=dev)
    sk = wp.array(k.astype(np.float32), dtype=wp.float32, device=dev)
    sl = wp.array(rest.astype(np.float32), dtype=wp.float32, device=dev)
    inv_m = wp.array(im.astype(np.float32), dtype=wp.float32, device=dev)
    g = wp.array(gg.astype(np.float32), dtype=wp.vec3, device=dev)
    f = wp.zeros(n, dtype=wp.vec3, device=dev)
    state = {}

    def reset():
        xs, vs = L.initial_state(x0)
        state["x"] = wp.array(xs.astype(np.float32), dtype=wp.vec3, device=dev)
        state["v"] = wp.array(vs.astype(np.float32), dtype=wp.vec3, device=dev)

    def step():
        x, v = state["x"], state["v"]
        f.zero_()
        wp.launch(spring_forces, dim=s, inputs=[x, sa, sb, sk, sl, f], device=dev)
        wp.launch(integrate, dim=n, inputs=[x, v, f, inv_m, g, wp.float32(L.DT)], device=dev)

    def run(steps):
        reset()
        for _ in range(steps):
            step()
        wp.synchronize_device(dev)
        return state["x"].numpy().astype(np.float64), state["v"].numpy().astype(np.float64)

    L.check(d, x0, run)
    reset()
    for _ in range(50):
        step()
    wp.synchronize_device(dev)
    if os.environ.get("CHECK_ONLY"):
        return
    print(f"== timing, load average {os.getloadavg()}")
    block, blocks = 20, 40
    ts = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(block):
            step()
        wp.synchronize_device(dev)
        ts.append((time.perf_counter() - t0) / block)
    record("warp", "step_256x256", ts, version=md.version("warp-lang"),
           threads=os.environ.get("RAYON_NUM_THREADS"))
    med = statistics.median(ts)
    print(f"warp (cpu, f32) step: median {med * 1e3:.3f} ms, min {min(ts) * 1e3:.3f} ms "
          f"({blocks} blocks of {block} steps); {med / s * 1e9:.2f} ns/spring")
    print(f"== load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
