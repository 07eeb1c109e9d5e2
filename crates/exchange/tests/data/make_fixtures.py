#!/usr/bin/env python3
"""geomdl fixtures for nurbspring-exchange's geomdl JSON tests.

Needs geomdl (NURBS-Python), tested with geomdl 5.4.0 on Python 3.11:

    python3 -m venv /tmp/venv-geomdl && /tmp/venv-geomdl/bin/pip install geomdl==5.4.0
    /tmp/venv-geomdl/bin/python crates/exchange/tests/data/make_fixtures.py

Part 1 (always) builds shapes with geomdl, writes them with geomdl.exchange.export_json
    geomdl/curves.json      a rational quadratic full circle and a rational cubic with
                            non-uniform knots (3-D points)
    geomdl/curves_2d.json   a rational quarter circle with 2-D points (dimension 2)
    geomdl/surfaces.json    a rational quarter cylinder (degree 2 x 1) and a rational
                            degree 3 x 2 surface with a double interior knot
and records geomdl's own evaluations (evaluate_single) of the shapes it reads back from those
files (exchange.import_json) in geomdl/evaluations.json.

Part 2 (when the files exist) reads the files that nurbspring wrote,
    geomdl/nurbspring_curves.json, geomdl/nurbspring_surfaces.json
(the Rust test `geomdl_fixtures::nurbspring_output_is_blessed` writes them with
NURBSPRING_BLESS=1), with geomdl.exchange.import_json, evaluates them in geomdl and re-exports
them, and records everything it checked in geomdl/geomdl_reads_nurbspring.json. The Rust tests
compare these geomdl evaluations with nurbspring's own (1e-12).

Run part 1, bless the Rust output, run the script again.
"""

import json
import math
import os
import sys

import geomdl
from geomdl import NURBS, exchange, multi

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "geomdl")
S = math.sqrt(0.5)


def curve(degree, ctrlpts, weights, knots):
    c = NURBS.Curve()
    c.degree = degree
    c.ctrlpts = ctrlpts
    c.weights = weights
    c.knotvector = knots
    return c


def surface(du, dv, size_u, size_v, ctrlpts, weights, ku, kv):
    s = NURBS.Surface()
    s.degree_u, s.degree_v = du, dv
    s.ctrlpts_size_u, s.ctrlpts_size_v = size_u, size_v
    s.ctrlpts = ctrlpts  # geomdl order: index = v + size_v * u
    s.weights = weights
    s.knotvector_u, s.knotvector_v = ku, kv
    return s


def circle():
    pts = [[1, 0, 0], [1, 1, 0], [0, 1, 0], [-1, 1, 0], [-1, 0, 0],
           [-1, -1, 0], [0, -1, 0], [1, -1, 0], [1, 0, 0]]
    pts = [[2.0 * x + 0.5, 2.0 * y - 0.25, 1.0] for x, y, _ in pts]
    w = [1, S, 1, S, 1, S, 1, S, 1]
    k = [0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]
    return curve(2, pts, w, k)


def cubic():
    pts = [[0, 0, 0], [1, 2, 0.5], [2.5, 2.2, -0.3], [3.1, 0.4, 1.2],
           [4.0, -1.0, 0.7], [5.2, 0.3, 0.0], [6.0, 1.5, -0.4]]
    w = [1.0, 0.8, 1.7, 0.6, 1.3, 0.9, 1.0]
    k = [0, 0, 0, 0, 0.15, 0.4, 0.4, 1, 1, 1, 1]
    return curve(3, pts, w, k)


def quarter_circle_2d():
    return curve(2, [[3.0, 0.0], [3.0, 3.0], [0.0, 3.0]], [1, S, 1], [0, 0, 0, 1, 1, 1])


def quarter_cylinder():
    r, h = 2.0, 3.0
    arc = [(r, 0.0, 1.0), (r, r, S), (0.0, r, 1.0)]  # along u
    pts, w = [], []
    for x, y, wi in arc:  # u index outer, v index inner (geomdl's order)
        for z in (0.0, h):
            pts.append([x, y, z])
            w.append(wi)
    return surface(2, 1, 3, 2, pts, w, [0, 0, 0, 1, 1, 1], [0, 0, 1, 1])


def wavy():
    nu, nv = 6, 4
    pts, w = [], []
    for i in range(nu):
        for j in range(nv):
            x = i * 0.8
            y = j * 1.1 + 0.2 * math.sin(i)
            z = 0.3 * math.cos(1.3 * i + 0.7 * j) + 0.1 * i * j
            pts.append([x, y, z])
            w.append(0.7 + 0.15 * ((3 * i + 5 * j) % 7))
    ku = [0, 0, 0, 0, 0.3, 0.3, 1, 1, 1, 1]
    kv = [0, 0, 0, 0.45, 1, 1, 1]
    return surface(3, 2, nu, nv, pts, w, ku, kv)


def container(kind, shapes):
    c = multi.CurveContainer() if kind == "curve" else multi.SurfaceContainer()
    for s in shapes:
        c.add(s)
    return c


def linspace(a, b, n):
    return [a + (b - a) * k / (n - 1) for k in range(n)]


