#!/usr/bin/env python3
"""A scene for timing the paper's derivation on refined nets (docs/benchmarks.md).

    paper_sheet.py N NODES OUT.toml [MAX_CANDIDATES]

The paper's material (mu = 25, beta11 = beta22 = 0.01), integrators, time step and load (the two
outer rings fixed, velocity (0, 0, -0.2)) on a flat 3 x 5 bicubic sheet at z = 2 with N x N
control points at the Greville abscissae of uniform clamped knots, and a uniform NODES x NODES
lattice. MAX_CANDIDATES (default 0: every distinct eigenvalue of M) bounds the mass scan.
"""
import sys

n, nodes, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
max_candidates = int(sys.argv[4]) if len(sys.argv) > 4 else 0
p = 3
inner = n - p - 1
knots = [0.0] * (p + 1) + [i / (inner + 1) for i in range(1, inner + 1)] + [1.0] * (p + 1)
greville = [sum(knots[i + 1:i + p + 1]) / p for i in range(n)]
rows = "\n".join(
    "  [" + ", ".join(f"[{3 * x!r}, {5 * y!r}, 2.0]" for y in greville) + "],"
    for x in greville
)
text = f"""[surface]
degree_u = 3
degree_v = 3
knots_u = {knots}
knots_v = {knots}
control_points = [
{rows}
]
[material]
mu = 25.0
beta11 = 0.01
beta22 = 0.01
[constraints]
fixed_rings = 2
[initial]
velocity = [0.0, 0.0, -0.2]
[simulation]
dt = 0.08
t_end = 4.0
dnurbs_integrator = "terzopoulos-qin"
msm_integrator = "symplectic-euler"
[fit]
max_candidates = {max_candidates}
[msm]
grid = "uniform"
nodes_u = {nodes}
nodes_v = {nodes}
"""
with open(out, "w") as f:
    f.write(text)
