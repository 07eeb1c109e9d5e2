#!/usr/bin/env bash
# Issue 31's speed target in one session: the explicit (symplectic-Euler) step of a 256 x 256
# spring + hinge cloth in nurbspring (crates/msm/benches/cloth.rs, criterion, at 2 threads and
# at 1) beside NVIDIA Newton's (Warp's) CPU cloth step on the same mesh and elements
# (bench-peers/cloth_step_newton.py, after its agreement check against nurbspring's dumped
# states, crates/msm/examples/cloth_dump.rs). docs/benchmarks.md ("Cloth step") has the figures.
# Needs a Python with newton (PYTHON, default /tmp/newton/bin/python):
#   python3 -m venv /tmp/newton && /tmp/newton/bin/pip install newton
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-/tmp/newton/bin/python}
DUMP=${DUMP:-/tmp/nurbspring-cloth}
echo "== machine"
lscpu | grep -E "Model name|^CPU\(s\)|L3" || true
uptime
rustc --version
echo "== nurbspring's cloth and its states after 1 and 10 steps (crates/msm/examples/cloth_dump.rs)"
cargo run --release -p nurbspring-msm --example cloth_dump -- "$DUMP"
echo "== nurbspring (crates/msm/benches/cloth.rs), 2 threads"
RAYON_NUM_THREADS=2 nice -n 10 cargo bench -p nurbspring-msm --bench cloth -- --save-baseline two-threads
echo "== nurbspring, 1 thread"
RAYON_NUM_THREADS=1 nice -n 10 cargo bench -p nurbspring-msm --bench cloth -- --save-baseline one-thread
echo "== Newton (bench-peers/cloth_step_newton.py)"
nice -n 10 "$PYTHON" bench-peers/cloth_step_newton.py "$DUMP"
uptime
