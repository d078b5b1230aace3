#!/usr/bin/env bash
# Deep fuzz runs (issue 22): every fuzz contract at EXAMPLES Hypothesis examples (default 2000),
# each from a clean Hypothesis database, one line per contract:
#
#   mesh: 2000 examples, 843 s, passed
#
# and a non-zero exit when any contract fails (its log is named on its line). Not for CI: CI runs
# the same tests at their small default counts.
#
# Usage: bash scripts/fuzz_deep.sh [EXAMPLES]
#   FUZZ_SEED=N    pass --hypothesis-seed=N to every contract (default: Hypothesis picks)
#   FUZZ_ONLY=a,b  run only these contracts (names as below)
#   FUZZ_LOGS=DIR  keep the pytest logs there (default: a new temporary directory)
#
# A contract is picked up by its file name, nothing to register: tests/core/test_fuzz.py is
# "mesh"; every other tests/*/test_fuzz_NAME.py is "NAME" (test_fuzz_cli.py: "cli"). Its tests
# must take their example count from the environment variable BD_UV_FUZZ_EXAMPLES.
set -uo pipefail

EXAMPLES="${1:-2000}"
case "$EXAMPLES" in ''|*[!0-9]*) echo "usage: bash scripts/fuzz_deep.sh [EXAMPLES]" >&2; exit 2;; esac
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PY="${PYTHON:-python3.11}"
LOGS="${FUZZ_LOGS:-$(mktemp -d "${TMPDIR:-/tmp}/bd-uv-fuzz.XXXXXX")}"
mkdir -p "$LOGS"
SEED_OPT=()
[ -n "${FUZZ_SEED:-}" ] && SEED_OPT=("--hypothesis-seed=$FUZZ_SEED")

contracts=()
[ -f "$ROOT/tests/core/test_fuzz.py" ] && contracts+=("mesh=tests/core/test_fuzz.py")
for f in "$ROOT"/tests/*/test_fuzz_*.py; do
    [ -e "$f" ] || continue
    name="$(basename "$f" .py)"
    contracts+=("${name#test_fuzz_}=${f#"$ROOT"/}")
done

failed=0
for entry in "${contracts[@]}"; do
    name="${entry%%=*}"
    target="${entry#*=}"
    if [ -n "${FUZZ_ONLY:-}" ] && [[ ",$FUZZ_ONLY," != *",$name,"* ]]; then
        continue
    fi
    log="$LOGS/$name.log"
    work="$(mktemp -d "${TMPDIR:-/tmp}/bd-uv-fuzz-$name.XXXXXX")"   # a clean .hypothesis/
    start=$(date +%s)
    (cd "$work" && PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}" BD_UV_FUZZ_EXAMPLES="$EXAMPLES" \
        "$PY" -m pytest -q -x -p no:cacheprovider --hypothesis-show-statistics "${SEED_OPT[@]}" \
        "$ROOT/$target") >"$log" 2>&1
    rc=$?
    secs=$(( $(date +%s) - start ))
    rm -rf "$work"
    # Hypothesis statistics: "- N passing examples, M failing examples, ..." per test and phase.
    ran=$(grep -oE '[0-9]+ passing examples, [0-9]+ failing' "$log" \
          | awk '{s += $1 + $4} END {print s + 0}')
    if [ "$rc" -eq 0 ]; then
        outcome="passed"
    else
        outcome="FAILED (exit $rc, log $log)"
        failed=1
    fi
    echo "$name: $ran examples, $secs s, $outcome"
done
[ "${#contracts[@]}" -gt 0 ] || { echo "no fuzz contracts found under $ROOT/tests" >&2; exit 2; }
exit "$failed"
