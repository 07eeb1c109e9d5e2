"""The lattice, initial state and checks shared by msm_step_{numpy,taichi,warp}.py.

It is `sheet(256)` of crates/msm/benches/step.rs, built here independently: the bilinear sheet
with corners S(0,0) = (0,0,0), S(0,1) = (0,1,0.1), S(1,0) = (1,0,0.1), S(1,1) = (1,1,0) sampled
at u_i = i/255, v_j = j/255 (node a = 256 i + j); structural springs between grid neighbours
along u and v (k = 1000) and shear springs on both diagonals of each cell (k = 500), 260,610
springs, rest length = initial length; node mass 1/256^2; gravity (0, 0, -9.81); nodes 0 and
255 * 256 fixed. The free coordinates (free nodes in increasing order, [x, y, z] each) are
perturbed by 1e-4 sin(0.7 i) so that the forces are non-zero; v = 0; dt = 1e-5.

One symplectic-Euler step, in every implementation:
    f_a = sum over springs at a of k (l - |d|) d/|d|,  d = x_a - x_b   (f_b gets -f_a)
    v += dt (f / m + g),  x += dt v                                    (free nodes only)
"""
import os

import numpy as np

N = 256
K_EDGE, K_DIAG = 1000.0, 500.0
MASS = 1.0 / (N * N)
GRAVITY = np.array([0.0, 0.0, -9.81])
DT = 1e-5


def lattice(n=N):
    """(x0 (nodes x 3), a, b, k, rest) with springs as int32 index arrays, on n x n nodes."""
    t = np.arange(n) / (n - 1)
    u, v = np.meshgrid(t, t, indexing="ij")  # node a = n i + j
    z = 0.1 * ((1 - u) * v + u * (1 - v))
    x0 = np.stack([u, v, z], axis=-1).reshape(-1, 3)
    idx = np.arange(n * n).reshape(n, n)
    pairs = [
        (idx[:-1, :], idx[1:, :], K_EDGE),    # along u
        (idx[:, :-1], idx[:, 1:], K_EDGE),    # along v
        (idx[:-1, :-1], idx[1:, 1:], K_DIAG),  # diagonal
        (idx[1:, :-1], idx[:-1, 1:], K_DIAG),  # anti-diagonal
    ]
    a = np.concatenate([p[0].ravel() for p in pairs]).astype(np.int32)
    b = np.concatenate([p[1].ravel() for p in pairs]).astype(np.int32)
    k = np.concatenate([np.full(p[0].size, p[2]) for p in pairs])
    rest = np.linalg.norm(x0[a] - x0[b], axis=1)
    return x0, a, b, k, rest


def free_mask(n=N):
    m = np.ones(n * n, dtype=bool)
    m[[0, (n - 1) * n]] = False
    return m


def initial_state(x0):
    """Perturbed positions (all nodes) and zero velocities."""
    x = x0.copy()
    free = free_mask(int(round(np.sqrt(x0.shape[0]))))
    q = x[free].ravel()
    q += 1e-4 * np.sin(0.7 * np.arange(q.size))
    x[free] = q.reshape(-1, 3)
    return x, np.zeros_like(x)


def per_node_constants():
    """1/m and g per node, zero on the fixed nodes (so they never move)."""
    free = free_mask()
    inv_m = np.where(free, 1.0 / MASS, 0.0)
    g = np.where(free[:, None], GRAVITY[None, :], 0.0)
    return inv_m, g


def reference(d, name):
    path = os.path.join(d, name + ".f64")
    return np.fromfile(path, dtype="<f8") if os.path.exists(path) else None


def check(d, x0, run_steps):
    """Compares with nurbspring's dump (the dump_msm example). run_steps(n) must return the
    (positions, velocities) of all nodes after n steps from initial_state(x0)."""
    free = free_mask()
    ref_x0 = reference(d, "x0")
    if ref_x0 is None:
        print(f"(no nurbspring dump in {d}; run the dump_msm example first)")
        return
    print(f"initial positions vs nurbspring: max |diff| {np.abs(ref_x0 - x0.ravel()).max():.2e}")
    x, _ = initial_state(x0)
    print(f"perturbed free coordinates vs nurbspring: max |diff| "
          f"{np.abs(reference(d, 'q0') - x[free].ravel()).max():.2e}")
    for n in (1, 100):
        x, v = run_steps(n)
        qr, vr = reference(d, f"q{n}"), reference(d, f"v{n}")
        dv = np.abs(vr - v[free].ravel()).max() / np.abs(vr).max()
        dq = np.abs(qr - x[free].ravel()).max()
        print(f"after {n} step(s): velocities max |diff| / max |v| = {dv:.2e} "
              f"(max |v| {np.abs(vr).max():.3e}); positions max |diff| {dq:.2e}")
