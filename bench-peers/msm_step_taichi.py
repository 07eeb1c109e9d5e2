#!/usr/bin/env python3
"""One symplectic-Euler step of the 256 x 256 spring lattice in Taichi on the CPU, f64
(ti.init(arch=ti.cpu, default_fp=ti.f64)), the peer of `msm/symplectic_euler_step/256x256`
in crates/msm/benches/step.rs. Lattice, state and step: bench-peers/msm_lattice.py. One kernel
per step: clear the forces, one parallel loop over springs with atomic adds to both nodes,
one parallel loop over nodes for the update. Taichi uses all cores (2 here).

Run: /tmp/peers2/bin/python bench-peers/msm_step_taichi.py [DIR]  (DIR: nurbspring's dump)
"""
import importlib.metadata as md
import os
import statistics
import sys
import time

import numpy as np
import taichi as ti

import msm_lattice as L
from results import record

ti.init(arch=ti.cpu, default_fp=ti.f64, log_level=ti.WARN)


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/nurbspring-agree"
    x0, a, b, k, rest = L.lattice()
    n, s = x0.shape[0], a.size
    print(f"taichi {md.version('taichi')}: {n} nodes, {s} springs, "
          f"{ti.lang.impl.current_cfg().cpu_max_num_threads} CPU threads")
    x = ti.Vector.field(3, ti.f64, n)
    v = ti.Vector.field(3, ti.f64, n)
    f = ti.Vector.field(3, ti.f64, n)
    g = ti.Vector.field(3, ti.f64, n)
    inv_m = ti.field(ti.f64, n)
    sa = ti.field(ti.i32, s)
    sb = ti.field(ti.i32, s)
    sk = ti.field(ti.f64, s)
    sl = ti.field(ti.f64, s)
    sa.from_numpy(a)
    sb.from_numpy(b)
    sk.from_numpy(k)
    sl.from_numpy(rest)
    im, gg = L.per_node_constants()
    inv_m.from_numpy(im)
    g.from_numpy(gg)

    @ti.kernel
    def step(dt: ti.f64):
        for i in f:
            f[i] = ti.Vector([0.0, 0.0, 0.0])
        for e in sa:
            i, j = sa[e], sb[e]
            dd = x[i] - x[j]
            r = dd.norm()
            fa = sk[e] * (sl[e] / r - 1.0) * dd
            f[i] += fa
            f[j] -= fa
        for i in x:
            v[i] += dt * (f[i] * inv_m[i] + g[i])
            x[i] += dt * v[i]

    def reset():
        xs, vs = L.initial_state(x0)
        x.from_numpy(xs)
        v.from_numpy(vs)

    def run(steps):
        reset()
        for _ in range(steps):
            step(L.DT)
        ti.sync()
        return x.to_numpy(), v.to_numpy()

    L.check(d, x0, run)
    reset()
    for _ in range(50):
        step(L.DT)
    ti.sync()
    if os.environ.get("CHECK_ONLY"):
        return
    print(f"== timing, load average {os.getloadavg()}")
    block, blocks = 20, 40
    ts = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(block):
            step(L.DT)
        ti.sync()
        ts.append((time.perf_counter() - t0) / block)
    record("taichi", "step_256x256", ts, version=md.version("taichi"),
           threads=os.environ.get("RAYON_NUM_THREADS"))
    med = statistics.median(ts)
    print(f"taichi (cpu, f64) step: median {med * 1e3:.3f} ms, min {min(ts) * 1e3:.3f} ms "
          f"({blocks} blocks of {block} steps); {med / s * 1e9:.2f} ns/spring")
    print(f"== load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
