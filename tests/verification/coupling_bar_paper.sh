#!/usr/bin/env bash
# The coupled bar in paper 000's own configuration (section 5.1; shared/reference/examples.md
# section 1): 10 x 10 x 100 mm, clamped at y = 0, 100 MPa on y = 100; PD (LPS, Gaussian,
# m = 3, h = 1, PDLAMMPS partial volumes, no surface correction) on y in [30, 70]; one B2
# element on each FE span, one L9 section element (examples/bar/bar_coupled_l9.yaml against
# bar_fe_l9.yaml, the same beam mesh as full FE). Issue 18; docs/coupling.md, "The fictitious
# FE element". Paper 000's operator as printed, `balance: none` (the default balances each
# interface since issue 34: verification.coupling_cbeam and coupling_balance). Checked:
#  - fictitious nodes (the default fictitious FE element, the removed beam element):
#    max |u_y - u_y^FE| / |u_y^FE| along the axis x = z = 5, y > 0, <= 0.7%: the paper's
#    figure (0.69%, section 5.1; observed 0.60%);
#  - its equilibrium imbalance |R + P| / P <= 0.7% (observed 0.43%): the method is not
#    momentum-conserving, and the clamped span carries the reaction, so the imbalance shows
#    one for one in that span's strain; alone it must stay within the paper's figure;
#  - Lagrange multipliers (bar_coupled_lagrange_l9.yaml) visibly worse: max relative error
#    >= 3 times the fictitious nodes' (paper: over 5% at the interfaces against 0.69%, a factor
#    above 7; observed 4.06% at y = 70 against 0.60%, 6.8x; the factor 3 leaves room for the
#    details the paper's Fig. 11 holds and the reconstruction does not), its largest error
#    within 3 mm of an interface, and its imbalance <= 1e-9 (symmetric, exact equilibrium);
#  - the cause (issue 18): the same model with the fictitious FE element of cupid before the
#    issue, the h/2 B2 element to the nearest PD plane (--set coupling.fictitious_fe=plane), still
#    gives the issue's figures: max relative error >= 4% and imbalance >= 3% (observed 5.24%
#    and 4.20%);
#  - every run: the clamped end does not move and the solver residual <= 1e-10.
# Runtime ~1 minute on 2 cores (two UMFPACK LUs of Eq. 38, 13,000 equations each).
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for m in fe_l9 coupled_l9 coupled_lagrange_l9; do
  none=(); [ "$m" = coupled_l9 ] && none=(--set coupling.balance=none) # Eq. 38 as printed
  "$CUPID" run "$SRC/examples/bar/bar_$m.yaml" -o "$work/$m" --quiet "${none[@]}" || { echo "FAIL: $m run"; exit 1; }
done
"$CUPID" run "$SRC/examples/bar/bar_coupled_l9.yaml" -o "$work/plane" --quiet --set coupling.fictitious_fe=plane --set coupling.balance=none ||
  { echo "FAIL: plane run"; exit 1; }
/usr/bin/python3 - "$work" <<'PY'
import csv, json, os, sys
w = sys.argv[1]
def axis(d):
    return [(float(r["y"]), float(r["uy"])) for r in csv.DictReader(open(os.path.join(w, d, "line_axis.csv")))]
fe = axis("fe_l9")
ok = True
res = {}
for m in ("coupled_l9", "coupled_lagrange_l9", "plane"):
    c = axis(m)
    s = json.load(open(os.path.join(w, m, "summary.json")))
    rel = [(abs(u - v) / abs(v), y) for (y, u), (_, v) in zip(c, fe) if y > 0]
    worst, at = max(rel)
    near = max(e for e, y in rel if min(abs(y - 30), abs(y - 70)) <= 3)
    imb = abs(s["applied_load_sum"][1] + s["reaction_sum"][1]) / abs(s["applied_load_sum"][1])
    res[m] = (worst, at, near, imb)
    print(f"{m}: max relative error {100 * worst:.3f}% at y = {at:g} (within 3 mm of an interface "
          f"{100 * near:.3f}%), imbalance {100 * imb:.3g}%, residual {s['solver']['residual']:.1e}, "
          f"u_y(0) {c[0][1]:.1e}")
    ok &= s["solver"]["residual"] <= 1e-10 and abs(c[0][1]) <= 1e-12
f, l, p = res["coupled_l9"], res["coupled_lagrange_l9"], res["plane"]
print(f"paper 0.69%: fictitious nodes {100 * f[0]:.3f}% <= 0.7%, imbalance {100 * f[3]:.3f}% <= 0.7%")
ok &= f[0] <= 0.007 and f[3] <= 0.007
print(f"Lagrange / fictitious: {l[0] / f[0]:.1f} >= 3; Lagrange's largest error near an interface: "
      f"{l[2] >= l[0] - 1e-15}; Lagrange imbalance {l[3]:.1e} <= 1e-9")
ok &= l[0] >= 3 * f[0] and l[2] >= l[0] - 1e-15 and l[3] <= 1e-9
print(f"cause: h/2 fictitious element {100 * p[0]:.2f}% >= 4%, imbalance {100 * p[3]:.2f}% >= 3%")
ok &= p[0] >= 0.04 and p[3] >= 0.03
print("coupling_bar_paper:", "passed" if ok else "FAILED")
sys.exit(0 if ok else 1)
PY
