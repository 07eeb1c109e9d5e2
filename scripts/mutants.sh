#!/usr/bin/env bash
# Mutation testing of the numeric core with a time budget (not run by CI; see docs/testing.md).
#
#   scripts/mutants.sh                 every package, the whole budget split between them
#   scripts/mutants.sh geom dnurbs     only these packages
#   BUDGET=7200 JOBS=2 scripts/mutants.sh
#   SHARD=3/10 scripts/mutants.sh sim  one tenth of a package's mutants, every file sampled
#                                      (round-robin; for a nightly rotation)
#   RETEST=mutants.out/sim/mutants.out/missed.txt scripts/mutants.sh sim
#                                      only the mutants of a missed list (after new tests)
#
# Configuration: .cargo/mutants.toml. Output: mutants.out/<package>/ (outcomes.json,
# caught.txt, missed.txt, timeout.txt, unviable.txt). Requires `cargo install cargo-mutants`.
set -euo pipefail
cd "$(dirname "$0")/.."

BUDGET=${BUDGET:-14400}          # seconds for the whole run
JOBS=${JOBS:-1}                  # parallel mutants (each builds its own copy of the tree)
SHARD=${SHARD:-}
RETEST=${RETEST:-}
packages=("$@")
if [ ${#packages[@]} -eq 0 ]; then
    packages=(geom dnurbs msm sim derive io)
fi
per_package=$(( BUDGET / ${#packages[@]} ))
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-target/mutants}

status=0
for p in "${packages[@]}"; do
    out="mutants.out/$p${RETEST:+-retest}"
    mkdir -p mutants.out
    args=(--package "nurbspring-$p" --jobs "$JOBS" --output "$out" --no-shuffle)
    if [ "$p" = io ]; then
        args+=(--file crates/io/src/atomic.rs)
    fi
    if [ -n "$SHARD" ]; then
        args+=(--shard "$SHARD" --sharding round-robin)
    fi
    if [ -n "$RETEST" ]; then
        # One anchored regex of the listed names (cargo-mutants' --re matches `--list` names).
        regex=$(python3 -c 'import re, sys; print("^(" + "|".join(re.escape(l.strip()) for l in open(sys.argv[1]) if l.strip()) + ")$")' "$RETEST")
        args+=(--re "$regex")
    fi
    echo "== nurbspring-$p (budget ${per_package}s)"
    # timeout ends the run at the budget; what finished is kept in mutants.out/$p.
    set +e
    timeout --signal=INT "$per_package" nice -n 10 cargo mutants "${args[@]}"
    rc=$?
    set -e
    case $rc in
        0) ;;                       # every mutant caught
        2) status=2 ;;              # some mutants missed: see $out/mutants.out/missed.txt
        124|130) echo "   budget reached; partial results in $out" ;;
        *) echo "   cargo mutants exited with $rc"; status=$rc ;;
    esac
    if [ -f "$out/mutants.out/outcomes.json" ] || [ -f "$out/outcomes.json" ]; then
        for f in caught missed timeout unviable; do
            file=$(ls "$out"/{,mutants.out/}$f.txt 2>/dev/null | head -1 || true)
            [ -n "$file" ] && printf '   %-8s %s\n' "$f" "$(wc -l < "$file")"
        done
    fi
done
exit $status
