"""The Newton export (`nurbspring export msm.json --format newton`) stepped by NVIDIA Newton on
the CPU follows nurbspring's `simulate` of the same msm.json over 1 s (docs/export.md).

The test runs Newton with the interpreter named by NURBSPRING_NEWTON_PYTHON, or this one when it
imports newton. Otherwise it installs Newton (`pip install newton`, which brings warp-lang,
about 150 MB) into its own virtual environment, kept in the temporary folder for later runs
(NURBSPRING_NEWTON_VENV names another place), and is skipped with pip's reason when that
cannot be done (no network, no space). NURBSPRING_NEWTON_INSTALL=0 skips the installation.

    python3 -m venv /tmp/newton && /tmp/newton/bin/pip install newton
    NURBSPRING_NEWTON_PYTHON=/tmp/newton/bin/python pytest bindings/python/tests/test_engine_newton.py
"""

import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest


def _imports_newton(python):
    try:
        return subprocess.run([python, "-c", "import newton, warp"], capture_output=True,
                              timeout=300).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def _install_newton():
    """Newton in the test's own virtual environment: (python, None), or (None, why not)."""
    if os.environ.get("NURBSPRING_NEWTON_INSTALL") == "0":
        return None, "NURBSPRING_NEWTON_INSTALL=0"
    venv = Path(os.environ.get("NURBSPRING_NEWTON_VENV")
                or Path(tempfile.gettempdir()) / "nurbspring-newton-venv")
    python = venv / "bin" / "python"
    if python.exists() and _imports_newton(str(python)):
        return str(python), None
    steps = [[sys.executable, "-m", "venv", str(venv)],
             [str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
              "numpy", "newton"]]
    for step in steps:
        try:
            done = subprocess.run(step, capture_output=True, text=True, timeout=900)
        except (OSError, subprocess.TimeoutExpired) as e:
            return None, f"{' '.join(step[:4])}: {e}"
        if done.returncode != 0:
            lines = (done.stderr or done.stdout).strip().splitlines()
            return None, f"{' '.join(step[:4])} failed: {lines[-1] if lines else done.returncode}"
    if _imports_newton(str(python)):
        return str(python), None
    return None, f"newton installed in {venv} but does not import"


def _newton_python():
    for python in filter(None, [os.environ.get("NURBSPRING_NEWTON_PYTHON"), sys.executable]):
        if _imports_newton(python):
            return python, None
    return _install_newton()


NEWTON_PYTHON, WHY_NOT = _newton_python()
needs_newton = pytest.mark.skipif(
    NEWTON_PYTHON is None,
    reason=f"NVIDIA Newton could not be installed here ({WHY_NOT}); pip install newton into a "
    "venv and set NURBSPRING_NEWTON_PYTHON to its python",
)


