#!/usr/bin/env bash
# Patch test end to end (`analysis: evaluate`, pd_nodes.csv): an affine displacement field
# gives zero force at every node farther than 2 delta (LPS) or delta (bond-based) from the
# surface. Tolerance: 1e-11 of the largest nodal force in the body (the surface forces are
# O(1) in these units; interior forces are sums of ~10^3 terms of that size that cancel, so
# round-off leaves ~1e-13).
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0; pass=0
for model in lps bond; do
  "$CUPID" run "$SRC/tests/models/verification/evaluate_affine_$model.yaml" -o "$work/$model" --quiet || { fail=$((fail+1)); continue; }
  python3 - "$work/$model/pd_nodes.csv" "$model" <<'PY' && pass=$((pass+1)) || fail=$((fail+1))
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
reach = 3.0 if sys.argv[2] == "lps" else 1.5        # 2 delta or delta, delta = 1.5
fmax = max(max(abs(float(r[c])) for c in ("fx", "fy", "fz")) for r in rows)
interior = [r for r in rows if all(reach < float(r[a]) < 8 - reach for a in "xyz")]
worst = max(max(abs(float(r[c])) for c in ("fx", "fy", "fz")) for r in interior)
print(f"{sys.argv[2]}: {len(interior)} interior nodes, max |f| {worst:.3e}, surface scale {fmax:.3e}")
sys.exit(0 if interior and fmax > 0 and worst <= 1e-11 * fmax else 1)
PY
done
echo "evaluate_patch: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
