#!/usr/bin/env bash
# Runs every "Mass-spring step" benchmark of docs/benchmarks.md in one session, in release:
# nurbspring-msm's own bench (memory bandwidth and triads, forces, the fused and the generic
# symplectic-Euler step, backward-Euler steps; rayon default pool, then the explicit ones and
# the triads on one thread), then the same
# symplectic-Euler step in numpy, Taichi (CPU, f64) and NVIDIA Warp (CPU, f32), each after
# checking its result against nurbspring's.
# Needs a Python venv (PYTHON, default /tmp/peers2/bin/python):
#   python3 -m venv /tmp/peers2 && /tmp/peers2/bin/pip install numpy taichi warp-lang
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-/tmp/peers2/bin/python}
DUMP=${DUMP:-/tmp/nurbspring-agree}
echo "== machine"
lscpu | grep -E "Model name|^CPU\(s\)|L3"
uptime
rustc --version
echo "== nurbspring reference states for the agreement check (bench-peers/examples/dump_msm.rs)"
cargo run --release --manifest-path bench-peers/Cargo.toml --example dump_msm -- "$DUMP"
echo "== nurbspring-msm (crates/msm/benches/step.rs), rayon default pool"
cargo bench -p nurbspring-msm --bench step
echo "== the same, one thread (RAYON_NUM_THREADS=1), explicit step only"
RAYON_NUM_THREADS=1 cargo bench -p nurbspring-msm --bench step -- \
  --save-baseline one-thread "triad|internal_force|symplectic|spring_arithmetic"
cd bench-peers
for peer in numpy taichi warp; do
  echo "== $peer (bench-peers/msm_step_$peer.py)"
  "$PYTHON" "msm_step_$peer.py" "$DUMP"
done
uptime
