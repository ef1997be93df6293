#!/usr/bin/env bash
# The cost of checkpoints (issue 36): an explicit fracture run of the notched plate
# (examples/notched_plate) widened to N x N x 3 nodes, without checkpoints and with one at every
# output step (output.checkpoint tiny: the worst case), best of 3 wall seconds each. Prints the
# checkpoint's size, the seconds one costs, and what that is at the default period (600 s).
#   bench/checkpoint.sh [build/cupid] [N (default 200)]
set -eu
CUPID=$(realpath "${1:-build/cupid}")
N=${2:-200}
SRC=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
# the plate N mm wide (1 mm spacing), the notch and grips as in the example; 400 steps
S=(--set "peridynamics.regions=[{x: [0, $N], y: [0, $N], z: [0, 3]}]"
   --set "peridynamics.precracks=[{normal: y, at: $((N / 2)), x: [0, $((N / 4))], z: [0, 3]}]"
   --set "constraints[0].displacement.box={x: [0, $N], y: [$((N - 3)), $N], z: [0, 3]}"
   --set "constraints[1].displacement.box={x: [0, $N], y: [0, 3], z: [0, 3]}"
   --set analysis.dynamic.duration=2e-5 --set output.plots=false --set output.vtu=false)
best() { # best of 3 wall seconds with output.checkpoint=$1; the progress log of the last
  local b=1e9 t
  for _ in 1 2 3; do
    rm -rf o .o.cupid-*
    /usr/bin/time -f %e -o t "$CUPID" run "$SRC/examples/notched_plate/notched_plate.yaml" -o o \
      "${S[@]}" --set output.checkpoint="$1" 2>log >/dev/null
    b=$(python3 -c "print(min($b, $(tail -1 t)))")
  done
  echo "$b"
}
off=$(best 0)
on=$(best 1e-9)
count=$(sed -n 's/.*checkpoints: \([0-9]*\) written.*/\1/p' log)
inside=$(sed -n 's/.*written, \([0-9.e+-]*\) s in all.*/\1/p' log)
rm -rf o .o.cupid-*
"$CUPID" run "$SRC/examples/notched_plate/notched_plate.yaml" -o o "${S[@]}" \
  --set output.checkpoint=1e-9 >/dev/null 2>&1 &
pid=$!
sleep 2; kill -TERM $pid; wait $pid || true
size=$(stat -c %s .o.cupid-partial/.checkpoint 2>/dev/null || echo 0)
python3 - "$N" "$off" "$on" "$count" "$inside" "$size" <<'PY'
import sys
n, off, on, count, inside, size = sys.argv[1:]
off, on, count, inside, size = float(off), float(on), int(count), float(inside), int(size)
per = (on - off) / count
print(f"| plate {n} x {n} x 3 ({3 * int(n) ** 2} nodes) | run without checkpoints {off:.2f} s | "
      f"with {count} (one per output step) {on:.2f} s | {per * 1e3:.1f} ms each by the wall "
      f"({inside / count * 1e3:.1f} ms writing it, by the run), {size / 1e6:.1f} MB | "
      f"{100 * per / 600:.4f}% at the default period of 600 s |")
PY
