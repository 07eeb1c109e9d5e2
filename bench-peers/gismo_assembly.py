#!/usr/bin/env python3
"""G+Smo (pygismo) and a numpy/scipy Kronecker shortcut on the nurbspring assembly benchmark.

The patch is the one of crates/dnurbs/benches/assembly.rs: bicubic, 128 x 128 uniform
elements (131 x 131 = 17,161 basis functions), 4 x 4 Gauss points per element, mu = 1,
beta11 = beta22 = 1. With uniform weights and parameter-domain integration nurbspring's scalar
matrices do not depend on the control points, so G+Smo gets the identity map of the unit
square (control points at the Greville abscissae) and integrates in the parameter domain too.

What each peer assembles (all single-threaded; this pygismo wheel is built without OpenMP):
- G+Smo mass: gsL2Projection.matrix(basis, geometry, targetDim=1), i.e. the scalar mass matrix
  int N_i N_j |det DG| (G+Smo's expression assembler, quadrature (p+1)^2 = 16 points);
- G+Smo "biharmonic": gsBiharmonicExprAssembler(...).assemble() (no boundary conditions, f = 0)
  then .matrix(): int Lap N_i Lap N_j = int N_i,uu N_j,uu + N_i,vv N_j,vv + N_i,uu N_j,vv +
  N_i,vv N_j,uu. The bindings expose no assembler for nurbspring's K = int N_uu N_uu + N_vv N_vv
  (beta11 = beta22 = 1) alone, so G+Smo's matrix has the two cross terms in addition: the
  same kind of work (second derivatives at every Gauss point), a different bilinear form;
- numpy/scipy Kronecker shortcut: 1D Gram matrices G_d = int N_i^(d) N_j^(d) (and the cross
  matrix int N_i'' N_j for G+Smo's form) by 4-point Gauss quadrature on each span, then
  M = G0 (x) G0 and K = G2 (x) G0 + G0 (x) G2 with scipy.sparse.kron. Valid only for a
  B-spline (uniform weights) on a tensor grid integrated in the parameter domain.

Agreement is checked before timing against the matrices written by
    cargo run --release --manifest-path bench-peers/Cargo.toml --example dump_dnurbs -- DIR
(nurbspring's sum-factorized kernel and its Gauss-point kernel; orderings differ: nurbspring
numbers control point (i, j) as i * n_v + j, G+Smo as i + n_u * j).

Run: /tmp/peers2/bin/python bench-peers/gismo_assembly.py [DIR]   (DIR default /tmp/nurbspring-agree)
"""
import importlib.metadata as md
import os
import statistics
import sys
import time

import numpy as np
import scipy.sparse as sp
from scipy.interpolate import BSpline

import pygismo as gs

from results import record

VERSIONS = {k: md.version(k) for k in ("pygismo", "numpy", "scipy")}

P = 3
NE = 128
N1 = NE + P  # basis functions per direction
KNOTS = [0.0] * (P + 1) + [i / NE for i in range(1, NE)] + [1.0] * (P + 1)
GAUSS = 4


def gismo_setup():
    kv = gs.nurbs.gsKnotVector(KNOTS, P)
    basis = gs.nurbs.gsTensorBSplineBasis2(kv, kv)
    g = np.array([sum(KNOTS[i + 1:i + P + 1]) / P for i in range(N1)])
    u, v = np.meshgrid(g, g, indexing="xy")  # u fastest, as G+Smo numbers its coefficients
    geo = gs.nurbs.gsTensorBSpline2(basis, np.column_stack([u.ravel(), v.ravel()]))
    mp = gs.core.gsMultiPatch()
    mp.addPatch(geo)
    mb = gs.core.gsMultiBasis(mp)
    return mp, mb


def gismo_mass(mp, mb):
    return gs.utils.gsL2Projection.matrix(mb, mp, 1)


def gismo_biharmonic(mp, mb):
    bc = gs.pde.gsBoundaryConditions()
    f = gs.core.gsFunctionExpr("0", 2)
    a = gs.assembler.gsBiharmonicExprAssembler(mp, mb, f, bc)
    a.assemble()
    return a.matrix()


def gram_1d():
    """1D span integrals by the 4-point Gauss rule: values, first and second derivatives at
    all Gauss points (dense (4 NE) x N1 collocation matrices, tiny), then B_d^T W B_e."""
    xg, wg = np.polynomial.legendre.leggauss(GAUSS)
    a = np.arange(NE) / NE
    h = 1.0 / NE
    x = (a[:, None] + 0.5 * h * (xg[None, :] + 1.0)).ravel()
    w = np.tile(0.5 * h * wg, NE)
    spl = BSpline(np.array(KNOTS), np.eye(N1), P)
    b0 = spl(x)
    b2 = spl.derivative(2)(x)
    g0 = (b0 * w[:, None]).T @ b0
    g2 = (b2 * w[:, None]).T @ b2
    a20 = (b2 * w[:, None]).T @ b0
    # Drop the structural zeros (|i - j| > P) so that the 2D matrices have the B-spline pattern.
    band = np.abs(np.subtract.outer(np.arange(N1), np.arange(N1))) <= P
    return [sp.csr_matrix(np.where(band, m, 0.0)) for m in (g0, g2, a20)]


def kron_mass_stiffness():
    g0, g2, _ = gram_1d()
    m = sp.kron(g0, g0, format="csr")
    k = (sp.kron(g2, g0, format="csr") + sp.kron(g0, g2, format="csr")).tocsr()
    return m, k


