#!/usr/bin/env bash
# Runs every benchmark of docs/benchmarks.md and every peer back to back in one session, then
# regenerates the document's tables (the blocks between `<!-- generated: … -->` markers) from
# what this run measured, with the machine, versions and load:
#   1. builds everything first (release; the workspace, its benches and bench-peers, sharing
#      one target folder), so no build runs while anything is timed;
#   2. geometry: nurbspring-geom, curvo, splipy (run_geometry.sh);
#   3. assembly: nurbspring-dnurbs, G+Smo, NumPy Kronecker (run_assembly.sh);
#   4. derive with the default derivation (crates/scene/benches/derive.rs);
#   5. `nurbspring paper` and the paper's derivation on refined nets (scripts/bench-derive/run.sh);
#   6. the mass-spring steps: nurbspring-msm, NumPy, Taichi, Warp (run_msm.sh), and the
#      backward-Euler step against SciPy (msm_step_scipy_be.py).
# Every peer is checked against nurbspring's result (the dump_* examples) before it is timed;
# a failed check stops the run. Criterion writes into RESULTS/criterion (CRITERION_HOME), the
# peers and binaries into RESULTS/results-SECTION.jsonl, the machine into RESULTS/run.json; the full log
# is RESULTS/log.txt. Then bench-peers/tables.py rewrites docs/benchmarks.md's tables (unless
# NO_TABLES is set). Needs one Python venv with every peer:
#   python3 -m venv /tmp/peers2 && /tmp/peers2/bin/pip install numpy scipy splipy pygismo taichi warp-lang
#   PYTHON=/tmp/peers2/bin/python bench-peers/run_all.sh [RESULTS]   # about 30 minutes on 2 cores
# Run it on a quiet machine: the tables record the load, and figures from a loaded one are
# only good for ratios.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
export PYTHON=${PYTHON:-/tmp/peers2/bin/python}
RESULTS=$(realpath -m "${1:-/tmp/nurbspring-bench-$(date -u +%Y%m%dT%H%M%S)}")
mkdir -p "$RESULTS"
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}
export CRITERION_HOME=$RESULTS/criterion
export DUMP=$RESULTS/agree
# SECTIONS (default all: geometry assembly derive-modal derive-paper msm) reruns only those
# sections into an existing RESULTS folder, replacing their figures and keeping the others'.
SECTIONS=${SECTIONS:-geometry assembly derive-modal derive-paper msm}
touch "$RESULTS/sections.tsv"
exec > >(tee "$RESULTS/log.txt") 2>&1

"$PYTHON" -c "import numpy, scipy, splipy, pygismo, taichi, warp" 2>/dev/null || {
  echo "run_all.sh: $PYTHON lacks a peer (numpy scipy splipy pygismo taichi warp-lang); see the header" >&2
  exit 2
}
load() { cut -d' ' -f1 /proc/loadavg; }
stamp() { date -u +%H:%M:%S; }
section() {  # name, command...
  local name=$1
  shift
  case " $SECTIONS " in *" $name "*) ;; *) return 0 ;; esac
  export NURBSPRING_BENCH_RESULTS=$RESULTS/results-$name.jsonl
  : >"$NURBSPRING_BENCH_RESULTS"
  sed -i "/^$name\t/d" "$RESULTS/sections.tsv"
  local start l0
  start=$(stamp)
  l0=$(load)
  echo "==== $name ($start UTC, load $l0)"
  "$@"
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$start" "$(stamp)" "$l0" "$(load)" "$(date -u +%F)" >>"$RESULTS/sections.tsv"
}
run_start=$(stamp)
load_start=$(load)

echo "==== build (not timed)"
# Each package alone, as the sections invoke it: cargo unifies features over the packages of
# one invocation, so a joint build would not be the one the sections reuse.
cargo build --release --locked -p nurbspring
for bench in geom:evaluate dnurbs:assembly scene:derive msm:step; do
  cargo bench --locked --no-run -p "nurbspring-${bench%%:*}" --bench "${bench#*:}"
done
cargo bench --manifest-path bench-peers/Cargo.toml --locked --no-run
cargo build --release --manifest-path bench-peers/Cargo.toml --locked --examples
# Let the build's load settle (the one-minute load average, up to two minutes).
for _ in $(seq 24); do
  awk '{ exit !($1 < 0.5) }' /proc/loadavg && break
  sleep 5
done

section geometry bench-peers/run_geometry.sh
section assembly bench-peers/run_assembly.sh
section derive-modal cargo bench --locked -p nurbspring-scene --bench derive
section derive-paper env BIN="$CARGO_TARGET_DIR/release/nurbspring" scripts/bench-derive/run.sh
msm() {
  bench-peers/run_msm.sh
  echo "== SciPy backward Euler (bench-peers/msm_step_scipy_be.py)"
  (cd bench-peers && "$PYTHON" msm_step_scipy_be.py "$DUMP")
}
section msm msm

peers=$("$PYTHON" - <<'PY'
import importlib.metadata as md
print(", ".join(f"{p} {md.version(p)}" for p in ("splipy", "pygismo", "numpy", "scipy", "taichi", "warp-lang")))
PY
)
curvo=$(grep -A1 '^name = "curvo"$' bench-peers/Cargo.lock | sed -n 's/version = "\(.*\)"/\1/p')
RUN_START=$run_start RUN_END=$(stamp) LOAD_START=$load_start LOAD_END=$(load) \
PEERS="curvo $curvo, $peers, Python $("$PYTHON" -c 'import platform; print(platform.python_version())')" \
RUSTC="$(rustc --version)" python3 - "$RESULTS" <<'PY'
import json, os, platform, subprocess, sys, time
d = sys.argv[1]
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "unknown CPU")
mem = next(int(l.split()[1]) for l in open("/proc/meminfo") if l.startswith("MemTotal"))
sections = {}
for line in open(os.path.join(d, "sections.tsv")):
    # name, start, end, loads and (since 2026-12-04) the UTC date the section ended
    name, start, end, l0, l1, *day = line.rstrip("\n").split("\t")
    sections[name] = {"start": start, "end": end, "load_start": float(l0), "load_end": float(l1),
                      "date": day[0] if day else None}
info = {"date": time.strftime("%Y-%m-%d", time.gmtime()), "start": os.environ["RUN_START"],
        "end": os.environ["RUN_END"], "load_start": float(os.environ["LOAD_START"]),
        "load_end": float(os.environ["LOAD_END"]), "cpu": f'"{cpu}"', "cpus": os.cpu_count(),
        "memory": f"{mem / 2**20:.0f} GiB", "kernel": f"Linux {platform.release()}",
        "rustc": os.environ["RUSTC"], "peers": os.environ["PEERS"], "sections": sections}
json.dump(info, open(os.path.join(d, "run.json"), "w"), indent=1)
PY
if [ -z "${NO_TABLES:-}" ]; then
  python3 bench-peers/tables.py "$RESULTS" "$CRITERION_HOME"
fi
echo "==== done: $RESULTS"
