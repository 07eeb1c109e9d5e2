#!/usr/bin/env python3
"""Open CASCADE fixtures for nurbspring-exchange's IGES tests.

Needs OCP (Open CASCADE 8.0 for Python), tested with cadquery-ocp-novtk 8.0.1.1.0 on Python 3.11:

    python3 -m venv /tmp/venv-ocp && /tmp/venv-ocp/bin/pip install cadquery-ocp-novtk==8.0.1.1.0
    /tmp/venv-ocp/bin/python crates/exchange/tests/data/make_iges_fixtures.py

Part 1 (always) builds with OCP
  - a rational B-spline surface (Geom_BSplineSurface): a surface of revolution of a rational
    cubic profile over a 180-degree rational quadratic arc, u knots (0, 0.7, 2) with
    multiplicities (3, 2, 3), v knots (-1, 0, 1.5, 3) with multiplicities (4, 2, 1, 4), weights
    = arc weight x profile weight (5 x 7 poles);
  - a rational curve: a 270-degree circular arc (quadratic, knots 0..3, double interior knots)
    in a tilted plane;
  - a rational cubic curve with non-uniform knots and a double knot,
puts them in one compound (a face on [0.1, 1.9] x [-0.5, 2.5] of the surface and two edges) and writes it with
IGESControl_Writer in BRep mode (entities 186/514/510/508/504/502 around the 128 and 126s) and
in Faces mode (144 trimmed surfaces with 142 curves on surface). The model IGESControl_Writer
computed is printed with IGESData_IGESWriter with reals as %.16E (17 significant digits), so
the files hold the geometry exactly:
    iges/ocp_brep.igs, iges/ocp_faces.igs
and once more with IGESControl_Writer.Write's own default number format (about 9 digits):
    iges/ocp_faces_default.igs
For every file, OCP reads it back (IGESControl_Reader), converts every 126 and 128 entity with
IGESToBRep_BasicCurve / IGESToBRep_BasicSurface (continuity kept as is) and evaluates it on a
grid of its own parameters; that and OCP's evaluation of the original geometry go to
    iges/ocp_points.json

Part 2 (when it exists) reads iges/nurbspring_written.igs (written by the Rust test
`iges_fixtures::nurbspring_iges_is_blessed` with NURBSPRING_BLESS=1), checks that
IGESControl_Reader loads it without fails and transfers its roots to faces and edges, records the
knots, weights and poles OCP parsed (IGESGeom entity accessors) and OCP's evaluation of each
entity, in iges/ocp_reads_nurbspring.json.
"""

import io
import json
import math
import os

from OCP.OCP.BRep import BRep_Builder
from OCP.OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace
from OCP.OCP.collections import Array1_double, Array1_gp_Pnt, Array1_int, Array2_double, Array2_gp_Pnt
from OCP.OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface
from OCP.OCP.gp import gp_Pnt
from OCP.OCP.IFSelect import IFSelect_RetDone
from OCP.OCP.IGESControl import IGESControl_Reader, IGESControl_Writer
from OCP.OCP.IGESData import IGESData_IGESWriter
from OCP.OCP.IGESSelect import IGESSelect_WorkLibrary
from OCP.OCP.IGESToBRep import IGESToBRep_BasicCurve, IGESToBRep_BasicSurface
from OCP.OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.OCP.TopExp import TopExp_Explorer
from OCP.OCP.TopoDS import TopoDS_Compound

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "iges")
S = math.sqrt(0.5)


def arr1(values, cls=Array1_double):
    a = cls(1, len(values))
    for i, v in enumerate(values):
        a.SetValue(i + 1, v)
    return a


def surface():
    arc = [(1, 0, 1.0), (1, 1, S), (0, 1, 1.0), (-1, 1, S), (-1, 0, 1.0)]  # 180 degrees
    profile = [(3.0, -1.0, 1.0), (3.6, -0.6, 0.8), (4.1, 0.2, 1.25), (3.8, 0.9, 0.9),
               (3.2, 1.4, 1.1), (2.7, 1.0, 1.0), (2.5, 0.3, 1.0)]  # (radius, z, weight)
    nu, nv = len(arc), len(profile)
    poles, weights = Array2_gp_Pnt(1, nu, 1, nv), Array2_double(1, nu, 1, nv)
    for i, (ax, ay, aw) in enumerate(arc):
        for j, (r, z, pw) in enumerate(profile):
            poles.SetValue(i + 1, j + 1, gp_Pnt(r * ax, r * ay, z))
            weights.SetValue(i + 1, j + 1, aw * pw)
    return Geom_BSplineSurface(
        poles, weights,
        arr1([0.0, 0.7, 2.0]), arr1([-1.0, 0.0, 1.5, 3.0]),
        arr1([3, 2, 3], Array1_int), arr1([4, 2, 1, 4], Array1_int), 2, 3)


