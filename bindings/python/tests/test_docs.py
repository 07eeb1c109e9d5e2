"""The examples of docs/python.md run as written."""

import re

import pytest

from conftest import REPO

BLOCKS = re.findall(r"```python\n(.*?)```", (REPO / "docs" / "python.md").read_text(), re.S)


def test_the_tour_runs(capsys):
    exec(compile(BLOCKS[0], "docs/python.md (tour)", "exec"), {})
    assert "the mass density must be positive" in capsys.readouterr().out


def test_the_notebook_example_runs():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    exec(compile(BLOCKS[1], "docs/python.md (notebook)", "exec"), {})
