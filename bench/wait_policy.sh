#!/usr/bin/env bash
# OpenMP's wait policy on a busy machine (issue 33, item 14): the notched Arlequin bar
# (examples/notched_bar, explicit dynamics, shortened to 1e-5 s) on every core while as many
# busy loops as cores run beside it, with the tool's default (PASSIVE since issue 33, set by
# src/app/main.c), OMP_WAIT_POLICY=ACTIVE (libgomp's spinning), GOMP_SPINCOUNT=10000, and one
# thread; then the same without the busy loops. Wall seconds, best of 3 each.
#   bench/wait_policy.sh [build/cupid]
set -eu
CUPID=$(realpath "${1:-build/cupid}")
SRC=$(cd "$(dirname "$0")/.." && pwd)
M=$SRC/examples/notched_bar/notched_bar_arlequin.yaml
work=$(mktemp -d)
busy=()
cleanup() { for p in "${busy[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$work"; }
trap cleanup EXIT
cores=$(nproc)
best() { # best of 3 wall seconds of: env ASSIGNMENTS... -- threads
  local b=1e9 t
  for _ in 1 2 3; do
    /usr/bin/time -f %e -o "$work/t" env "$@" "$CUPID" run "$M" -o "$work/o" --quiet \
      --set analysis.dynamic.duration=1e-5 --set output.vtu=false --set output.plots=false \
      >/dev/null 2>&1
    t=$(tail -1 "$work/t")
    b=$(python3 -c "print(min($b, $t))")
  done
  echo "$b"
}
row() { # label
  printf '| %s | %s | %s | %s | %s |\n' "$1" \
    "$(best -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT OMP_NUM_THREADS=$cores)" \
    "$(best -u GOMP_SPINCOUNT OMP_WAIT_POLICY=ACTIVE OMP_NUM_THREADS=$cores)" \
    "$(best -u OMP_WAIT_POLICY GOMP_SPINCOUNT=10000 OMP_NUM_THREADS=$cores)" \
    "$(best -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT OMP_NUM_THREADS=1)"
}
echo "| machine | default (PASSIVE), $cores threads | ACTIVE | GOMP_SPINCOUNT=10000 | 1 thread |"
echo "|---|---|---|---|---|"
row "idle"
for _ in $(seq 1 "$cores"); do (while :; do :; done) & busy+=($!); done
row "$cores busy loops beside"
