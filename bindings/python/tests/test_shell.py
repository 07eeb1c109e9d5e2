"""Kirchhoff–Love scenes through the Python package: load, solve (the equilibrium path), modes and
a simulation, each equal to what the CLI prints or writes."""

import json

import numpy as np
import pytest

import nurbspring as ns

STRIP = "examples/cantilever_strip.toml"


def bits(x):
    return np.float64(x).tobytes()


def test_steady_path_equals_the_cli(cli, tmp_path):
    scene = ns.Scene.load(STRIP)
    solved = ns.steady(scene, load_steps=4)
    assert solved["equations"].startswith("nonlinear")
    assert [level["lambda"] for level in solved["path"]] == [0.25, 0.5, 0.75, 1.0]
    assert solved["p"].shape[1] == 3
    printed = json.loads(cli("steady", STRIP, "--load-steps", 4, "--out", tmp_path / "s").stdout)
    assert solved["probes"] == printed["probes"]
    rows = [l.strip().split(",") for l in open(tmp_path / "s" / "load_path.csv")][1:]
    for level, row in zip(solved["path"], rows):
        assert bits(level["lambda"]) == bits(float(row[0]))
        mine = level["displacements"].ravel()
        theirs = np.array([float(x) for x in row[1:]])
        assert [bits(x) for x in mine] == [bits(x) for x in theirs]
    # The tip under the full end shear: Sze's table gives w = 6.698 (the elastica 6.6996).
    tip = solved["path"][-1]["displacements"][1]
    assert abs(tip[2] - 6.6996) < 0.01 * 6.6996


def test_linear_and_modes_of_a_shell(cli):
    scene = ns.Scene.load(STRIP)
    linear = ns.steady(scene, linear=True)
    assert linear["equations"].startswith("linear")
    # The linear tip deflection P L³ / (3 E I) = 4 · 1000 / (3 · 1.2e6 · 1e-4 / 1.2... ): the
    # nonlinear one is smaller (the tip moves inwards and the arm shortens).
    assert linear["path"][-1]["displacements"][1][2] > 6.6996
    omega = ns.modes(scene, count=3)
    printed = json.loads(cli("modes", STRIP, "--count", 3).stdout)
    assert [bits(x) for x in omega] == [bits(x) for x in printed["omega"]]


def test_simulate_a_shell(cli, tmp_path):
    scene = ns.Scene.load(STRIP)
    run = ns.simulate(scene, model="dnurbs", t_end=0.05)
    assert run["integrator"] == "newmark"
    cli("simulate", STRIP, "--model", "dnurbs", "--t-end", 0.05, "--out", tmp_path / "r")
    rows = [l.strip().split(",") for l in open(tmp_path / "r" / "trajectory.csv")][1:]
    probes = run["probes"].reshape(len(rows), -1)
    for mine, row in zip(probes, rows):
        assert [bits(x) for x in mine] == [bits(float(x)) for x in row[1:]]


def test_springs_derivation_equals_the_cli(cli, tmp_path):
    cloth = "examples/cloth_corners.toml"
    d = ns.derive(ns.Scene.load(cloth))
    assert d.report["derivation"] == "springs"
    assert d.report["hinges"] > 0 and len(d.msm["hinges"]) == d.report["hinges"]
    cli("derive", cloth, "--out", tmp_path / "d")
    written = json.load(open(tmp_path / "d" / "report.json"))
    assert written == d.report
    assert json.load(open(tmp_path / "d" / "msm.json")) == d.msm
    assert d.central_node["t"].size == 0
    # The lowest elastic frequency is the shell's.
    assert abs(d.report["frequencies"][0]["relative_error"]) < 1e-9


def test_modal_derivation_of_a_shell_groups_by_band():
    d = ns.derive(ns.Scene.load("examples/cloth_corners.toml"), derivation="modal")
    assert d.report["derivation"] == "modal"
    groups = d.report["groups"]
    assert sum(g["elements"] for g in groups) == d.report["springs"] + d.report["hinges"]
    assert abs(d.report["frequencies"][0]["relative_error"]) < 1e-9


def test_reduction_of_a_shell_has_no_msm():
    d = ns.derive(ns.Scene.load(STRIP), derivation="reduction")
    assert d.report["derivation"] == "reduction" and d.report["kind"] == "exact"
    assert d.msm is None
    assert all(abs(f["relative_error"]) < 1e-9 for f in d.report["frequencies"])
    with pytest.raises(ns.InputError):
        d.mass_spring()
