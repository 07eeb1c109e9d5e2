#!/usr/bin/env python3
"""One symplectic-Euler step of the 256 x 256 spring lattice in numpy (f64), the peer of
`msm/symplectic_euler_step/256x256` in crates/msm/benches/step.rs. Lattice, state and step:
bench-peers/msm_lattice.py. Per-spring forces vectorised, scattered to the nodes with
np.bincount (np.add.at is also timed; it is slower).

Run: /tmp/peers2/bin/python bench-peers/msm_step_numpy.py [DIR]  (DIR: nurbspring's dump)
"""
import os
import statistics
import sys
import time

import numpy as np

import msm_lattice as L
from results import record


def make_step(x0, a, b, k, rest, scatter="bincount"):
    inv_m, g = L.per_node_constants()
    n = x0.shape[0]

    def forces(x):
        d = x[a] - x[b]
        r = np.sqrt(np.einsum("ij,ij->i", d, d))
        fa = (k * (rest / r - 1.0))[:, None] * d
        if scatter == "bincount":
            f = np.empty((n, 3))
            for c in range(3):
                f[:, c] = np.bincount(a, fa[:, c], n) - np.bincount(b, fa[:, c], n)
        else:
            f = np.zeros((n, 3))
            np.add.at(f, a, fa)
            np.subtract.at(f, b, fa)
        return f

    def step(x, v):
        f = forces(x)
        v += L.DT * (f * inv_m[:, None] + g)
        x += L.DT * v

    return step


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/nurbspring-agree"
    x0, a, b, k, rest = L.lattice()
    print(f"numpy {np.__version__}: {x0.shape[0]} nodes, {a.size} springs")
    step = make_step(x0, a, b, k, rest)

    def run(n):
        x, v = L.initial_state(x0)
        for _ in range(n):
            step(x, v)
        return x, v

    L.check(d, x0, run)
    if os.environ.get("CHECK_ONLY"):
        return
    print(f"== timing, load average {os.getloadavg()}")
    for scatter, steps in (("bincount", 100), ("add.at", 10)):
        st = make_step(x0, a, b, k, rest, scatter)
        x, v = L.initial_state(x0)
        for _ in range(3):
            st(x, v)
        ts = []
        for _ in range(steps):
            t0 = time.perf_counter()
            st(x, v)
            ts.append(time.perf_counter() - t0)
        record("numpy", f"step_256x256_{scatter}", ts, version=np.__version__)
        med = statistics.median(ts)
        print(f"numpy ({scatter}) step: median {med * 1e3:.2f} ms, min {min(ts) * 1e3:.2f} ms "
              f"over {steps} steps; {med / a.size * 1e9:.1f} ns/spring")
    print(f"== load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
