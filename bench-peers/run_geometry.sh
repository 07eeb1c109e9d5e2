#!/usr/bin/env bash
# Runs every "Geometry" benchmark of docs/benchmarks.md in one session, in release:
# nurbspring-geom's own bench, nurbspring vs curvo, then splipy on the same patch.
# Needs a Python venv with splipy (PYTHON, default /tmp/peers/bin/python):
#   python3 -m venv /tmp/peers && /tmp/peers/bin/pip install splipy numpy
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-/tmp/peers/bin/python}
ARGS=(--warm-up-time 1 --measurement-time 3)
echo "== machine"
lscpu | grep -E "Model name|^CPU\(s\)"
uptime
rustc --version
echo "== nurbspring-geom (crates/geom/benches/evaluate.rs)"
cargo bench -p nurbspring-geom --bench evaluate -- "${ARGS[@]}"
echo "== nurbspring vs curvo (bench-peers/benches/peers.rs)"
cargo bench --manifest-path bench-peers/Cargo.toml --bench peers -- "${ARGS[@]}"
echo "== splipy (bench-peers/splipy_grid.py)"
"$PYTHON" bench-peers/splipy_grid.py
uptime
