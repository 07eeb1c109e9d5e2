"""Shared fixtures: the repository root as working directory (scenes are named as the CLI
names them, by the path given) and the CLI binary for comparisons."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def _cli_path():
    given = os.environ.get("NURBSPRING_CLI")
    if given:
        return Path(given)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        p = target / profile / "nurbspring"
        if p.exists():
            return p
    found = shutil.which("nurbspring")
    return Path(found) if found else None


@pytest.fixture(autouse=True)
def in_repo(monkeypatch):
    monkeypatch.chdir(REPO)


@pytest.fixture(scope="session")
def cli():
    """Runs the nurbspring CLI (NURBSPRING_CLI, or target/debug/nurbspring) in the repo root."""
    path = _cli_path()
    if path is None or not path.exists():
        pytest.skip("the nurbspring CLI is not built (cargo build -p nurbspring)")

    def run(*args, check=True):
        return subprocess.run(
            [str(path), "--quiet", *map(str, args)],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=check,
        )

    return run
