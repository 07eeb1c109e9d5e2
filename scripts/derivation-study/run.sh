#!/usr/bin/env bash
# Measures a derivation on the random scenes and on the test scenes:
#   scripts/derivation-study/run.sh [DERIVATION] [SEED]
# Prints, per scene, the central node's 3-D relative RMS against the exact D-NURBS motion and the
# same under the second excitation, then the median, mean and worst of each.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
method=${1:-modal}
seed=${2:-20261201}
cargo build --release --quiet --manifest-path "$root/Cargo.toml" -p nurbspring
bin="$root/target/release/nurbspring"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 "$here/random_scenes.py" "$work/scenes" "$seed" >/dev/null
scenes=("$work"/scenes/*.toml "$root"/examples/paper.toml "$root"/examples/string.toml "$root"/crates/scene/tests/data/derivations/*.toml)
for s in "${scenes[@]}"; do
  n=$(basename "$s" .toml)
  if ! "$bin" --quiet derive "$s" --derivation "$method" --out "$work/out-$n" 2>"$work/err-$n"; then
    echo "$n: refused: $(head -c 300 "$work/err-$n")"
  fi
done
python3 - "$work" <<'PY'
import glob, json, os, statistics as st, sys
rows = {}
for f in sorted(glob.glob(os.path.join(sys.argv[1], "out-*", "report.json"))):
    r = json.load(open(f))
    v = r["validation"]["relative_rms"]
    rows[f.split("out-")[1].split("/")[0]] = (float("inf") if v is None else v, r["second_excitation"]["relative_rms"])
for name, (a, b) in rows.items():
    print(f"{name:10s} {100 * a:7.2f} % {100 * b:7.2f} %")
for label, pick in (("random", lambda n: n.startswith("r") and n[1:].isdigit()), ("named", lambda n: not (n.startswith("r") and n[1:].isdigit()))):
    sel = [v for n, v in rows.items() if pick(n)]
    if sel:
        a, b = [x[0] for x in sel], [x[1] for x in sel]
        print(f"{label}: own excitation median {100*st.median(a):.2f} % mean {100*st.mean(a):.2f} % worst {100*max(a):.2f} %; "
              f"second excitation median {100*st.median(b):.2f} % mean {100*st.mean(b):.2f} % worst {100*max(b):.2f} %")
PY
