#!/usr/bin/env bash
# Issue 33's implicit paper derivation against its SciPy reference, in one run: writes the
# scene (a 17 x 17 bicubic net clamped by two rings, the 33 x 33 uniform lattice, dt = 0.01,
# t_end = 20, the paper's derivation, backward Euler for the MSM; and the same with the
# explicit default integrator), times `nurbspring derive` on both (release build), then
# bench-peers/paper_implicit_reference.py (Kronecker assembly of 3267 unknowns and 8
# shift-invert modes), and prints the ratio with the machine and its load.
#   bench-peers/paper_implicit.sh [OUT]     (PYTHON: an interpreter with numpy and scipy)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=$(realpath -m "${1:-/tmp/nurbspring-paper-implicit}")
PYTHON=${PYTHON:-python3}
mkdir -p "$OUT"
cargo build --release -q -p nurbspring
BIN=${BIN:-target/release/nurbspring}
"$PYTHON" - "$OUT" <<'PY'
import sys
n, p = 17, 3
inner = n - p - 1
knots = [0.0] * (p + 1) + [i / (inner + 1) for i in range(1, inner + 1)] + [1.0] * (p + 1)
g = [sum(knots[i + 1:i + p + 1]) / p for i in range(n)]
rows = ",\n".join("  [" + ", ".join(f"[{x!r}, {y!r}, 0.0]" for y in g) + "]" for x in g)
base = f"""[surface]
degree_u = 3
degree_v = 3
knots_u = {knots}
knots_v = {knots}
control_points = [
{rows}
]
[material]
mu = 1.0
alpha11 = 1.0
alpha22 = 1.0
beta11 = 0.01
beta22 = 0.01
[constraints]
fixed_rings = 2
[initial]
velocity = [0.0, 0.0, -0.1]
[msm]
grid = "uniform"
nodes_u = 33
nodes_v = 33
[fit]
derivation = "paper"
"""
out = sys.argv[1]
open(f"{out}/explicit.toml", "w").write(base + "[simulation]\ndt = 0.01\nt_end = 20.0\n")
open(f"{out}/implicit.toml", "w").write(
    base + '[simulation]\ndt = 0.01\nt_end = 20.0\nmsm_integrator = "backward-euler"\n')
PY
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); load $(cut -d' ' -f1-3 /proc/loadavg)"
for job in explicit implicit; do
  start=$(date +%s.%N)
  "$BIN" derive "$OUT/$job.toml" --out "$OUT/$job" -q > "$OUT/$job.txt" 2>&1
  end=$(date +%s.%N)
  echo "nurbspring derive ($job): $(echo "$end - $start" | bc) s"
  echo "$end - $start" | bc > "$OUT/$job.seconds"
done
"$PYTHON" bench-peers/paper_implicit_reference.py 5 | tee "$OUT/reference.json"
"$PYTHON" - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
ref = json.load(open(f"{out}/reference.json"))["seconds"]
for job in ("explicit", "implicit"):
    s = float(open(f"{out}/{job}.seconds").read())
    print(f"{job}: {s:.2f} s = {s / ref:.0f} x the SciPy reference ({ref:.3f} s)")
PY
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
