"""Bad input raises InputError (a ValueError) with the CLI's message; Ctrl-C raises
KeyboardInterrupt in the middle of a long call."""

import os
import signal
import subprocess
import sys
import time

import pytest

import nurbspring as ns

GOOD = open(os.path.join(os.path.dirname(__file__), "..", "..", "..", "examples", "sheet_gravity.toml")).read()


def test_input_error_is_a_value_error():
    assert issubclass(ns.InputError, ValueError)
    assert issubclass(ns.RunError, RuntimeError)
    assert not issubclass(ns.RunError, ns.InputError)


def test_invalid_value_names_file_key_and_value(cli, tmp_path):
    text = GOOD.replace("mu = 0.5", "mu = -0.5")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ns.InputError) as err:
        ns.Scene.load(path)
    message = str(err.value)
    assert "material.mu" in message and "-0.5" in message and str(path) in message
    printed = cli("check", path, check=False)
    assert printed.returncode != 0
    assert message in printed.stderr
    with pytest.raises(ValueError):
        ns.Scene.from_toml(text, name="bad.toml")


def test_syntax_and_unknown_keys():
    with pytest.raises(ns.InputError, match="x.toml"):
        ns.Scene.from_toml("[surface\n", name="x.toml")
    with pytest.raises(ns.InputError, match="materail"):
        ns.Scene.from_toml(GOOD + "\n[materail]\nmu = 1\n", name="y.toml")
    with pytest.raises(ns.InputError):
        ns.Scene.from_dict({"material": {"mu": float("nan")}})
    with pytest.raises(ns.InputError):
        ns.Scene.load("does/not/exist.toml")


def test_bad_msm_and_derivation_arguments():
    with pytest.raises(ns.InputError, match="nodes"):
        ns.MassSpring.from_dict({"springs": []})
    with pytest.raises(ns.InputError, match="unknown derivation"):
        ns.derive(ns.Scene.from_toml(GOOD), derivation="guess")


INTERRUPTED = r"""
import sys, nurbspring as ns
scene = ns.Scene.load("examples/paper.toml")
print("ready", flush=True)
try:
    ns.simulate(scene, model="dnurbs", t_end=1.0e5)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(3)
print("finished", flush=True)
"""


def test_ctrl_c_interrupts_a_long_simulation():
    p = subprocess.Popen(
        [sys.executable, "-c", INTERRUPTED],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert p.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        start = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert time.monotonic() - start < 10, "the run did not stop promptly"
    assert p.returncode == 3, (out, err)
    assert "interrupted" in out


def test_long_calls_release_the_gil():
    import threading

    scene = ns.Scene.load("examples/paper.toml")
    worker = threading.Thread(target=ns.simulate, args=(scene,), kwargs={"t_end": 1.0e4})
    worker.start()
    ticks = 0
    while worker.is_alive():
        ticks += 1
        time.sleep(0.005)
    worker.join()
    # Holding the GIL for the whole run would leave this thread a tick or two.
    assert ticks >= 10