def arc270():
    square = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1)]
    w = [1, S, 1, S, 1, S, 1]
    pts = []
    for x, y in square:
        x, y = 1.5 * x + 0.25, 1.5 * y - 0.5
        pts.append(gp_Pnt(x, y, 1.0 + 0.5 * x))
    return Geom_BSplineCurve(arr1(pts, Array1_gp_Pnt), arr1(w), arr1([0.0, 1.0, 2.0, 3.0]),
                             arr1([3, 2, 2, 3], Array1_int), 2)


def cubic():
    pts = [(0, 0, 0), (1, 2, 0.5), (2.5, 2.2, -0.3), (3.1, 0.4, 1.2), (4.0, -1.0, 0.7),
           (5.2, 0.3, 0.0), (6.0, 1.5, -0.4)]
    w = [1.0, 0.8, 1.7, 0.6, 1.3, 0.9, 1.0]
    return Geom_BSplineCurve(arr1([gp_Pnt(*p) for p in pts], Array1_gp_Pnt), arr1(w),
                             arr1([-1.0, -0.25, 0.5, 2.0]), arr1([4, 1, 2, 4], Array1_int), 3)


def linspace(a, b, n):
    return [a + (b - a) * k / (n - 1) for k in range(n)]


def eval_curve(c, n=17):
    a, b = c.FirstParameter(), c.LastParameter()
    out = []
    for t in linspace(a, b, n):
        p = c.Value(t)
        out.append([t, p.X(), p.Y(), p.Z()])
    return {"domain": [a, b], "points": out}


def eval_surface(s, nu=9, nv=11):
    u0, u1, v0, v1 = s.Bounds()
    out = []
    for u in linspace(u0, u1, nu):
        for v in linspace(v0, v1, nv):
            p = s.Value(u, v)
            out.append([u, v, p.X(), p.Y(), p.Z()])
    return {"domain": [[u0, u1], [v0, v1]], "points": out}


def compound(shapes):
    b, comp = BRep_Builder(), TopoDS_Compound()
    b.MakeCompound(comp)
    for s in shapes:
        b.Add(comp, s)
    return comp


def write_exact(writer, path):
    """Print the model that IGESControl_Writer computed, reals with 17 significant digits."""
    iw = IGESData_IGESWriter(writer.Model())
    fw = iw.FloatWriter()
    fw.SetFormat("%.16E")
    fw.SetFormatForRange("%.16E", 0.1, 1000.0)
    fw.SetZeroSuppress(False)
    iw.SendModel(IGESSelect_WorkLibrary.DefineProtocol_s())
    buf = io.BytesIO()
    assert iw.Print(buf)
    with open(path, "wb") as f:
        f.write(buf.getvalue())


def read_back(path):
    """OCP reads the file, converts each 126/128 on its own and evaluates it."""
    r = IGESControl_Reader()
    assert r.ReadFile(path) == IFSelect_RetDone, path
    model = r.IGESModel()
    conv_s, conv_c = IGESToBRep_BasicSurface(), IGESToBRep_BasicCurve()
    for conv in (conv_s, conv_c):
        conv.SetModel(model)
        conv.SetContinuity(0)
    entities, types = [], {}
    for i in range(1, model.NbEntities() + 1):
        ent = model.Entity(i)
        t = ent.TypeNumber()
        types[str(t)] = types.get(str(t), 0) + 1
        de = 2 * i - 1
        if t == 128:
            g = conv_s.TransferBSplineSurface(ent)  # OCP hands out the IGESGeom_BSplineSurface
            entities.append(dict(de=de, type=128, unit_factor=conv_s.GetUnitFactor(), **eval_surface(g)))
        elif t == 126:
            g = conv_c.TransferBSplineCurve(ent)
            entities.append(dict(de=de, type=126, unit_factor=conv_c.GetUnitFactor(), **eval_curve(g)))
    n = r.TransferRoots()
    shape = r.OneShape()
    faces = edges = 0
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        faces += 1
        ex.Next()
    ex = TopExp_Explorer(shape, TopAbs_EDGE)
    while ex.More():
        edges += 1
        ex.Next()
    return {"entity_types": types, "entities": entities,
            "transfer_roots": {"roots_transferred": n, "faces": faces, "edges": edges}}


def parsed_entity(ent):
    """The numbers OCP parsed from a 126 or 128 entity."""
    t = ent.TypeNumber()
    if t == 126:
        e = ent  # IGESGeom_BSplineCurve
        k, m = e.UpperIndex(), e.Degree()
        return {"K": k, "M": m,
                "knots": [e.Knot(i) for i in range(-m, k + 2)],
                "weights": [e.Weight(i) for i in range(k + 1)],
                "poles": [list(e.Pole(i).Coord()) for i in range(k + 1)],
                "range": [e.UMin(), e.UMax()]}
    e = ent
    k1, k2, m1, m2 = e.UpperIndexU(), e.UpperIndexV(), e.DegreeU(), e.DegreeV()
    return {"K1": k1, "K2": k2, "M1": m1, "M2": m2,
            "knots_u": [e.KnotU(i) for i in range(-m1, k1 + 2)],
            "knots_v": [e.KnotV(i) for i in range(-m2, k2 + 2)],
            # (i, j), i along u; listed here with j inner: nurbspring's order i * n_v + j.
            "weights": [e.Weight(i, j) for i in range(k1 + 1) for j in range(k2 + 1)],
            "poles": [list(e.Pole(i, j).Coord()) for i in range(k1 + 1) for j in range(k2 + 1)],
            "range": [e.UMin(), e.UMax(), e.VMin(), e.VMax()]}


