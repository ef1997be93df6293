#!/usr/bin/env bash
# Coupled patch test end to end (`analysis: evaluate`, pd_nodes.csv): an affine field imposed
# on a bar FE | PD | FE coupled by fictitious nodes gives zero force on every real PD node
# farther than 2 delta (LPS) or delta (bond-based) from the free lateral faces, including the
# nodes next to the two interfaces (no ghost forces). Tolerance: 1e-11 of the largest nodal
# force (the lateral-surface forces, O(1) here; interior sums of ~10^3 terms of that size
# cancel to ~1e-14). The C test unit.coupling_patch checks the FE rows and the solve.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0; pass=0
for model in lps_te2 bond_l9; do
  "$CUPID" run "$SRC/tests/models/coupling/evaluate_affine_$model.yaml" -o "$work/$model" --quiet || { fail=$((fail+1)); continue; }
  python3 - "$work/$model/pd_nodes.csv" "$model" <<'PY' && pass=$((pass+1)) || fail=$((fail+1))
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
reach = 3.0 if sys.argv[2].startswith("lps") else 1.5        # 2 delta or delta, delta = 1.5
fmax = max(max(abs(float(r[c])) for c in ("fx", "fy", "fz")) for r in rows)
interior = [r for r in rows if all(reach < float(r[a]) < 8 - reach for a in "xz")]
near = [r for r in interior if float(r["y"]) < 6 + 2 * reach or float(r["y"]) > 12 - 2 * reach]
worst = max(max(abs(float(r[c])) for c in ("fx", "fy", "fz")) for r in interior)
print(f"{sys.argv[2]}: {len(interior)} interior nodes ({len(near)} near an interface), max |f| {worst:.3e}, surface scale {fmax:.3e}")
sys.exit(0 if near and fmax > 0 and worst <= 1e-11 * fmax else 1)
PY
done
echo "coupling_patch: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
