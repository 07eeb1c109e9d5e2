#!/usr/bin/env bash
# Mutation testing of the numeric core with a time budget (not run by CI; see docs/testing.md).
#
#   scripts/mutants.sh                 every package, the whole budget split between them
#   scripts/mutants.sh geom dnurbs     only these packages
#   BUDGET=7200 JOBS=2 scripts/mutants.sh
#   SHARD=3/8 scripts/mutants.sh sim   one shard of the mutants of a package (for nightly rotation)
#
# Configuration: .cargo/mutants.toml. Output: mutants.out/<package>/ (outcomes.json,
# caught.txt, missed.txt, timeout.txt, unviable.txt). Requires `cargo install cargo-mutants`.
set -euo pipefail
cd "$(dirname "$0")/.."

BUDGET=${BUDGET:-14400}          # seconds for the whole run
JOBS=${JOBS:-1}                  # parallel mutants (each builds its own copy of the tree)
SHARD=${SHARD:-}
packages=("$@")
if [ ${#packages[@]} -eq 0 ]; then
    packages=(geom dnurbs msm sim derive io)
fi
per_package=$(( BUDGET / ${#packages[@]} ))
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-target/mutants}

status=0
for p in "${packages[@]}"; do
    args=(--package "nurbspring-$p" --jobs "$JOBS" --output "mutants.out/$p" --no-shuffle)
    if [ "$p" = io ]; then
        args+=(--file crates/io/src/atomic.rs)
    fi
    if [ -n "$SHARD" ]; then
        args+=(--shard "$SHARD")
    fi
    echo "== nurbspring-$p (budget ${per_package}s)"
    # timeout ends the run at the budget; what finished is kept in mutants.out/$p.
    set +e
    timeout --signal=INT "$per_package" nice -n 10 cargo mutants "${args[@]}"
    rc=$?
    set -e
    case $rc in
        0) ;;                       # every mutant caught
        2) status=2 ;;              # some mutants missed: see mutants.out/$p/missed.txt
        124|130) echo "   budget reached; partial results in mutants.out/$p" ;;
        *) echo "   cargo mutants exited with $rc"; status=$rc ;;
    esac
    if [ -f "mutants.out/$p/mutants.out/outcomes.json" ] || [ -f "mutants.out/$p/outcomes.json" ]; then
        for f in caught missed timeout unviable; do
            file=$(ls "mutants.out/$p"/{,mutants.out/}$f.txt 2>/dev/null | head -1 || true)
            [ -n "$file" ] && printf '   %-8s %s\n' "$f" "$(wc -l < "$file")"
        done
    fi
done
exit $status
