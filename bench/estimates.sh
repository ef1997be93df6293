#!/usr/bin/env bash
# How good are the estimates `solver: auto` chooses by (issue 20)? Runs every static example
# with solver auto (or the engine given as $SOLVER) and prints, per model, the chosen engine
# and path, the estimated and the measured seconds (factorisation + solve phases) and peak
# memory, and their ratios. A reported figure, not a test: the estimates are calibrated to be
# right within a factor of a few (src/problem/estimate.c, method_*.c), which is what a choice
# between paths 2-10x apart needs.
#   bench/estimates.sh [EXAMPLE_DIR...]      (default: examples/bar examples/cbeam examples/panel)
#   SOLVER=krylov bench/estimates.sh examples/bar
# Models over MAX_GB (default 8) of estimated memory are skipped with a line saying so.
set -euo pipefail
cd "$(dirname "$0")/.."
CUPID=${CUPID:-build/cupid}
MAX_GB=${MAX_GB:-8}
dirs=("$@")
[ ${#dirs[@]} -eq 0 ] && dirs=(examples/bar examples/cbeam examples/panel)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '| model | engine | path | est. s | meas. s | meas./est. | est. GB | peak GB | peak/est. |\n'
printf '|---|---|---|---:|---:|---:|---:|---:|---:|\n'
for d in "${dirs[@]}"; do
  for m in "$d"/*.yaml; do
    grep -Eq "^  type: (dynamic|evaluate)" "$m" && continue  # static analyses only
    sed "s/^  solver: [a-z]*/  solver: ${SOLVER:-auto}/" "$m" > "$tmp/model.yaml"
    est=$("$CUPID" check "$tmp/model.yaml" 2>/dev/null | sed -n 's/.*estimated peak memory, direct path: \([0-9.e+]*\) GB.*/\1/p')
    if [ -n "$est" ] && /usr/bin/python3 -c "import sys; sys.exit(float(sys.argv[1]) <= float(sys.argv[2]))" "$est" "$MAX_GB" \
       && [ "${SOLVER:-auto}" = direct ]; then
      echo "| $m | skipped: the direct path needs ~$est GB (MAX_GB=$MAX_GB) |"; continue
    fi
    if ! "$CUPID" run "$tmp/model.yaml" -o "$tmp/out" --quiet --max-memory "$MAX_GB" 2>"$tmp/err"; then
      echo "| $m | skipped: $(head -c 160 "$tmp/err" | tr '\n' ' ') |"; continue
    fi
    /usr/bin/python3 - "$tmp/out/summary.json" "$m" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); v = s["solver"]; e = v.get("estimate", {})
t = s["phases"]["factorisation"]["time_s"] + s["phases"]["solve"]["time_s"]
peak = s["peak_memory_bytes"] / 1e9
es, eb = e.get("seconds", 0.0), e.get("bytes", 0.0) / 1e9
r = lambda a, b: "%.2f" % (a / b) if b > 0 else "-"
print("| %s | %s | %s | %.3g | %.3g | %s | %.3g | %.3g | %s |" % (
    sys.argv[2], v.get("engine", v["method"]), e.get("path", "-"), es, t, r(t, es), eb, peak, r(peak, eb)))
PY
  done
done
