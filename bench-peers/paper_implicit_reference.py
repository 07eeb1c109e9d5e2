#!/usr/bin/env python3
"""The SciPy reference of issue 33's implicit paper derivation, of the same size.

nurbspring's job: `derive` with the paper's derivation of a 17 x 17 bicubic control net (two
rings clamped) on a 33 x 33 uniform lattice, `simulation.msm_integrator = "backward-euler"`
(bench-peers/paper_implicit.sh writes the scene and times it). The reference is what a SciPy
user computes for a model of that size: the lattice's 33 x 33 x 3 = 3267 unknowns assembled by
Kronecker products (a bicubic Galerkin mass and a membrane + bending stiffness from 1-D cubic
B-spline matrices, S (x) T (x) I3) and its 8 lowest modes by shift-invert Lanczos
(scipy.sparse.linalg.eigsh, sigma = 0), the outer two rings clamped. It prints one JSON line:
the seconds of the best of REPEAT runs and the versions.

Run: python3 bench-peers/paper_implicit_reference.py [REPEAT]
"""
import json
import sys
import time

import numpy as np
import scipy
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def bspline_1d(n, p=3, gauss=4):
    """Mass, first- and second-derivative Gram matrices of n clamped uniform B-splines of
    degree p on [0, 1] (Gauss-Legendre, `gauss` points a span)."""
    inner = n - p - 1
    knots = np.concatenate([np.zeros(p + 1), np.arange(1, inner + 1) / (inner + 1), np.ones(p + 1)])
    xg, wg = np.polynomial.legendre.leggauss(gauss)
    rows, cols, m, k1, k2 = [], [], [], [], []
    for span in range(p, n):
        a, b = knots[span], knots[span + 1]
        if b <= a:
            continue
        x = 0.5 * (b - a) * xg + 0.5 * (a + b)
        w = 0.5 * (b - a) * wg
        basis = np.array([scipy.interpolate.BSpline(knots, np.eye(n)[i], p)(x, nu=d)
                          for d in range(3) for i in range(span - p, span + 1)])
        basis = basis.reshape(3, p + 1, len(x))
        for d, store in ((0, m), (1, k1), (2, k2)):
            g = (basis[d] * w) @ basis[d].T
            for i in range(p + 1):
                for j in range(p + 1):
                    if d == 0:
                        rows.append(span - p + i)
                        cols.append(span - p + j)
                    store.append(g[i, j])
    shape = (n, n)
    return [sp.csr_matrix((v, (rows, cols)), shape=shape) for v in (m, k1, k2)]


def job(n=33, modes=8):
    m1, d1, d2 = bspline_1d(n)
    i3 = sp.identity(3, format="csr")
    mass = sp.kron(sp.kron(m1, m1), i3, format="csc")
    stiff = (sp.kron(sp.kron(d1, m1), i3) + sp.kron(sp.kron(m1, d1), i3)
             + 0.01 * (sp.kron(sp.kron(d2, m1), i3) + sp.kron(sp.kron(m1, d2), i3))).tocsc()
    free1 = np.zeros(n, dtype=bool)
    free1[2:n - 2] = True
    free = np.repeat(np.outer(free1, free1).ravel(), 3)
    idx = np.flatnonzero(free)
    k, mm = stiff[idx][:, idx], mass[idx][:, idx]
    vals = spla.eigsh(k, k=modes, M=mm, sigma=0.0, which="LM", return_eigenvectors=False)
    return np.sort(np.sqrt(vals))


def main():
    repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        omega = job()
        best = min(best, time.perf_counter() - t0)
    print(json.dumps({"job": "paper-implicit-reference", "unknowns": 33 * 33 * 3,
                      "seconds": best, "omega": omega.tolist(), "numpy": np.__version__,
                      "scipy": scipy.__version__}))


if __name__ == "__main__":
    main()
