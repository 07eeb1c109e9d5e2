"""Reads nurbspring's lattice frames with VTK itself (not run in CI).

    python3 -m venv /tmp/vtkenv && /tmp/vtkenv/bin/pip install vtk meshio
    cargo run -p nurbspring-scene --example lattice_vtk -- /tmp/lattice-vtk
    cargo run -p nurbspring -- derive examples/paper.toml --derivation paper --out /tmp/paper-derive
    /tmp/vtkenv/bin/python scripts/vtk-check/check_lattice_vtk.py /tmp/lattice-vtk /tmp/paper-derive

Checks, for each of binary64.vtu, binary32.vtu and ascii.vtu (and derive's lattice.vtu), that
vtkXMLUnstructuredGridReader gives one VTK_LINE cell per spring, a numeric cell array `kind`
and a vtkStringArray `kind_name` whose every entry is the name of its code (0 structural,
1 shear, 2 bend), and that the three encodings hold the same values. It also records what
meshio makes of the same files (meshio reads no string array, see docs/export.md).
"""
import os
import sys

import vtk
from vtk.util.numpy_support import vtk_to_numpy

NAMES = {0: "structural", 1: "shear", 2: "bend"}


def read(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode() != 0:
        raise SystemExit(f"{path}: VTK reports error code {r.GetErrorCode()}")
    g = r.GetOutput()
    cd = g.GetCellData()
    kind = cd.GetArray("kind")
    names = cd.GetAbstractArray("kind_name")
    if kind is None or names is None:
        raise SystemExit(f"{path}: kind or kind_name missing")
    if not isinstance(names, vtk.vtkStringArray):
        raise SystemExit(f"{path}: kind_name is a {type(names).__name__}, not a vtkStringArray")
    n = g.GetNumberOfCells()
    types = {g.GetCellType(i) for i in range(n)}
    if types != {vtk.VTK_LINE}:
        raise SystemExit(f"{path}: cell types {types}, expected only VTK_LINE (3)")
    codes = [int(c) for c in vtk_to_numpy(kind)]
    strings = [names.GetValue(i) for i in range(names.GetNumberOfValues())]
    if len(codes) != n or len(strings) != n:
        raise SystemExit(f"{path}: {n} cells, {len(codes)} codes, {len(strings)} names")
    bad = [(i, c, s) for i, (c, s) in enumerate(zip(codes, strings)) if NAMES.get(c) != s]
    if bad:
        raise SystemExit(f"{path}: cell, code, name that disagree: {bad[:5]}")
    counts = {name: strings.count(name) for name in NAMES.values()}
    return n, codes, strings, counts


def meshio_verdict(path):
    try:
        import meshio
    except ImportError:
        return "meshio not installed"
    try:
        m = meshio.read(path)
        return f"meshio reads it: {[(c.type, len(c.data)) for c in m.cells]}"
    except BaseException as e:  # meshio calls sys.exit on some read errors
        return f"meshio refuses it: {type(e).__name__}: {e}"


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    frames = sys.argv[1]
    results = {}
    for name in ["binary64.vtu", "binary32.vtu", "ascii.vtu"]:
        path = os.path.join(frames, name)
        results[name] = read(path)
        n, _, _, counts = results[name]
        print(f"{name}: {n} VTK_LINE cells, kind_name counts {counts}")
    first = results["binary64.vtu"]
    for name, r in results.items():
        if r[1:3] != first[1:3]:
            raise SystemExit(f"{name} differs from binary64.vtu")
    if min(first[3].values()) == 0:
        raise SystemExit(f"not every kind occurs: {first[3]}")
    print("binary (UInt64, UInt32) and ascii agree")
    print("meshio on binary64.vtu:", meshio_verdict(os.path.join(frames, "binary64.vtu")))
    if len(sys.argv) > 2:
        path = os.path.join(sys.argv[2], "lattice.vtu")
        n, _, _, counts = read(path)
        print(f"{path}: {n} VTK_LINE cells, kind_name counts {counts}")
    print("ok")


if __name__ == "__main__":
    main()
