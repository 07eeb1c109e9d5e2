"""Every function of the package on the examples: shapes, values, and exact agreement with
the CLI's files (matrices to the last bit, report.json and msm.json key by key)."""

import json
import struct

import numpy as np
import pytest

import nurbspring as ns

CURVE_TOML = """
[curve]
degree = 2
knots = [0, 0, 0, 1, 1, 1]
control_points = [[0, 0, 0], [1, 1, 0], [2, 0, 0]]

[material]
mu = 2.0
alpha11 = 1.0

[constraints]
fixed_rings = 1
"""

SHEET = "examples/sheet_gravity.toml"
PAPER = "examples/paper.toml"


def bits(x):
    return struct.pack("<d", float(x))


def read_mtx(path):
    """Matrix Market coordinate or array file, values as Python floats (exact); a `symmetric`
    file holds the lower triangle only."""
    lines = [l for l in open(path) if not l.startswith("%")]
    head = lines[0].split()
    if len(head) == 3:
        nrows, ncols, _ = map(int, head)
        entries = {}
        for l in lines[1:]:
            i, j, v = l.split()
            entries[(int(i) - 1, int(j) - 1)] = float(v)
        return (nrows, ncols), entries
    return tuple(map(int, head)), [float(l) for l in lines[1:]]


def assert_close(a, b, path="report"):
    """Equal JSON values, floats to 1e-12 relative or 1e-25 absolute."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for k in a:
            assert_close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            assert_close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert abs(a - b) <= max(1e-12 * max(abs(a), abs(b)), 1e-25), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def csr_entries(a):
    if isinstance(a, tuple):
        data, indices, indptr, shape = a
    else:
        data, indices, indptr, shape = a.data, a.indices, a.indptr, a.shape
    # Stored zeros are left out, as the CLI's Matrix Market files leave them out.
    out = {}
    for i in range(shape[0]):
        for k in range(indptr[i], indptr[i + 1]):
            if data[k] != 0.0:
                out[(i, int(indices[k]))] = float(data[k])
    return tuple(shape), out


# --- scenes and geometry -----------------------------------------------------------------


def test_load_from_toml_and_from_dict_agree():
    a = ns.Scene.load(SHEET)
    assert a.path == SHEET and a.kind == "surface"
    b = ns.Scene.from_toml(open(SHEET).read(), name=SHEET)
    c = ns.Scene.from_toml(a.to_toml(), name="round trip")
    assert b.to_toml() == a.to_toml() == c.to_toml()
    curve = ns.Scene.from_toml(CURVE_TOML)
    d = ns.Scene.from_dict(
        {
            "curve": {
                "degree": 2,
                "knots": np.array([0.0, 0, 0, 1, 1, 1]),
                "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]],
            },
            "material": {"mu": 2.0, "alpha11": 1.0},
            "constraints": {"fixed_rings": 1},
        }
    )
    assert d.kind == "curve" and d.path == "<dict>"
    assert d.to_toml() == curve.to_toml()


def test_surface_evaluate_shapes_and_values():
    scene = ns.Scene.load(PAPER)
    surface = scene.surface
    (u0, u1), (v0, v1) = surface.domain
    u = np.linspace(u0, u1, 7)
    v = np.linspace(v0, v1, 7)
    pts = surface.evaluate(u, v)
    assert pts.shape == (7, 3) and pts.dtype == np.float64
    # A clamped surface interpolates its corner control points.
    assert np.allclose(pts[0], [0.0, 0.0, 2.0]) and np.allclose(pts[-1], [3.0, 5.0, 2.0])
    assert surface.evaluate(0.5, 0.5).shape == (3,)
    d1 = surface.evaluate(u, v, derivatives=1)
    assert sorted(d1) == ["point", "u", "v"]
    d2 = surface.evaluate(u, v, derivatives=2)
    assert sorted(d2) == ["point", "u", "uu", "uv", "v", "vv"]
    assert np.array_equal(d2["point"], pts)
    # ∂c/∂u against a central difference.
    h = 1e-6
    fd = (surface.evaluate(0.4 + h, 0.3) - surface.evaluate(0.4 - h, 0.3)) / (2 * h)
    assert np.allclose(surface.evaluate(0.4, 0.3, derivatives=1)["u"], fd, rtol=1e-6, atol=1e-7)
    with pytest.raises(ns.InputError):
        surface.evaluate(1.5, 0.5)
    with pytest.raises(ns.InputError):
        scene.curve


def test_curve_evaluate():
    scene = ns.Scene.from_toml(CURVE_TOML)
    pts = scene.curve.evaluate([0.0, 0.5, 1.0])
    assert np.allclose(pts, [[0, 0, 0], [1, 0.5, 0], [2, 0, 0]])
    assert sorted(scene.curve.evaluate([0.5], derivatives=2)) == ["point", "u", "uu"]
    with pytest.raises(ns.InputError):
        scene.surface


# --- matrices and modes ------------------------------------------------------------------


@pytest.mark.parametrize("example", [PAPER, SHEET, "examples/half_cylinder.toml", "examples/string.toml"])
def test_matrices_equal_the_cli_files_to_the_last_bit(cli, tmp_path, example):
    out = tmp_path / "m"
    cli("matrices", example, "--out", out)
    mats = ns.matrices(ns.Scene.load(example))
    for name in "MDK":
        symmetric = "symmetric" in open(out / f"{name}.mtx").readline()
        shape, entries = read_mtx(out / f"{name}.mtx")
        got_shape, got = csr_entries(mats[name])
        assert got_shape == shape
        if symmetric:
            # The file stores the lower triangle, bit for bit; the upper one mirrors it to the
            # writer's symmetry tolerance (1e-12 of the largest entry).
            scale = max((abs(v) for v in got.values()), default=0.0)
            for (i, j), v in got.items():
                if i < j:
                    assert abs(v - got.get((j, i), 0.0)) <= 1e-12 * scale, (name, i, j)
            got = {k: v for k, v in got.items() if k[0] >= k[1]}
        assert got.keys() == entries.keys()
        assert all(bits(got[k]) == bits(entries[k]) for k in entries), name
    _, f = read_mtx(out / "f.mtx")
    assert mats["f"].shape == (len(f),)
    assert [bits(x) for x in mats["f"]] == [bits(x) for x in f]
    dofs = json.load(open(out / "dofs.json"))
    dofs.pop("files")
    got = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in mats["dofs"].items()}
    assert got == dofs


def test_matrices_are_scipy_csr():
    sparse = pytest.importorskip("scipy.sparse")
    mats = ns.matrices(ns.Scene.load(SHEET))
    n = mats["dofs"]["n_dofs"]
    for name in "MDK":
        assert sparse.isspmatrix_csr(mats[name]) and mats[name].shape == (n, n)
    m = mats["M"]
    assert abs(m - m.T).max() <= 1e-12 * abs(m).max()


def test_modes_equal_the_cli(cli):
    scene = ns.Scene.load(SHEET)
    omega = ns.modes(scene, count=6)
    assert omega.shape == (6,) and np.all(np.diff(omega) >= 0)
    printed = json.loads(cli("modes", SHEET, "--count", 6).stdout)
    assert [bits(x) for x in omega] == [bits(x) for x in printed["omega"]]
    with pytest.raises(ns.InputError):
        ns.modes(scene, count=0)


# --- simulations -------------------------------------------------------------------------


def read_csv(path):
    rows = [l.strip().split(",") for l in open(path)]
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


@pytest.mark.parametrize("model", ["dnurbs", "msm"])
def test_simulate_scene_equals_the_cli(cli, tmp_path, model):
    scene = ns.Scene.load(SHEET)
    run = ns.simulate(scene, model=model, t_end=0.5)
    out = tmp_path / model
    cli("simulate", SHEET, "--model", model, "--t-end", 0.5, "--out", out)
    header, traj = read_csv(out / "trajectory.csv")
    T, P = run["t"].size, run["probes"].shape[1]
    assert run["probes"].shape == (T, P, 3) and len(header) == 1 + 3 * P
    assert np.array_equal(run["t"], traj[:, 0])
    assert np.array_equal(run["probes"].reshape(T, 3 * P), traj[:, 1:])
    _, energy = read_csv(out / "energy.csv")
    assert np.array_equal(run["energy"]["kinetic"], energy[:, 1])
    assert np.array_equal(run["energy"]["elastic"], energy[:, 2])
    assert np.array_equal(run["energy"]["external"], energy[:, 3])
    assert np.array_equal(run["energy"]["total"], energy[:, 4])
    assert run["t_end"] == 0.5


def test_simulate_options_and_errors():
    scene = ns.Scene.load(SHEET)
    run = ns.simulate(scene, integrator="newmark", dt=0.05, t_end=0.2)
    assert run["integrator"] == "newmark" and run["dt"] == 0.05
    # A short, smooth run: no step was halved, none stopped the run.
    assert run["halved_steps"] == 0 and run["stopped"] is None
    with pytest.raises(ns.InputError, match="unknown integrator"):
        ns.simulate(scene, integrator="leapfrog-ish")
    with pytest.raises(ns.InputError, match="model"):
        ns.simulate(scene, model="fem")
    with pytest.raises(ns.InputError, match="--dt"):
        ns.simulate(scene, dt=-1.0)


# --- derivations -------------------------------------------------------------------------


def test_derive_equals_the_cli_files(cli, tmp_path):
    scene = ns.Scene.load(SHEET)
    d = ns.derive(scene, derivation="modal")
    cli("derive", SHEET, "--derivation", "modal", "--out", tmp_path / "d")
    report = json.load(open(tmp_path / "d" / "report.json"))
    assert d.report.keys() == report.keys()
    assert d.report == report
    assert d.msm == json.load(open(tmp_path / "d" / "msm.json"))
    c = d.central_node
    assert c["dnurbs"].shape == c["msm"].shape == (c["t"].size, 3)
    _, csv = read_csv(tmp_path / "d" / "central_node.csv")
    assert np.array_equal(np.column_stack([c["t"], c["dnurbs"], c["msm"]]), csv)


def test_mass_spring_from_derived_dict_runs():
    d = ns.derive(ns.Scene.load(SHEET), derivation="modal")
    msm = ns.MassSpring.from_dict(d.msm)
    n = len(d.msm["nodes"])
    assert msm.positions.shape == (n, 3) and msm.masses.shape == (n,)
    assert msm.fixed.dtype == bool and msm.fixed.shape == (n,)
    assert msm.springs.shape == (len(d.msm["springs"]), 2)
    assert isinstance(msm.elements, list)
    run = ns.simulate(msm, integrator="newmark", dt=0.01, t_end=0.5)
    assert run["probes"].shape == (run["t"].size, len(d.msm["probe_nodes"]), 3)
    assert run["integrator"] == "newmark"
    assert d.mass_spring().positions.shape == (n, 3)


def test_mass_spring_equals_the_cli_on_a_file(cli, tmp_path):
    d = ns.derive(ns.Scene.load(SHEET), derivation="modal")
    path = tmp_path / "msm.json"
    path.write_text(json.dumps(d.msm))
    run = ns.simulate(ns.MassSpring.load(path), integrator="newmark", t_end=0.4)
    cli("simulate", path, "--model", "msm", "--integrator", "newmark", "--t-end", 0.4, "--out", tmp_path / "r")
    _, traj = read_csv(tmp_path / "r" / "trajectory.csv")
    assert np.array_equal(run["probes"].reshape(run["t"].size, -1), traj[:, 1:])


def test_mass_spring_of_a_scene():
    msm = ns.MassSpring.from_scene(ns.Scene.load(PAPER))
    s = msm.stability()
    assert s["omega_max"] > 0 and s["dt_critical"] > 0
    assert msm.probe_nodes[0] >= 0 and msm.grid is not None


def test_run_error_on_a_diverging_run():
    msm = ns.MassSpring.from_scene(ns.Scene.load(PAPER))
    dt = 20 * msm.stability()["dt_critical"]
    with pytest.raises(ns.InputError, match="dt"):
        ns.simulate(msm, integrator="symplectic-euler", dt=dt, t_end=1000 * dt)
    with pytest.raises(ns.RunError):
        ns.simulate(msm, integrator="symplectic-euler", dt=dt, t_end=1000 * dt, force_unstable=True)


def test_paper_equals_the_cli(cli, tmp_path):
    report = ns.paper()
    cli("paper", "--out", tmp_path / "p")
    # Quantities at round-off level (the lattice's normal stiffness share, ~1e-32) depend on
    # the order of parallel sums: equal to 1e-12 relative (or 1e-25 absolute), keys exactly.
    assert_close(report, json.load(open(tmp_path / "p" / "report.json")))
    assert "verdicts" in report["paper"]
