#!/usr/bin/env bash
# Determinism (docs/hardening.md): the same model run with 1, 2 and 4 threads gives the same
# results to 1e-10 relative, and two runs with the same thread count give bitwise identical
# files (apart from the timings and memory figures of summary.json).
#
# The models have more than 1024 PD nodes so that the OpenMP loops of src/pd really run in
# parallel (below that they run on one thread), two materials, expression loads, a static solve
# (assembly, CHOLMOD, stress) and an `evaluate` run (matrix-free operator).
# Tolerance: 1e-10 relative to the largest value of the same kind (displacement, force, stress)
# in the file, so that entries that are zero up to round-off need no tolerance of their own.
# Summing in another order changes results by ~1e-16 of that scale; 1e-10 leaves room for the
# accumulation over ~10^5 bonds but catches any race or thread-dependent algorithm.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0; fail=0
export OPENBLAS_NUM_THREADS=1

cat > static.yaml <<'EOF'
title: determinism, static LPS
materials:
  m: {E: 1000, nu: 0.25, density: 2}
  soft: {E: 300, nu: 0.3, density: 1}
peridynamics:
  spacing: 1.0
  horizon: 2.0
  model: lps
  influence: gaussian
  partial_volume: exact
  regions:
    - {x: [0, 8], y: [-2, 16], z: [0, 8], material: m}
    - {x: [0, 8], y: [16, 22], z: [0, 8], material: soft}
constraints:
  - fix: {box: {y: [-2, 0]}}
loads:
  - traction: {y: 22, value: [1, 10, "0.5*x"]}
  - body: {value: [0, 0, "-0.01*density"]}
output:
  vtu: true
  pd_nodes: true
  plots: false
  lines:
    - {name: axis, from: [4, 0, 4], to: [4, 22, 4], points: 23}
  points:
    - {name: tip, at: [4, 22, 4], stress: true}
    - {name: mid, at: [2.5, 10, 6.5], stress: true}
EOF
cat > evaluate.yaml <<'EOF'
title: determinism, evaluate bond-based
materials:
  m: {E: 1000, nu: 0.25}
peridynamics:
  spacing: 0.5
  horizon: 1.5
  model: bond
  influence: inverse
  partial_volume: pdlammps
  material: m
  regions:
    - {x: [0, 6], y: [0, 6], z: [0, 6]}
analysis:
  type: evaluate
  field: ["1e-3*x*y", "1e-3*sin(z)", "1e-4*x*x"]
output:
  vtu: true
  pd_nodes: true
  plots: false
  points:
    - {name: centre, at: [3, 3, 3], stress: true}
EOF

