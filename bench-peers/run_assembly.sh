#!/usr/bin/env bash
# Runs every "Assembly" benchmark of docs/benchmarks.md in one session, in release:
# nurbspring-dnurbs's own bench (rayon default pool, then one thread), the size-scaling bench
# of bench-peers, then G+Smo (pygismo) and the numpy/scipy Kronecker shortcut on the same
# 128 x 128-element bicubic patch, after the agreement checks against nurbspring's matrices.
# Needs a Python venv with pygismo, numpy and scipy (PYTHON, default /tmp/peers2/bin/python):
#   python3 -m venv /tmp/peers2 && /tmp/peers2/bin/pip install pygismo numpy scipy
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-/tmp/peers2/bin/python}
DUMP=${DUMP:-/tmp/nurbspring-agree}
echo "== machine"
lscpu | grep -E "Model name|^CPU\(s\)|L3"
uptime
rustc --version
echo "== nurbspring matrices for the agreement check (bench-peers/examples/dump_dnurbs.rs)"
cargo run --release --manifest-path bench-peers/Cargo.toml --example dump_dnurbs -- "$DUMP"
echo "== nurbspring-dnurbs (crates/dnurbs/benches/assembly.rs), rayon default pool"
cargo bench -p nurbspring-dnurbs --bench assembly
echo "== the same, one thread (RAYON_NUM_THREADS=1), assembly only"
RAYON_NUM_THREADS=1 cargo bench -p nurbspring-dnurbs --bench assembly -- \
  --save-baseline one-thread "pattern only|Assembler::assemble_scalar"
echo "== sizes 32, 64, 128 (bench-peers/benches/dnurbs_scaling.rs)"
cargo bench --manifest-path bench-peers/Cargo.toml --bench dnurbs_scaling
echo "== G+Smo and the Kronecker shortcut (bench-peers/gismo_assembly.py)"
(cd bench-peers && "$PYTHON" gismo_assembly.py "$DUMP")
uptime
