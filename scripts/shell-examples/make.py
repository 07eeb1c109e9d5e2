#!/usr/bin/env python3
"""Writes the Kirchhoff–Love shell examples (examples/scordelis_lo.toml,
examples/cantilever_strip.toml, examples/cloth_corners.toml): a coarse exact patch per example
(one rational Bézier patch), refined by `nurbspring refine` (exact degree elevation and knot
insertion), then the constraints, loads and probes appended.

Run from the repository root: `python3 scripts/shell-examples/make.py [path/to/nurbspring]`.
"""
import math
import os
import subprocess
import sys
import tempfile

CLI = sys.argv[1] if len(sys.argv) > 1 else "target/debug/nurbspring"


def patch(points, weights, degree_u, degree_v):
    """A one-span patch: rows along u of points [x, y, z], Bézier knots."""
    ku = [0] * (degree_u + 1) + [1] * (degree_u + 1)
    kv = [0] * (degree_v + 1) + [1] * (degree_v + 1)
    rows = "\n".join("  [" + ", ".join(f"[{p[0]!r}, {p[1]!r}, {p[2]!r}]" for p in r) + "]," for r in points)
    wrows = "\n".join("  [" + ", ".join(repr(w) for w in r) + "]," for r in weights)
    return f"""[surface]
degree_u = {degree_u}
degree_v = {degree_v}
knots_u = {ku}
knots_v = {kv}
control_points = [
{rows}
]
weights = [
{wrows}
]
"""


def refine(coarse_text, header, degree, spans_u, spans_v, rest, out):
    """Refines the coarse scene to `degree` with `spans` equal spans and writes `header`, the
    refined scene and `rest` to `out`."""
    inner = lambda n: ",".join(repr(k / n) for k in range(1, n))
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "coarse.toml")
        dst = os.path.join(d, "fine.toml")
        open(src, "w").write(coarse_text)
        args = [CLI, "--quiet", "refine", src, "--elevate", f"{degree},{degree}", "--out", dst]
        if spans_u > 1:
            args += ["--insert-u", inner(spans_u)]
        if spans_v > 1:
            args += ["--insert-v", inner(spans_v)]
        subprocess.run(args, check=True)
        fine = open(dst).read()
    # `refine` writes the whole scene; keep its [surface] and replace the rest.
    surface = fine[fine.index("[surface]"):]
    end = surface.index("\n[", 1)
    open(out, "w").write(header + "\n" + surface[:end].rstrip() + "\n\n" + rest.strip() + "\n")


def scordelis_lo():
    r, length = 25.0, 25.0
    a0, a1 = math.radians(50), math.radians(90)
    h = 0.5 * (a1 - a0)
    mid = 0.5 * (a0 + a1)
    arc = [(r * math.cos(a0), r * math.sin(a0)), (r / math.cos(h) * math.cos(mid), r / math.cos(h) * math.sin(mid)),
           (r * math.cos(a1), r * math.sin(a1))]
    points = [[[x, c[0], c[1]] for c in arc] for x in (0.0, length)]
    weights = [[1.0, math.cos(h), 1.0]] * 2
    coarse = patch(points, weights, 1, 2) + """
[material]
model = "kirchhoff-love"
young = 4.32e8
poisson = 0.0
thickness = 0.25
density = 1.0
"""
    header = """# The Scordelis–Lo roof (Belytschko et al. 1985), a quarter by symmetry: a cylindrical
# roof, radius 25, length 50, 80° of arc, thickness 0.25, E = 4.32e8, ν = 0, under its
# self-weight of 90 per unit area, on rigid diaphragms at its curved ends, straight edges
# free. This quarter: x from the diaphragm (x = 0) to midspan (x = 25), the arc from the free
# edge (50°, v = 0) to the crown (90°, v = 1). Degree 4, 16 × 16 spans (written by
# scripts/shell-examples/make.py). The free edge's midpoint, probe (1, 0), sinks by 0.3006
# (Kirchhoff–Love; 0.3024 in the older tables with shear deformation):
#   nurbspring steady examples/scordelis_lo.toml --linear
"""
    rest = """
[material]
model = "kirchhoff-love"
young = 4.32e8
poisson = 0.0
thickness = 0.25
density = 1.0

[loads]
distributed = [0.0, 0.0, -90.0]

# The rigid diaphragm at x = 0: no displacement in its plane.
[[constraints.edge]]
edge = "u0"
hold = ["y", "z"]

# Midspan x = 25 and the crown are planes of symmetry.
[[constraints.edge]]
edge = "u1"
condition = "symmetry"

[[constraints.edge]]
edge = "v1"
condition = "symmetry"

[simulation]
dt = 0.002
t_end = 0.1
probes = [[1.0, 0.0]]
"""
    refine(coarse, header, 4, 16, 16, rest, "examples/scordelis_lo.toml")


