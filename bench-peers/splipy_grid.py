#!/usr/bin/env python3
"""splipy (numpy) on the nurbspring benchmark patch: a 1000 x 1000 tensor grid.

The patch is the one of crates/geom/benches/evaluate.rs and bench-peers/benches/peers.rs:
rational bicubic, 8 x 8 control points, knots {0,0,0,0, 0.2, 0.4, 0.6, 0.8, 1,1,1,1} in both
directions, P_ij = (i/7, j/7, ((3i + 5j) mod 7) / 14), w_ij = 1 + ((i + 2j) mod 3) / 4.

Run (same session as the Rust benchmarks, see docs/benchmarks.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install splipy numpy
    /tmp/peers/bin/python bench-peers/splipy_grid.py
"""
import importlib.metadata as md
import statistics
import time

import numpy as np
import splipy

from results import record

KNOTS = [0.0, 0.0, 0.0, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.0, 1.0, 1.0]

# nurbspring-geom's NurbsSurface::grid on linspace(0, 1, 1000)² at a few grid points, as printed
# by bench-peers/benches/peers.rs; splipy must agree (same surface, same parameters).
NURBSPRING = {
    (0, 0): [0.0, 0.0, 0.0],
    (123, 456): [0.2015787800928498, 0.4641257537270454, 0.19586289074975227],
    (500, 500): [0.49722640132080165, 0.5034543317447567, 0.23502372128753593],
    (999, 1): [1.0, 0.0017211132292181007, 0.004280218982899106],
    (999, 999): [1.0, 1.0, 0.0],
}
NURBSPRING_CHECKSUM = 1.208028652310036e6



def patch():
    basis = splipy.BSplineBasis(4, KNOTS)
    cps = []
    for j in range(8):  # splipy: u fastest
        for i in range(8):
            w = 1.0 + ((i + 2 * j) % 3) / 4.0
            p = [i / 7.0, j / 7.0, ((3 * i + 5 * j) % 7) / 14.0]
            cps.append([w * p[0], w * p[1], w * p[2], w])
    return splipy.Surface(basis, basis, cps, rational=True)


def main():
    s = patch()
    t = np.linspace(0.0, 1.0, 1000)
    times = []
    for _ in range(7):
        start = time.perf_counter()
        grid = s(t, t)  # tensor evaluation, shape (1000, 1000, 3)
        times.append(time.perf_counter() - start)
    assert grid.shape == (1000, 1000, 3)
    print(f"splipy {md.version('splipy')}, numpy {md.version('numpy')}")
    print(f"grid 1000x1000: min {min(times) * 1e3:.1f} ms, median {statistics.median(times) * 1e3:.1f} ms "
          f"over {len(times)} runs")
    print(f"checksum sum(x + y + z) = {grid.sum():.15e} (nurbspring {NURBSPRING_CHECKSUM:.15e})")
    worst = max(abs(a - b) for (i, j), p in NURBSPRING.items() for a, b in zip(grid[i, j], p))
    assert worst < 1e-14, worst
    assert abs(grid.sum() - NURBSPRING_CHECKSUM) < 1e-12 * NURBSPRING_CHECKSUM
    print(f"agrees with nurbspring at {len(NURBSPRING)} grid points to {worst:.1e}")
    record("splipy", "grid_1000x1000", times, version=md.version("splipy"), agree=worst)
    # Per-point (scattered) evaluation, for reference: the same 4096 LCG parameters.
    state = 0x2545F4914F6CDD1D
    ps = []
    for _ in range(4096):
        state = (state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        u = (state >> 11) / float(1 << 53)
        state = (state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        v = (state >> 11) / float(1 << 53)
        ps.append((u, v))
    us = np.array([p[0] for p in ps])
    vs = np.array([p[1] for p in ps])
    times = []
    for _ in range(7):
        start = time.perf_counter()
        pts = s(us, vs, tensor=False)
        times.append(time.perf_counter() - start)
    print(f"scattered 4096 points (vectorised, tensor=False): min {min(times) * 1e9 / 4096:.0f} ns/point")
    record("splipy", "point_scattered", [t / 4096 for t in times], version=md.version("splipy"))
    print(f"  first scattered point ({us[0]!r}, {vs[0]!r}) = {pts[0].tolist()}")


if __name__ == "__main__":
    main()