def part1():
    os.makedirs(OUT, exist_ok=True)
    s, c1, c2 = surface(), arc270(), cubic()
    # A face on part of the surface's domain, so that its boundary is a real trim.
    face = BRepBuilderAPI_MakeFace(s, 0.1, 1.9, -0.5, 2.5, 1e-7).Face()
    e1, e2 = BRepBuilderAPI_MakeEdge(c1).Edge(), BRepBuilderAPI_MakeEdge(c2).Edge()
    comp = compound([face, e1, e2])
    files = {}
    for name, mode, exact in [("ocp_brep.igs", 1, True), ("ocp_faces.igs", 0, True),
                              ("ocp_faces_default.igs", 0, False)]:
        w = IGESControl_Writer("MM", mode)
        assert w.AddShape(comp)
        w.ComputeModel()
        path = os.path.join(OUT, name)
        if exact:
            write_exact(w, path)
        else:
            assert w.Write(path)
        files[name] = dict(mode="BRep" if mode == 1 else "Faces",
                           reals="%.16E" if exact else "IGESControl_Writer.Write default",
                           **read_back(path))
    data = {
        "ocp": "cadquery-ocp-novtk 8.0.1.1.0 (Open CASCADE 8.0)",
        "original": {"surface": eval_surface(s), "curves": [eval_curve(c1), eval_curve(c2)]},
        "files": files,
        "note": "points: [t, x, y, z] or [u, v, x, y, z] at OCP's own parameters; 'de' is the "
                "entity's Directory Entry pointer (2 i - 1 for model entity i); 'original' is "
                "OCP's evaluation of the geometry it wrote; the files' entities are what "
                "IGESControl_Reader read back from each file, converted by "
                "IGESToBRep_BasicSurface/BasicCurve with SetContinuity(0) (no knot removal)",
    }
    with open(os.path.join(OUT, "ocp_points.json"), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    print("part 1: wrote", ", ".join(files), "and ocp_points.json")


def part2():
    path = os.path.join(OUT, "nurbspring_written.igs")
    if not os.path.exists(path):
        print("part 2 skipped: bless the Rust output first (NURBSPRING_BLESS=1 cargo test "
              "-p nurbspring-exchange --test iges_fixtures)")
        return
    back = read_back(path)
    r = IGESControl_Reader()
    assert r.ReadFile(path) == IFSelect_RetDone
    model = r.IGESModel()
    parsed = []
    for i in range(1, model.NbEntities() + 1):
        ent = model.Entity(i)
        if ent.TypeNumber() in (126, 128):
            parsed.append(dict(de=2 * i - 1, type=ent.TypeNumber(), **parsed_entity(ent)))
    checks = r.WS().ModelCheckList()  # the load checks of every entity and the model
    n_fail = model.GlobalCheck().NbFails()
    g = model.GlobalSection()
    data = {
        "ocp": "cadquery-ocp-novtk 8.0.1.1.0 (Open CASCADE 8.0)",
        "global": {"units_flag": g.UnitFlag(), "units_name": g.UnitName().ToCString(),
                   "scale": g.Scale(), "version": g.IGESVersion(),
                   "unit_factor": model.GlobalSection().UnitValue()},
        "global_check_fails": n_fail,
        "model_check_status": str(checks.Status()).split(".")[-1],
        "model_check_fails_empty": checks.IsEmpty(True),
        "parsed": parsed,
        **back,
        "checked": [
            "IGESControl_Reader.ReadFile returned IFSelect_RetDone",
            "the model's global check has no fails (global_check_fails) and the load check list "
            "of all entities has no fails (model_check_status, model_check_fails_empty)",
            "TransferRoots made faces and edges of it (transfer_roots)",
            "parsed: K, M, knots, weights, poles, parameter range of every 126/128 as OCP's "
            "IGESGeom entities hold them; the Rust test compares them bit for bit with the shapes "
            "nurbspring wrote",
            "entities: OCP's evaluation (IGESToBRep conversion, continuity kept) at its "
            "parameters; the Rust test compares nurbspring's evaluation to 1e-12",
        ],
    }
    with open(os.path.join(OUT, "ocp_reads_nurbspring.json"), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    print("part 2: wrote ocp_reads_nurbspring.json", data["transfer_roots"])


if __name__ == "__main__":
    part1()
    part2()