def cantilever_strip():
    points = [[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[10.0, 0.0, 0.0], [10.0, 1.0, 0.0]]]
    weights = [[1.0, 1.0], [1.0, 1.0]]
    coarse = patch(points, weights, 1, 1)
    header = """# The cantilever under end shear of Sze, Liu and Lo (2004, §3.1): a strip 10 × 1, thickness
# 0.1, E = 1.2e6, ν = 0, clamped at x = 0, a shear force of 4 spread over its tip edge.
# Degree 3, 16 × 1 spans (written by scripts/shell-examples/make.py). Its tip (probe (1, 0.5))
# follows the elastica to −u = 3.2894, w = 6.6996 at the full load (Sze's table: 3.286,
# 6.698):
#   nurbspring steady examples/cantilever_strip.toml --load-steps 20 --out strip
"""
    rest = """
[material]
model = "kirchhoff-love"
young = 1.2e6
poisson = 0.0
thickness = 0.1
density = 500.0

[[loads.edge]]
edge = "u1"
force = [0.0, 0.0, 4.0]

[[constraints.edge]]
edge = "u0"
condition = "clamped"

[simulation]
dt = 0.01
t_end = 0.5
probes = [[1.0, 0.5]]
"""
    refine(coarse, header, 3, 16, 1, rest, "examples/cantilever_strip.toml")


def cloth_corners():
    size = 0.5
    points = [[[0.0, 0.0, 0.0], [0.0, size, 0.0]], [[size, 0.0, 0.0], [size, size, 0.0]]]
    weights = [[1.0, 1.0], [1.0, 1.0]]
    coarse = patch(points, weights, 1, 1)
    spans, degree = 12, 2
    n = spans + degree
    header = f"""# A square cloth, 0.5 m × 0.5 m, 0.3 mm thick, cotton-like (E = 5 MPa, ν = 0.3,
# ρ = 500 kg/m³: 0.15 kg/m²), held at two corners of one edge and falling under gravity from
# flat: a large-rotation dynamic run of the Kirchhoff–Love shell (implicit generalized-α with
# Newton on the consistent tangent; ρ∞ = 0.8 damps the stiff membrane modes that make Newmark's
# average acceleration gain energy at this Δt). Degree {degree}, {spans} × {spans} spans (written by
# scripts/shell-examples/make.py):
#   nurbspring simulate examples/cloth_corners.toml --model dnurbs --out cloth
"""
    rest = f"""
[material]
model = "kirchhoff-love"
young = 5.0e6
poisson = 0.3
thickness = 0.0003
density = 500.0
gamma = 0.02

[loads]
gravity = [0.0, 0.0, -9.81]

# The two corners of the edge v = 0: the corner control points are the surface's corners.
[constraints]
fixed = [[0, 0], [{n - 1}, 0]]

[simulation]
dnurbs_integrator = "generalized-alpha"
rho_infinity = 0.8
dt = 0.005
t_end = 0.5
probes = [[0.5, 1.0], [1.0, 1.0]]
"""
    refine(coarse, header, degree, spans, spans, rest, "examples/cloth_corners.toml")


if __name__ == "__main__":
    scordelis_lo()
    cantilever_strip()
    cloth_corners()
