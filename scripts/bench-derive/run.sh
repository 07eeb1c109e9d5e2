#!/usr/bin/env bash
# Times `nurbspring paper`, `nurbspring derive SCENE --derivation paper` on refined nets and
# the default derivation on the same sheets (docs/benchmarks.md, "Derivation: the paper's
# derivation on refined nets"): BIN (default the
# release build) and, when BASE names another binary, that one in turn with it, each job RUNS
# times (default 3). With NURBSPRING_BENCH_RESULTS set, every run is also appended to that file
# as a JSON line (bench-peers/results.py's format) for bench-peers/tables.py.
#   cargo build --release -p nurbspring && scripts/bench-derive/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${BIN:-target/release/nurbspring}
BASE=${BASE:-}
RUNS=${RUNS:-3}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "== machine"; lscpu | grep -E "Model name|^CPU\(s\)"; uptime
# One timed run: label, binary, then the command's arguments. Prints the time line and records it.
timed() {
  local label=$1 bin=$2
  shift 2
  # A job that fails is timed and recorded as failed (with its error), not dropped.
  local failed=false
  /usr/bin/time -f "%e %U %M" -o "$dir/t" "$bin" "$@" >/dev/null 2>"$dir/err" || failed=true
  read -r wall user kb < <(tail -1 "$dir/t")
  if $failed; then
    echo "$label: $bin FAILED after $wall s: $(grep -m1 '^error' "$dir/err" || tail -1 "$dir/err")"
  else
    echo "$label: $bin $wall s wall, $user s user, $kb KB"
  fi
  if [ -n "${NURBSPRING_BENCH_RESULTS:-}" ]; then
    local load error; load=$(cut -d' ' -f1 /proc/loadavg)
    error=$(grep -m1 '^error' "$dir/err" | cut -c1-160 | sed 's/\\/\\\\/g; s/"/\\"/g' || true)
    printf '{"source": "%s", "bench": "%s", "times_s": [%s], "min_s": %s, "median_s": %s, "load": %s, "info": {"user_s": %s, "max_rss_kb": %s, "failed": %s, "error": "%s"}}\n' \
      "$bin" "$label" "$wall" "$wall" "$wall" "$load" "$user" "$kb" "$failed" "$error" >>"$NURBSPRING_BENCH_RESULTS"
  fi
}
for run in $(seq "$RUNS"); do
  for bin in $BIN $BASE; do
    timed "paper" "$bin" paper --out "$dir/paper" -q
  done
done
for size in "7 9 0" "9 17 0" "17 33 0" "17 33 12" "33 65 12"; do
  set -- $size
  scene="$dir/paper_$1_$2_c$3.toml"
  python3 scripts/bench-derive/paper_sheet.py "$1" "$2" "$scene" "$3"
  for run in $(seq "$RUNS"); do
    for bin in $BIN $BASE; do
      timed "derive_paper_$1_$2_c$3" "$bin" derive "$scene" --derivation paper --out "$dir/out" -q
    done
  done
done
# The default derivation on the same sheets (lattice as fine as the net): every mode of both
# models (dense, O(n³)) up to 2,000 free unknowns (the 9² – 33² nets), their lowest 200 (sparse
# shift-invert Lanczos, O(n) for a fixed count) above (65² – 129²).
for n in 9 17 33 65 97 129; do
  scene="$dir/default_$n.toml"
  python3 scripts/bench-derive/paper_sheet.py "$n" "$n" "$scene"
  for run in $(seq "$RUNS"); do
    for bin in $BIN $BASE; do
      timed "derive_default_$n" "$bin" derive "$scene" --out "$dir/out" -q
    done
  done
done
uptime
