#!/usr/bin/env bash
# CUF beam benchmark: builds cupid (Release), runs bench_cuf on the C-section beam of
# shared/reference/examples.md section 2 with 1 and 2 threads, and the beam-element
# convergence / locking study of tests/verification/test_cuf_cantilever.c, and prints a
# markdown report (redirect it into bench/README_cuf.md to refresh the stored figures).
#
# usage: bench/run_cuf.sh [max_L9_level (default 3)] > bench/README_cuf.md.new
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${CUPID_BUILD_DIR:-$root/build}"
level="${1:-3}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_cuf verification_cuf_cantilever >/dev/null

echo "## Machine"
echo
echo "- $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
echo "- load average before the run: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "- $(date -u +%Y-%m-%d) , commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo
for threads in 1 2; do
  echo "## C-section beam, OMP_NUM_THREADS=$threads"
  echo
  OMP_NUM_THREADS=$threads OPENBLAS_NUM_THREADS=1 "$build/bench/bench_cuf" "$level" 0 | tail -n +3
  echo
done
echo "## Integration: convergence in beam elements (TE2 cantilever, tip traction)"
echo
echo '```'
OMP_NUM_THREADS=2 "$build/tests/verification_cuf_cantilever" 2>&1 | sed -n '/TE2 cantilever/,/rates:/p'
echo '```'
