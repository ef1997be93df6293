#!/usr/bin/env bash
# The C-beam with a PD region in the web (examples/cbeam/cbeam_pd_l9.yaml: a region over part of
# the section, interfaces parallel to the axis, paper 000 sections 4.4 and 5.2) against the
# full L9 model (cbeam_fe_l9.yaml). Checked:
#  - u_z at A and B within 2% of the full model (the issue's target; observed -1.65% and
#    -1.09%: the PD web, 5 nodes thick at m = 3, is stiffer than E through its surface effect);
#  - the coupled run is stiffer than the full model at both points (sign of that effect);
#  - equilibrium imbalance |R + P| / P <= 10% (observed 7.7%: the coupling is not
#    momentum-conserving, docs/coupling.md) and solver residual <= 1e-8.
# Runtime ~25 s on 2 cores (UMFPACK LU of 27,000 equations), the largest of the suite.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$CUPID" run "$SRC/examples/cbeam/cbeam_pd_l9.yaml" -o "$work/pd" --quiet || { echo "FAIL: pd run"; exit 1; }
"$CUPID" run "$SRC/examples/cbeam/cbeam_fe_l9.yaml" -o "$work/fe" --quiet || { echo "FAIL: fe run"; exit 1; }
python3 - "$work" <<'PY'
import json, sys, os
w = sys.argv[1]
pd = json.load(open(os.path.join(w, "pd", "summary.json")))
fe = json.load(open(os.path.join(w, "fe", "summary.json")))
ok = True
for name in ("A", "B"):
    a = next(p["uz"] for p in pd["points"] if p["name"] == name)
    b = next(p["uz"] for p in fe["points"] if p["name"] == name)
    err = (abs(a) - abs(b)) / abs(b)
    print(f"u_z {name}: coupled {a:.5f}, full FE {b:.5f}, error {100 * err:+.2f}%")
    ok &= abs(err) <= 0.02 and err < 0
imb = max(abs(v) for v in pd["equilibrium_imbalance"]) / 1000.0
print(f"imbalance {100 * imb:.2f}% of the load, residual {pd['solver']['residual']:.1e}")
ok &= imb <= 0.10 and pd["solver"]["residual"] <= 1e-8
sys.exit(0 if ok else 1)
PY
