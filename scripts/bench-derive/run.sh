#!/usr/bin/env bash
# Times `nurbspring derive SCENE --derivation paper` on refined nets (docs/benchmarks.md,
# "Derivation: the paper's derivation on refined nets"): BIN (default the release build) and,
# when BASE names another binary, that one in turn with it, each scene three times.
#   cargo build --release -p nurbspring && scripts/bench-derive/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${BIN:-target/release/nurbspring}
BASE=${BASE:-}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
echo "== machine"; lscpu | grep -E "Model name|^CPU\(s\)"; uptime
for size in "7 9 0" "9 17 0" "17 33 0" "17 33 12" "33 65 12"; do
  set -- $size
  scene="$dir/paper_$1_$2_c$3.toml"
  python3 scripts/bench-derive/paper_sheet.py "$1" "$2" "$scene" "$3"
  for run in 1 2 3; do
    for bin in $BIN $BASE; do
      /usr/bin/time -f "$1² cps / $2² lattice, candidates ${3/#0/all}: $bin %e s wall, %U s user, %M KB" \
        "$bin" derive "$scene" --derivation paper --out "$dir/out" -q >/dev/null 2>>"$dir/times" || true
      tail -1 "$dir/times"
    done
  done
done
uptime
