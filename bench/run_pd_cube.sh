#!/usr/bin/env bash
# Build cupid (Release) and run the PD cube benchmark: bench/run_pd_cube.sh [n ...] [--bond] [--exact]
# Threads: OMP_NUM_THREADS (default: all cores). Output: a markdown table on stdout.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${CUPID_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_pd_cube >/dev/null
export OPENBLAS_NUM_THREADS=1
exec "$build/bench/bench_pd_cube" "$@"