def kron_biharmonic_cross():
    g0, _, a20 = gram_1d()
    return (sp.kron(a20, a20.T, format="csr") + sp.kron(a20.T, a20, format="csr")).tocsr()


def load_ours(d, name):
    colptr = np.fromfile(os.path.join(d, name + ".colptr.u64"), dtype="<u8").astype(np.int64)
    rowidx = np.fromfile(os.path.join(d, name + ".rowidx.u64"), dtype="<u8").astype(np.int64)
    vals = np.fromfile(os.path.join(d, name + ".values.f64"), dtype="<f8")
    n = len(colptr) - 1
    return sp.csc_matrix((vals, rowidx, colptr), shape=(n, n))


def to_gismo_order(a):
    """nurbspring index i * N1 + j  ->  G+Smo index i + N1 * j."""
    perm = np.arange(N1 * N1).reshape(N1, N1).T.ravel()  # perm[g] = nurbspring index of g
    return a.tocsr()[perm][:, perm]


def maxdiff(a, b):
    d = (a - b).tocoo()
    return float(np.abs(d.data).max()) if d.nnz else 0.0


def timed(f, reps):
    ts = []
    out = None
    for _ in range(reps):
        t0 = time.perf_counter()
        out = f()
        ts.append(time.perf_counter() - t0)
    return out, ts


def show(name, ts, key=None):
    if key:
        record(key[0], key[1], ts, versions=VERSIONS)
    print(f"{name}: min {min(ts) * 1e3:.1f} ms, median {statistics.median(ts) * 1e3:.1f} ms "
          f"({len(ts)} runs)")


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else "/tmp/nurbspring-agree"
    print("pygismo", md.version("pygismo"), "numpy", np.__version__, "scipy",
          md.version("scipy"), "python", sys.version.split()[0])
    mp, mb = gismo_setup()

    # ---- agreement (not timed)
    gm = gismo_mass(mp, mb)
    gb = gismo_biharmonic(mp, mb)
    km, kk = kron_mass_stiffness()
    kc = kron_biharmonic_cross()
    print(f"sizes: G+Smo mass {gm.shape} nnz {gm.nnz}, biharmonic nnz {gb.nnz}; "
          f"Kronecker mass nnz {km.nnz}")
    print(f"sum of mass entries (= area 1): G+Smo {gm.sum():.16f}, Kronecker {km.sum():.16f}")
    scale_m, scale_k = abs(km).max(), abs(kk).max()
    print(f"G+Smo mass vs Kronecker: max |diff| {maxdiff(gm, km):.2e} (max entry {scale_m:.3e})")
    print(f"G+Smo biharmonic vs Kronecker (K + cross terms): max |diff| "
          f"{maxdiff(gb, kk + kc):.2e} (max entry {abs(gb).max():.3e})")
    print(f"G+Smo biharmonic - Kronecker cross terms vs nurbspring's K form: max |diff| "
          f"{maxdiff(gb - kc, kk):.2e}")
    for kernel in ("tensor", "gauss"):
        try:
            om = to_gismo_order(load_ours(d, kernel + "_mass"))
            ok = to_gismo_order(load_ours(d, kernel + "_stiffness"))
        except FileNotFoundError:
            print(f"(no nurbspring dump in {d}; run the dump_dnurbs example first)")
            break
        print(f"nurbspring {kernel} kernel: mass sum {om.sum():.16f}, "
              f"mass vs G+Smo {maxdiff(om, gm):.2e}, vs Kronecker {maxdiff(om, km):.2e}; "
              f"K vs Kronecker {maxdiff(ok, kk):.2e} (max entry {scale_k:.3e}), "
              f"K vs G+Smo biharmonic - cross terms {maxdiff(ok, gb - kc):.2e}")
        # A few entries, in G+Smo numbering: (i + 131 j, ...).
        for r, c in [(0, 0), (1, 0), (131 * 65 + 65, 131 * 65 + 65), (131 * 65 + 65, 131 * 66 + 68)]:
            print(f"   K[{r},{c}]: nurbspring {ok[r, c]:.12e}  Kronecker {kk[r, c]:.12e}  "
                  f"G+Smo-cross {(gb - kc)[r, c]:.12e}")

    # ---- timing
    if os.environ.get("CHECK_ONLY"):
        return
    print(f"== timing, load average {os.getloadavg()}")
    _, ts = timed(lambda: gismo_mass(mp, mb), 7)
    show("G+Smo mass (gsL2Projection.matrix, scalar)", ts, ("gismo", "mass"))
    _, ts = timed(lambda: gismo_biharmonic(mp, mb), 5)
    show("G+Smo biharmonic (gsBiharmonicExprAssembler: construct + assemble + matrix)", ts, ("gismo", "biharmonic"))
    bc = gs.pde.gsBoundaryConditions()
    f = gs.core.gsFunctionExpr("0", 2)
    a = gs.assembler.gsBiharmonicExprAssembler(mp, mb, f, bc)
    _, ts = timed(a.assemble, 5)
    show("G+Smo biharmonic, assemble() only", ts)
    _, ts = timed(a.matrix, 5)
    show("G+Smo biharmonic, matrix() only (copy to scipy)", ts)
    _, ts = timed(gram_1d, 21)
    show("Kronecker: 1D Gram matrices only", ts)
    _, ts = timed(lambda: (lambda g: sp.kron(g[0], g[0], format="csr"))(gram_1d()), 11)
    show("Kronecker: mass only", ts)
    _, ts = timed(kron_mass_stiffness, 11)
    show("Kronecker: mass and stiffness (K = G2 x G0 + G0 x G2)", ts, ("numpy-kronecker", "mass_stiffness"))
    print(f"== load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