def cloth(path, curved):
    """A 9 x 7 triangulated cloth (alternating diagonals): springs on every edge with axial
    damping, a hinge on every interior edge (rest angles from the positions: zero when flat,
    not when `curved`), varied masses and weights, two corners fixed, gravity, node damping,
    an initial velocity; symplectic Euler, dt = 5e-4, 1 s."""
    nu, nv = 9, 7

    def idx(i, j):
        return i * nv + j

    nodes = []
    for i in range(nu):
        for j in range(nv):
            x, y = i / (nu - 1), 0.8 * j / (nv - 1)
            z = 0.15 * math.sin(2 * x) * math.cos(y) if curved else 0.0
            nodes.append({"position": [x, y, z], "mass": 0.01 * (1 + 0.1 * ((i + j) % 3)),
                          "fixed": i == 0 and j in (0, nv - 1), "damping": 0.002,
                          "uv": [i / (nu - 1), j / (nv - 1)]})
    tris = []
    for i in range(nu - 1):
        for j in range(nv - 1):
            p00, p10, p11, p01 = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            if (i + j) % 2 == 0:
                tris += [[p00, p10, p11], [p00, p11, p01]]
            else:
                tris += [[p00, p10, p01], [p10, p11, p01]]
    springs, hinges, first = [], [], {}
    for t in tris:
        for c in range(3):
            f, to, o = t[c], t[(c + 1) % 3], t[(c + 2) % 3]
            key = (min(f, to), max(f, to))
            grid = f // nv == to // nv or f % nv == to % nv
            if key in first:
                f0, t0, o0 = first.pop(key)
                hinges.append({"nodes": [f0, t0, o0, o],
                               "class": "hinge" if grid else "hinge_diagonal",
                               "k": 0.02 if grid else 0.01,
                               "weight": 1.0 + 0.02 * (len(hinges) % 5)})
            else:
                first[key] = (f, to, o)
                springs.append({"a": f, "b": to, "kind": "structural" if grid else "shear",
                                "k": 40.0 if grid else 15.0,
                                "weight": 1.0 + 0.01 * (len(springs) % 7), "damping": 0.01})
    velocities = [[0.0, 0.0, 0.0] if n["fixed"] else
                  [0.0, 0.05 * n["position"][0], 0.3 * n["position"][0]] for n in nodes]
    model = {"nodes": nodes, "springs": springs, "hinges": hinges, "triangles": tris,
             "gravity": [0.0, 0.0, -9.81], "grid": [nu, nv], "initial_velocities": velocities,
             "simulation": {"dt": 0.0005, "t_end": 1.0, "integrator": "symplectic-euler"},
             "probe_nodes": [idx(nu - 1, nv - 1), idx(nu // 2, nv // 2)]}
    path.write_text(json.dumps(model))
    return path


def trajectory(path):
    with open(path) as f:
        header = f.readline().strip()
    return header, np.loadtxt(path, delimiter=",", skiprows=1)


def difference(ours, theirs):
    """(relative RMS over every sample and probe coordinate, largest difference over the
    largest motion of a probe coordinate)."""
    a, b = ours[:, 1:], theirs[:, 1:]
    d = a - b
    return (float(np.linalg.norm(d) / np.linalg.norm(a)),
            float(np.abs(d).max() / np.abs(a - a[0]).max()))


@needs_newton
@pytest.mark.parametrize("curved", [False, True], ids=["flat", "curved"])
def test_newton_follows_simulate(cli, tmp_path, curved):
    model = cloth(tmp_path / "msm.json", curved)
    cli("simulate", model, "--model", "msm", "--out", tmp_path / "ours")
    script = tmp_path / "cloth_newton.py"
    cli("export", model, "--format", "newton", "--out", script)
    runs = {}
    for bending in ("nurbspring", "newton"):
        out = tmp_path / f"newton_{bending}.csv"
        subprocess.run([NEWTON_PYTHON, str(script), str(out), "--bending", bending],
                       check=True, capture_output=True, timeout=600)
        runs[bending] = trajectory(out)
    header, ours = trajectory(tmp_path / "ours" / "trajectory.csv")
    for theirs_header, theirs in runs.values():
        assert theirs_header == header
        assert theirs.shape == ours.shape and ours.shape[0] > 100
        np.testing.assert_allclose(theirs[:, 0], ours[:, 0], rtol=0, atol=1e-12)
    # The run moves: the free corner falls and swings by more than a third of the size.
    assert np.abs(ours[:, 1:] - ours[0, 1:]).max() > 0.3
    # Newton's springs, gravity and integrator with nurbspring's hinge force: the same model,
    # up to Newton's float32 (the docs' NumPy stepper run in float32 differs from `simulate` by
    # the same 5e-7 RMS, 7e-7 of the motion at most; in float64 by 2e-15).
    rms, worst = difference(ours, runs["nurbspring"][1])
    assert rms <= 1e-6 and worst <= 1e-6, (rms, worst)
    # Newton's own bending edges, edge_ke converted at rest: equal to first order about the rest
    # state only (docs/export.md: 0.4 % RMS on this cloth).
    rms, worst = difference(ours, runs["newton"][1])
    assert rms <= 1e-2, (rms, worst)