# compare DIR_A DIR_B: summary points, pd_nodes.csv, line CSVs and VTU arrays to 1e-10.
compare() {
  python3 - "$1" "$2" "$SRC/tests/tools/read_vtu.py" <<'EOF'
import csv, glob, json, os, subprocess, sys
a, b, reader = sys.argv[1:4]
bad = []

def kind(name):
    n = name.lower()
    if n.startswith("u"): return "u"
    if n.startswith("f"): return "f"
    if n.startswith("s") and len(n) == 3: return "s"
    return n

def close(label, pairs):
    """pairs: list of (kind, va, vb); tolerance 1e-10 x the largest |value| of that kind."""
    scale = {}
    for k, va, vb in pairs:
        scale[k] = max(scale.get(k, 0.0), abs(va), abs(vb))
    worst = 0.0
    for k, va, vb in pairs:
        d = abs(va - vb) / scale[k] if scale[k] > 0 else abs(va - vb)
        worst = max(worst, d)
        if d > 1e-10:
            bad.append(f"{label}: {k} {va!r} vs {vb!r} (relative {d:.2e})")
            return
    return worst

sa, sb = (json.load(open(os.path.join(d, "summary.json"))) for d in (a, b))
for key in ("counts", "applied_load_sum"):
    if sa[key] != sb[key]: bad.append(f"summary {key} differ: {sa[key]} vs {sb[key]}")
pairs = []
for pa, pb in zip(sa["points"], sb["points"]):
    for f, v in pa.items():
        if isinstance(v, float) or (isinstance(v, int) and not isinstance(v, bool)):
            pairs.append((kind(f), float(v), float(pb[f])))
pairs += [("r", x, y) for x, y in zip(sa["reaction_sum"], sb["reaction_sum"])]
close("summary.json points", pairs)

for path in sorted(glob.glob(os.path.join(a, "*.csv"))):
    name = os.path.basename(path)
    ra = list(csv.reader(open(path)))
    rb = list(csv.reader(open(os.path.join(b, name))))
    if ra[0] != rb[0] or len(ra) != len(rb):
        bad.append(f"{name}: header or row count differ"); continue
    pairs = []
    for x, y in zip(ra[1:], rb[1:]):
        for h, u, v in zip(ra[0], x, y):
            try: pairs.append((kind(h), float(u), float(v)))
            except ValueError:
                if u != v: bad.append(f"{name}: {h} {u} vs {v}")
    close(name, pairs)

for path in sorted(glob.glob(os.path.join(a, "*.vtu"))):
    name = os.path.basename(path)
    da, db = (subprocess.run([sys.executable, reader, p], check=True, capture_output=True,
                             text=True).stdout.split("\n")
              for p in (path, os.path.join(b, name)))
    if len(da) != len(db):
        bad.append(f"{name}: different structure"); continue
    pairs, section = [], "?"
    for x, y in zip(da, db):
        if x.startswith(("array", "points", "cells")):
            section = x.split()[2] if x.startswith("array") else x
            if x != y: bad.append(f"{name}: {x} vs {y}")
            continue
        if x: pairs.append((section, float(x), float(y)))
    close(name, pairs)

for m in bad[:10]: print("  " + m)
sys.exit(1 if bad else 0)
EOF
}

# The files of two runs, bitwise; summary.json without its timings and memory figures.
identical() {
  local a=$1 b=$2 f
  for f in "$a"/*; do
    f=$(basename "$f")
    [ "$f" = summary.json ] && continue
    cmp -s "$a/$f" "$b/$f" || { echo "  $f differs"; return 1; }
  done
  python3 - "$a/summary.json" "$b/summary.json" <<'EOF'
import json, sys
def strip(d):
    if isinstance(d, dict):
        return {k: strip(v) for k, v in d.items()
                if k not in ("time_s", "total_time_s", "peak_memory_bytes")}
    if isinstance(d, list): return [strip(v) for v in d]
    return d
a, b = (strip(json.load(open(p))) for p in sys.argv[1:3])
sys.exit(0 if a == b else 1)
EOF
}

for model in static evaluate; do
  ok_runs=1
  for t in 1 2 4 2; do
    dir=${model}_t$t; [ -d "$dir" ] && dir=${dir}_again
    if ! "$CUPID" run $model.yaml -o "$dir" --threads $t --quiet; then
      echo "FAIL: $model with $t threads did not run"; fail=$((fail+1)); ok_runs=0
    fi
  done
  [ "$ok_runs" -eq 1 ] || continue
  grep -q '"threads": 4' ${model}_t4/summary.json && pass=$((pass+1)) || { echo "FAIL: $model: --threads 4 not applied"; fail=$((fail+1)); }
  for t in 2 4; do
    if compare ${model}_t1 ${model}_t$t; then pass=$((pass+1)); else echo "FAIL: $model: 1 vs $t threads differ"; fail=$((fail+1)); fi
  done
  if identical ${model}_t2 ${model}_t2_again; then pass=$((pass+1)); else echo "FAIL: $model: two runs with 2 threads are not bitwise identical"; fail=$((fail+1)); fi
done

# OpenBLAS threads inside CHOLMOD change the order of its sums (measured: 1.5e-13 relative);
# the results must still agree to 1e-10.
if OPENBLAS_NUM_THREADS=2 "$CUPID" run static.yaml -o static_blas2 --threads 2 --quiet &&
   compare static_t1 static_blas2; then
  pass=$((pass+1))
else
  echo "FAIL: static: 2 OpenBLAS threads change the results"; fail=$((fail+1))
fi

echo "determinism: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
