#!/usr/bin/env bash
# The Kirchhoff–Love shell's nonlinear static solves beside Kratos Multiphysics' IGA
# Shell3pElement on the same nets and loads, one after the other in one run (docs/benchmarks.md,
# "Shell: nonlinear static solves"). Both sides print the best of 3 in-process wall times of the
# solve alone (all load steps). Threads: THREADS (default 1) for both.
#
#   PYTHON=/path/to/venv/bin/python bench-peers/run_shell.sh [OUT_DIR]
#
# The Python needs KratosMultiphysics, KratosIgaApplication and
# KratosStructuralMechanicsApplication 10.4.4 (pip install; see bench-peers/kratos/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-/tmp/bench-shell}"
mkdir -p "$out"
threads="${THREADS:-1}"
python="${PYTHON:-python3}"
cargo build --release -p nurbspring-dnurbs --example shell_solve --quiet
ours=target/release/examples/shell_solve
{
  echo "date: $(date -u +%FT%TZ)"
  echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
  echo "load: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "threads: $threads"
} > "$out/context.txt"
for problem in cantilever scordelis hemisphere; do
  # Kratos takes minutes on the hemisphere: one run of it, the best of 3 elsewhere.
  repeats=3
  [ "$problem" = hemisphere ] && repeats=1
  RAYON_NUM_THREADS=$threads "$ours" "$problem" 16 $repeats > "$out/nurbspring_$problem.json"
  OMP_NUM_THREADS=$threads "$python" bench-peers/kratos/kratos_shell.py --problem "$problem" \
    --spans 16 --hemisphere-spans 16 --repeats $repeats --threads "$threads" \
    --json "$out/kratos_$problem.json" > "$out/kratos_$problem.log" 2>&1
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out/context.txt"
"$python" - "$out" <<'PY'
import json, sys, pathlib
out = pathlib.Path(sys.argv[1])
print(open(out / "context.txt").read().strip())
print("| problem | dofs | nurbspring solve [s] | Kratos solve [s] | Kratos / nurbspring | Newton iterations (ours / Kratos) | displacement at full load (ours / Kratos) |")
print("|---|---|---|---|---|---|---|")
runs = {"cantilever": ("cantilever", "line_load_condition"),
        "scordelis": ("scordelis", "nonlinear_dead_load"),
        "hemisphere": ("hemisphere_16", "nonlinear")}
for problem, (key, part) in runs.items():
    ours = json.loads((out / f"nurbspring_{problem}.json").read_text())
    k = json.load(open(out / f"kratos_{problem}.json"))[key][part]
    solve = k["timing"]["solve_wall_s_best"]
    iters = k["result"].get("total_iterations")
    print(f"| {problem} | {ours['dofs']} | {ours['solve_s']:.3f} | {solve:.3f} | "
          f"{solve / ours['solve_s']:.1f}× | {ours['iterations']} / {iters} | {ours['levels'][-1][1]:.6f} |")
PY
