#!/usr/bin/env bash
# The C-beam with a PD region in the web (examples/cbeam/cbeam_pd_l9.yaml: a region over part of
# the section, interfaces parallel to the axis, paper 000 sections 4.4 and 5.2) against the
# full L9 model (cbeam_fe_l9.yaml). Checked:
#  - with every default (issue 34: the balanced coupling is the default): u_z at A and B within
#    2% of the full model and the equilibrium imbalance |R + P| / P under 1% (the issue's
#    figures; observed +0.00% at both and 0; it was -1.65% / -1.09% and 7.7% by default
#    before) and solver residual <= 1e-8;
#  - paper 000's operator as printed (`balance: none`): still within 2% but stiffer than the
#    full model at both points (the PD web, 5 nodes thick at m = 3, through its surface effect,
#    which Eq. 38's kinematic reads pass on) with an imbalance between 5% and 10% (observed
#    7.7%: the coupling is not momentum-conserving, docs/coupling.md): the before of the
#    before/after table.
# Runtime ~25 s on 2 cores (two UMFPACK LUs of 27,000 equations), the largest of the suite.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$CUPID" run "$SRC/examples/cbeam/cbeam_pd_l9.yaml" -o "$work/pd" --quiet || { echo "FAIL: pd run"; exit 1; }
"$CUPID" run "$SRC/examples/cbeam/cbeam_pd_l9.yaml" -o "$work/none" --quiet --set coupling.balance=none || { echo "FAIL: none run"; exit 1; }
"$CUPID" run "$SRC/examples/cbeam/cbeam_fe_l9.yaml" -o "$work/fe" --quiet || { echo "FAIL: fe run"; exit 1; }
python3 - "$work" <<'PY'
import json, sys, os
w = sys.argv[1]
fe = json.load(open(os.path.join(w, "fe", "summary.json")))
ok = True
for run, label in (("pd", "defaults"), ("none", "balance: none")):
    pd = json.load(open(os.path.join(w, run, "summary.json")))
    for name in ("A", "B"):
        a = next(p["uz"] for p in pd["points"] if p["name"] == name)
        b = next(p["uz"] for p in fe["points"] if p["name"] == name)
        err = (abs(a) - abs(b)) / abs(b)
        print(f"{label}: u_z {name}: coupled {a:.5f}, full FE {b:.5f}, error {100 * err:+.2f}%")
        ok &= abs(err) <= 0.02 and (err < 0 or run == "pd")
    imb = max(abs(v) for v in pd["equilibrium_imbalance"]) / 1000.0
    print(f"{label}: imbalance {100 * imb:.2f}% of the load, residual {pd['solver']['residual']:.1e}")
    ok &= pd["solver"]["residual"] <= 1e-8
    ok &= imb < 0.01 if run == "pd" else 0.05 <= imb <= 0.10
sys.exit(0 if ok else 1)
PY
