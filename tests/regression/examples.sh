#!/usr/bin/env bash
# Every example with stored results (tests/regression/expected/*.json) is run and compared:
# point values to the stored tolerance (1e-8 relative: a direct solve is deterministic up to
# round-off from the thread count, ~1e-13; anything larger is a change of behaviour), exact
# counts, solver residual <= 1e-10 and equilibrium to 1e-9 of the applied load.
# To accept new results after an intended change: run with UPDATE=1 and review the diff.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
pass=0; fail=0
for expected in "$SRC"/tests/regression/expected/*.json; do
  name=$(basename "$expected" .json)
  model=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["example"])' "$expected")
  if ! "$CUPID" run "$SRC/$model" -o "$work/$name" --quiet; then
    echo "FAIL: $name: cupid run failed"; fail=$((fail+1)); continue
  fi
  if python3 "$SRC/tests/regression/compare_summary.py" "$expected" "$work/$name/summary.json" ${UPDATE:+--update}; then
    pass=$((pass+1))
  else
    fail=$((fail+1))
  fi
done
echo "regression: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
