#!/usr/bin/env python3
"""A backward-Euler step of the 128 x 128 sheet in NumPy/SciPy, against nurbspring's.

The lattice is bench-peers/msm_lattice.py's sheet at n = 128 (node mass 1/128², nodes 0 and
127·128 fixed), the initial state perturbed by 1e-4 sin(0.7 i), Δt = 1e-3: the job of
`msm/backward_euler_step/128x128` in crates/msm/benches/step.rs. One step solves, for the
end-of-step acceleration a of the free coordinates,

    R(a) = M a - f_springs(q0 + Δt v0 + Δt² a) - M g = 0,    v1 = v0 + Δt a,  q1 = q0 + Δt v1,

by Newton's method with the Newton matrix J = M + Δt² K_T assembled each iteration (per spring
k [(1 - l/|d|)(I - n nᵀ) + n nᵀ] on the four 3 × 3 blocks, COO then CSC, vectorised) and
factored by SuperLU (scipy.sparse.linalg.splu; SciPy has no sparse Cholesky), until
|R|∞ ≤ 1e-8 · max(|M a|∞, |M g|∞, largest spring force), the tolerance nurbspring runs with.
That is what a SciPy user writes; it refactors every iteration, where nurbspring keeps its
factor while Newton converges.

The result is checked against nurbspring's (the dump_msm example) before it is timed.
Run: python bench-peers/msm_step_scipy_be.py /tmp/nurbspring-agree
"""
import importlib.metadata as md
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import msm_lattice as L
from results import record

n = 128
DT = 1e-3
TOL = 1e-8


def setup():
    x0, a, b, k, rest = L.lattice(n)
    free = L.free_mask(n)
    mass = 1.0 / (n * n)
    # free coordinate index of each node coordinate (-1 on fixed nodes)
    dof = -np.ones((n * n, 3), dtype=np.int64)
    dof[free] = np.arange(3 * free.sum()).reshape(-1, 3)
    return x0, a, b, k, rest, free, mass, dof


def forces_and_tangent(x, a, b, k, rest, dof, want_tangent):
    """Spring forces on all nodes (nodes x 3), the largest spring force, and K_T on the free
    coordinates (CSC) when asked."""
    d = x[a] - x[b]
    length = np.linalg.norm(d, axis=1)
    unit = d / length[:, None]
    t = k * (rest - length)  # tension < 0 when stretched: f_a = t unit
    fa = t[:, None] * unit
    f = np.zeros_like(x)
    for c in range(3):
        f[:, c] = np.bincount(a, fa[:, c], x.shape[0]) - np.bincount(b, fa[:, c], x.shape[0])
    if not want_tangent:
        return f, np.abs(t).max(), None
    nn = unit[:, :, None] * unit[:, None, :]
    s = 1.0 - rest / length
    blk = k[:, None, None] * (s[:, None, None] * (np.eye(3)[None] - nn) + nn)
    rows, cols, vals = [], [], []
    for p, q, sign in ((a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)):
        r = dof[p][:, :, None].repeat(3, axis=2)
        cc = dof[q][:, None, :].repeat(3, axis=1)
        keep = (r >= 0) & (cc >= 0)
        rows.append(r[keep])
        cols.append(cc[keep])
        vals.append(sign * blk[keep])
    m = int(dof.max()) + 1
    kt = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(m, m)).tocsc()
    return f, np.abs(t).max(), kt


def step(q0, v0, ctx):
    x0, a, b, k, rest, free, mass, dof = ctx
    g = np.tile(L.GRAVITY, q0.size // 3)
    acc = np.zeros_like(q0)
    x = x0.copy()
    iterations = 0
    while True:
        q = q0 + DT * v0 + DT * DT * acc
        x[free] = q.reshape(-1, 3)
        f, fmax, kt = forces_and_tangent(x, a, b, k, rest, dof, True)
        r = mass * acc - f[free].ravel() - mass * g
        scale = max(np.abs(mass * acc).max(), np.abs(mass * g).max(), fmax)
        if np.abs(r).max() <= TOL * scale:
            break
        j = (mass * sp.identity(q0.size, format="csc") + DT * DT * kt).tocsc()
        acc -= spla.splu(j).solve(r)
        iterations += 1
        if iterations > 50:
            raise RuntimeError("Newton did not converge")
    v1 = v0 + DT * acc
    return q0 + DT * v1, v1, iterations


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/nurbspring-agree"
    ctx = setup()
    x0, a, _, _, _, free, _, _ = ctx
    print(f"numpy {np.__version__}, scipy {md.version('scipy')}: {n} x {n} nodes, {a.size} springs")
    xs, _ = L.initial_state(x0)
    q0 = xs[free].ravel()
    v0 = np.zeros_like(q0)
    q1, v1, its = step(q0, v0, ctx)
    ref = L.reference(d, "be128_v1")
    if ref is None:
        print(f"(no nurbspring dump in {d}; run the dump_msm example first)")
    else:
        dq0 = np.abs(L.reference(d, "be128_q0") - q0).max()
        dv = np.abs(ref - v1).max() / np.abs(ref).max()
        dq = np.abs(L.reference(d, "be128_q1") - q1).max()
        print(f"initial state vs nurbspring: {dq0:.2e}; after one step: velocities max |diff| / "
              f"max |v| = {dv:.2e}, positions {dq:.2e} ({its} Newton iterations)")
        assert dq0 < 1e-15 and dv < 1e-5, (dq0, dv)
    if os.environ.get("CHECK_ONLY"):
        return
    print(f"== timing, load average {os.getloadavg()}")
    ts, total = [], 0
    q, v = q0, v0
    for _ in range(5):
        t0 = time.perf_counter()
        q, v, its = step(q, v, ctx)
        ts.append(time.perf_counter() - t0)
        total += its
    print(f"scipy backward-Euler step (Newton + SuperLU): median {np.median(ts) * 1e3:.0f} ms, "
          f"min {min(ts) * 1e3:.0f} ms over {len(ts)} steps, {total / len(ts):.1f} Newton iterations a step")
    record("scipy", "backward_euler_step_128x128", ts, version=md.version("scipy"),
           newton_iterations=total / len(ts))
    print(f"== load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