def evaluate(shape, n_curve=13, n_u=9, n_v=7):
    """geomdl's evaluation at a grid of its (normalized) parameters."""
    if isinstance(shape, NURBS.Curve):
        return [[t] + list(shape.evaluate_single(t)) for t in linspace(0.0, 1.0, n_curve)]
    out = []
    for u in linspace(0.0, 1.0, n_u):
        for v in linspace(0.0, 1.0, n_v):
            out.append([u, v] + list(shape.evaluate_single((u, v))))
    return out


def describe(shape):
    if isinstance(shape, NURBS.Curve):
        return {"degree": shape.degree, "knotvector": list(shape.knotvector),
                "ctrlpts": shape.ctrlpts, "weights": list(shape.weights),
                "dimension": shape.dimension}
    return {"degree_u": shape.degree_u, "degree_v": shape.degree_v,
            "size_u": shape.ctrlpts_size_u, "size_v": shape.ctrlpts_size_v,
            "knotvector_u": list(shape.knotvector_u), "knotvector_v": list(shape.knotvector_v),
            "ctrlpts": shape.ctrlpts, "weights": list(shape.weights),
            "dimension": shape.dimension}


def dump(name, data):
    with open(os.path.join(OUT, name), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


def part1():
    os.makedirs(OUT, exist_ok=True)
    files = {
        "curves.json": ("curve", [circle(), cubic()]),
        "curves_2d.json": ("curve", [quarter_circle_2d()]),
        "surfaces.json": ("surface", [quarter_cylinder(), wavy()]),
    }
    evaluations = {"geomdl_version": geomdl.__version__, "files": {}}
    for name, (kind, shapes) in files.items():
        path = os.path.join(OUT, name)
        exchange.export_json(container(kind, shapes), path)
        back = exchange.import_json(path)
        assert len(back) == len(shapes)
        evaluations["files"][name] = [
            {"shape": describe(s), "points": evaluate(s)} for s in back
        ]
    evaluations["note"] = (
        "points: [t, x, y, z] (curves) or [u, v, x, y, z] (surfaces) from geomdl's "
        "evaluate_single on the shapes exchange.import_json read from each file; parameters "
        "are geomdl's, in its normalized [0, 1] knot domain (all these files have knots in [0, 1])"
    )
    dump("evaluations.json", evaluations)
    print("part 1: wrote", ", ".join(files), "and evaluations.json")


def part2():
    names = ["nurbspring_curves.json", "nurbspring_surfaces.json"]
    if not all(os.path.exists(os.path.join(OUT, n)) for n in names):
        print("part 2 skipped: bless the Rust output first (NURBSPRING_BLESS=1 cargo test "
              "-p nurbspring-exchange --test geomdl_fixtures)")
        return
    report = {"geomdl_version": geomdl.__version__, "files": {}, "checked": []}
    for name in names:
        path = os.path.join(OUT, name)
        with open(path) as f:
            raw = json.load(f)["shape"]["data"]
        shapes = exchange.import_json(path)
        assert len(shapes) == len(raw), name
        entries = []
        for s, r in zip(shapes, raw):
            d = describe(s)
            # geomdl keeps the weights as written and the points up to (x*w)/w rounding.
            assert d["weights"] == r["control_points"]["weights"], name
            dev = max(abs(a - b) for p, q in zip(d["ctrlpts"], r["control_points"]["points"])
                      for a, b in zip(p, q))
            assert dev <= 1e-15 * max(1.0, max(abs(x) for p in d["ctrlpts"] for x in p)), dev
            if "degree" in r:
                domains = [(r["knotvector"][0], r["knotvector"][-1])]
                assert d["degree"] == r["degree"]
            else:
                domains = [(r["knotvector_u"][0], r["knotvector_u"][-1]),
                           (r["knotvector_v"][0], r["knotvector_v"][-1])]
                assert (d["size_u"], d["size_v"]) == (r["size_u"], r["size_v"])
            entries.append({"shape": d, "file_domains": domains,
                            "max_ctrlpt_deviation": dev, "points": evaluate(s)})
        # geomdl writes them back; the re-export holds the same numbers.
        again = os.path.join(OUT, "_reexport.json")
        exchange.export_json(container("curve" if "curves" in name else "surface", shapes), again)
        shapes2 = exchange.import_json(again)
        os.remove(again)
        for s, s2 in zip(shapes, shapes2):
            assert describe(s)["weights"] == describe(s2)["weights"]
        report["files"][name] = entries
    report["checked"] = [
        "geomdl.exchange.import_json read every shape of nurbspring_curves.json and "
        "nurbspring_surfaces.json (same count, degrees and sizes)",
        "the weights geomdl holds equal the file's exactly",
        "the control points geomdl returns equal the file's up to geomdl's (x*w)/w rounding "
        "(max_ctrlpt_deviation, at most 1e-15 relative)",
        "geomdl normalized the knot vectors to [0, 1] (knotvector* in 'shape'); the file's "
        "domains are in 'file_domains': geomdl's t is nurbspring's a + t (b - a)",
        "geomdl.exchange.export_json wrote the shapes back and import_json read the same weights",
        "points: geomdl's evaluate_single at its parameters t (curves: [t, x, y, z]; surfaces: "
        "[u, v, x, y, z]); the Rust test evaluates nurbspring at a + t (b - a) and compares to 1e-12",
    ]
    dump("geomdl_reads_nurbspring.json", report)
    print("part 2: wrote geomdl_reads_nurbspring.json")


if __name__ == "__main__":
    part1()
    part2()
    sys.exit(0)
