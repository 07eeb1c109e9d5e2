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

KNOTS = [0.0, 0.0, 0.0, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.0, 1.0, 1.0]



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
    print(f"checksum sum(x + y + z) = {grid.sum():.15e}")
    for (i, j) in [(0, 0), (123, 456), (500, 500), (999, 1), (999, 999)]:
        print(f"  point[{i}][{j}] = {grid[i, j].tolist()}")
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
    print(f"  first scattered point ({us[0]!r}, {vs[0]!r}) = {pts[0].tolist()}")


if __name__ == "__main__":
    main()
