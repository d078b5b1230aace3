#!/usr/bin/env bash
# Deep fuzz runs (issue 22): every fuzz contract at EXAMPLES Hypothesis examples (default 2000),
# each from a clean Hypothesis database, one line per contract:
#
#   mesh: 2000 examples, seed 1804289383, 843 s (load 2.10), passed
#
# and a non-zero exit when any contract fails (its log is named on its line). Not for CI: CI runs
# the same tests at their small default counts. Every run has a seed, printed on each line: the
# one given, else one drawn at random here, so a run someone else started (a failure above all)
# is repeated exactly by passing that seed back.
#
# Usage: bash scripts/fuzz_deep.sh [EXAMPLES [SEED]]
#   SEED           --hypothesis-seed for every contract (or FUZZ_SEED=N; default: a random one)
#   FUZZ_ONLY=a,b  run only these contracts (names as below)
#   FUZZ_LOGS=DIR  keep the pytest logs there (default: a new temporary directory)
#
# A contract is picked up by its file name, nothing to register: tests/core/test_fuzz.py is
# "mesh"; every other tests/*/test_fuzz_NAME.py is "NAME" (test_fuzz_cli.py: "cli"). Its tests
# must take their example count from the environment variable BD_UV_FUZZ_EXAMPLES.
set -uo pipefail

EXAMPLES="${1:-2000}"
SEED="${2:-${FUZZ_SEED:-}}"
[ -n "$SEED" ] || SEED=$(( $(od -An -N4 -tu4 /dev/urandom) % 2147483648 ))
for n in "$EXAMPLES" "$SEED"; do
    case "$n" in ''|*[!0-9]*)
        echo "usage: bash scripts/fuzz_deep.sh [EXAMPLES [SEED]] (whole numbers)" >&2; exit 2;;
    esac
done
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PY="${PYTHON:-python3.11}"
LOGS="${FUZZ_LOGS:-$(mktemp -d "${TMPDIR:-/tmp}/bd-uv-fuzz.XXXXXX")}"
mkdir -p "$LOGS"

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
        "$PY" -m pytest -q -x -p no:cacheprovider --hypothesis-show-statistics \
        "--hypothesis-seed=$SEED" \
        "$ROOT/$target") >"$log" 2>&1
    rc=$?
    secs=$(( $(date +%s) - start ))
    rm -rf "$work"
    # Hypothesis statistics, per test and phase: "- N passing examples, M failing examples, ..."
    # (Hypothesis 6.155) or "- N passing, M failing, and K invalid test cases" (6.170).
    ran=$(grep -oE '[0-9]+ passing( examples)?, [0-9]+ failing' "$log" | grep -oE '[0-9]+' \
          | awk '{s += $1} END {print s + 0}')
    if [ "$rc" -eq 0 ]; then
        outcome="passed"
    else
        outcome="FAILED (exit $rc, log $log)"
        failed=1
    fi
    load=$(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo "?")   # times mean little without it
    echo "$name: $ran examples, seed $SEED, $secs s (load $load), $outcome"
done
[ "${#contracts[@]}" -gt 0 ] || { echo "no fuzz contracts found under $ROOT/tests" >&2; exit 2; }
exit "$failed"
