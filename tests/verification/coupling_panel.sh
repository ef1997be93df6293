#!/usr/bin/env bash
# The stiffened panel with PD regions in both stringers (examples/panel/panel_pd_l9.yaml, paper
# 000 section 5.3) against its full L9 model (panel_fe_l9.yaml). The issue's 2% is NOT met at
# h = 1 with paper 000's operator as printed (`balance: none`, pinned here; the default
# balances the coupling, verification.coupling_panel_balance) (u_z A +4.5%, u_z B -2.1%, sigma_yy C +10.6%; docs/coupling.md "C-beam and panel":
# the 4-node-thick PD blades' own stiffness error, which no FE mesh removes, examples/panel/
# study.py and blade.py; at h = 0.5 the coupled panel is within 1% of the converged full L9:
# verification.mpi_panel_fine, PETSc build). This test records that state so a change shows, and checks the
# diagnosis the documentation rests on:
#  - the coupled figures equal the recorded ones to 1e-4 relative (UMFPACK rounding is ~1e-10;
#    a change of the coupling, the PD operator or the section mesh moves them by >= 1e-3);
#  - the coupled panel is softer than the full model at A (the blades' out-of-plane bending,
#    t^3 term, is 12.5% softer as PD at m = 3) and sigma_yy at C is higher;
#  - equilibrium imbalance in z between 3.5 and 4.2 N of 20 N (observed 3.85 N: the
#    fictitious-node coupling is not momentum-conserving) and the solver's backward error
#    <= 1e-12 (observed 6e-17; the absolute residual, 1.1e-8, scales with the 1e4 MPa moduli).
# Runtime ~10 s and 1.3 GB on 2 cores.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$CUPID" run "$SRC/examples/panel/panel_pd_l9.yaml" -o "$work/pd" --quiet --set coupling.balance=none || { echo "FAIL: pd run"; exit 1; }
"$CUPID" run "$SRC/examples/panel/panel_fe_l9.yaml" -o "$work/fe" --quiet || { echo "FAIL: fe run"; exit 1; }
python3 - "$work" <<'PY'
import json, sys, os
w = sys.argv[1]
pd = json.load(open(os.path.join(w, "pd", "summary.json")))
fe = json.load(open(os.path.join(w, "fe", "summary.json")))
# recorded coupled values (h = 1, m = 3, LPS, no surface correction)
recorded = {("A", "uz"): -20.736729, ("B", "uz"): 1.258586, ("C", "syy"): 2.440032}
ok = True
err = {}
for (name, c), ref in recorded.items():
    a = next(p[c] for p in pd["points"] if p["name"] == name)
    b = next(p[c] for p in fe["points"] if p["name"] == name)
    err[name] = a / b - 1
    same = abs(a / ref - 1) <= 1e-4
    print(f"{c} {name}: coupled {a:.6f} (recorded {ref:.6f}{'' if same else ', CHANGED'}), "
          f"full FE {b:.6f}, error {100 * err[name]:+.2f}%")
    ok &= same
ok &= err["A"] > 0 and err["C"] > 0
imb = pd["equilibrium_imbalance"]
print(f"imbalance {imb[0]:.3f}, {imb[1]:.3f}, {imb[2]:.3f} N of 20 N, "
      f"backward error {pd['solver']['backward_error']:.1e}")
ok &= 3.5 <= imb[2] <= 4.2 and pd["solver"]["backward_error"] <= 1e-12
sys.exit(0 if ok else 1)
PY
