#!/usr/bin/env bash
# Arlequin (paper 004 section 3) with PD regions over part of the section and several regions:
# the C-beam's web region (examples/cbeam/cbeam_pd_l9_arlequin.yaml: overlaps y [480, 490],
# [510, 520] normal to the axis and z [-30, -15], [15, 30] parallel to it) and the panel's two
# stringer regions (examples/panel/panel_pd_l9_arlequin.yaml: one slab list y [280, 290],
# [310, 320], z [2, 7] for both), against the full-L9 examples (cbeam_fe_l9.yaml,
# panel_fe_l9.yaml; the Arlequin beam meshes add element ends at the overlap bounds, which
# moves the full-FE figures by <= 0.05%). Checked, with the figures observed when written:
#  - the regions are all there (PD nodes: 5 x 40 x 60 for the C-beam, 2 x 4 x 40 x 20 for the
#    panel) and the beam gave way in their cores (more FE DOFs held at zero than the clamp of
#    the full-FE twin holds);
#  - equilibrium: |reaction + load| <= 1e-6 of the load (symmetric and momentum-conserving;
#    observed 8e-9 for the C-beam, 3e-8 for the panel: the solver's round-off);
#  - C-beam u_z at A and B within the issue's 2% of full L9 (observed -0.03% and -0.05%: the
#    PD web region is far from A and B and the Arlequin coupling adds no interface force);
#  - panel u_z at A and sigma_yy at C within 2% of full L9 (observed -0.10% and -1.04%), u_z at
#    B within 3% (observed +2.44%). Why B has its own bound: B (1.29 mm, against 19.8 at A) is
#    set by the stringers' twist, where the two models of the stringer differ by more than 2%
#    on their own: the coarse L9 stringer (one element through its 4 mm) is 5.4% off the
#    converged full-L9 panel at B (examples/panel/README.md), and the h = 1 PD stringer (4
#    nodes through) has its own torsion and out-of-plane bending errors (blade.py: +2.6% and
#    +12.5%). The Arlequin result is insensitive to the coupling's own parameters there
#    (kappa 1e4-1e6 and the three weights move B by 0.2%), so the 3% bounds the model
#    difference, not a coupling error.
. "$(dirname "$0")/../tools/checks.sh"
run() { # $1 example, $2 output; the progress log to $2.log
  "$CUPID" run "$SRC/examples/$1" -o "$2" > "$2.log" 2>&1 || { cat "$2.log"; bad "cupid run $1"; return 1; }
}
run cbeam/cbeam_fe_l9.yaml cfe
run cbeam/cbeam_pd_l9_arlequin.yaml carl
run panel/panel_fe_l9.yaml pfe
run panel/panel_pd_l9_arlequin.yaml parl
python3 - "$work" <<'PY' && ok || bad "Arlequin C-beam and panel against full L9"
import json, sys, os
w = sys.argv[1]
def load(d):
    s = json.load(open(os.path.join(w, d, "summary.json")))
    return s, {p["name"]: p for p in s["points"]}
errs = []
def check(name, ref, got, key, bound):
    e = (got / ref - 1) * 100
    print("%-24s %-8s full L9 %12.6g  Arlequin %12.6g  %+7.3f%%  (bound %g%%)" % (name, key, ref, got, e, bound))
    if not abs(e) <= bound: errs.append("%s %s %+.3f%%" % (name, key, e))
for fe, arl, npd, pts in (("cfe", "carl", 5 * 40 * 60, (("A", "uz", 2), ("B", "uz", 2))),
                          ("pfe", "parl", 2 * 4 * 40 * 20, (("A", "uz", 2), ("B", "uz", 3), ("C", "syy", 2)))):
    sf, pf = load(fe)
    sa, pa = load(arl)
    c = sa["counts"]
    print("%-24s %d PD nodes; %d DOFs held (full FE: %d)" % (arl, c["pd_nodes"], c["constrained_dofs"], sf["counts"]["constrained_dofs"]))
    if c["pd_nodes"] != npd: errs.append("%s: %d PD nodes, expected %d" % (arl, c["pd_nodes"], npd))
    if not c["constrained_dofs"] > sf["counts"]["constrained_dofs"]: errs.append(arl + ": the beam did not give way")
    for p, k, b in pts:
        check(arl + " " + p, pf[p][k], pa[p][k], k, b)
    load_sum = sa["applied_load_sum"]
    imb = max(abs(v) for v in sa["equilibrium_imbalance"])
    scale = max(abs(v) for v in load_sum)
    print("%-24s imbalance %.2e of the load" % (arl, imb / scale))
    if not imb <= 1e-6 * scale: errs.append("%s imbalance %.2e" % (arl, imb / scale))
    if sa["counts"]["fictitious_nodes"] != 0: errs.append(arl + ": fictitious nodes in an Arlequin model")
for e in errs: print("FAIL:", e)
sys.exit(1 if errs else 0)
PY
finish arlequin_partial
