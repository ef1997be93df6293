#!/usr/bin/env bash
# The plate with a hole against CalculiX (issue 35): examples/geometry/plate_hole_calculix.yaml
# (40 x 40 x 6, r = 5.5, LPS with the surface correction and cut-cell volumes, h = 1) and the
# same plate as C3D20R hexahedra in ccx (tests/tools/plate_hole_ccx.py: an O-grid with curved
# edges on the hole; 16 x 16 x 4 elements a block, 20k nodes). Checks:
#  - the FE model has converged: its displacement differences change by less than 2e-3 from
#    8 x 8 x 2 elements a block (measured 2e-4 to 1.3e-3, the last the hole's width; quadratic
#    elements, so the fine mesh's own error is a fraction of that);
#  - PD's displacement differences between chosen points against the FE's (the grips differ:
#    PD holds a layer of nodes, the FE model a face, so differences are compared): along the
#    load's axis across the hole, near the left edge, and across the hole's height within 1%
#    (measured +0.26%, +0.67%, +0.88%; with whole cells -2.9%, -0.2%, -4.1%: the hole then
#    lacks the cut cells' volume); the hole's width (x, one spacing off its sides, where PD
#    smooths over the horizon) within 4% (measured +2.9%; whole cells -6.9%);
#  - the stress concentration, reported beside Kirsch's 3 (infinite plate) and Heywood's 3.28
#    (gross section, d / W = 0.275): the FE's s_yy / t at the hole's edge on the mid-plane
#    within [3.2, 3.7] (measured 3.49 here, 3.52 at 24 x 24 x 6: the 3D mid-plane value of a
#    plate as thick as the hole's radius lies above the plane-stress one), and PD's nodal s_yy
#    one spacing off the side within 15% of the FE's there (measured +6%: PD's nodal stress
#    averages over the horizon).
# Needs ccx (Debian's calculix-ccx, scripts/install-deps.sh); ~40 s on 2 cores.
. "$(dirname "$0")/../tools/checks.sh"
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
command -v ccx >/dev/null || { echo "pd_plate_calculix: ccx not found (apt-get install calculix-ccx)"; exit 1; }
"$CUPID" run "$SRC/examples/geometry/plate_hole_calculix.yaml" -o pd --quiet && ok || bad "the PD plate"
pts=(20.5,33.5,2.5 20.5,6.5,2.5 3.5,33.5,2.5 3.5,6.5,2.5 20.5,26.5,2.5 20.5,13.5,2.5
     13.5,20.5,2.5 26.5,20.5,2.5 14.5,20,3)
"$PY" "$SRC/tests/tools/plate_hole_ccx.py" fe1 40 6 5.5 8 8 2 "${pts[@]}" > fe1.json && ok || bad "ccx, coarse"
"$PY" "$SRC/tests/tools/plate_hole_ccx.py" fe2 40 6 5.5 16 16 4 "${pts[@]}" > fe2.json && ok || bad "ccx, fine"
"$PY" - <<'PY' && ok || bad "PD against CalculiX"
import json
pd = {p["name"]: p for p in json.load(open("pd/summary.json"))["points"]}
fe = [[p for p in json.load(open(f))["points"]] for f in ("fe1.json", "fe2.json")]
fine = json.load(open("fe2.json"))
# (name, PD points, FE point indices, component, bound)
pairs = [("axis: uy(20.5, 33.5) - uy(20.5, 6.5)", "axis_top", "axis_bottom", 0, 1, 1, 0.01),
         ("near the edge: uy(3.5, 33.5) - uy(3.5, 6.5)", "side_top", "side_bottom", 2, 3, 1, 0.01),
         ("hole's height: uy(20.5, 26.5) - uy(20.5, 13.5)", "hole_above", "hole_below", 4, 5, 1, 0.01),
         ("hole's width: ux(26.5, 20.5) - ux(13.5, 20.5)", "hole_right", "hole_left", 7, 6, 0, 0.04)]
print("CalculiX C3D20R: %d nodes, %d elements" % (fine["nodes"], fine["elements"]))
for what, a, b, i, j, c, bound in pairs:
    d = ["ux", "uy", "uz"][c]
    p = pd[a][d] - pd[b][d]
    f = [F[i]["u"][c] - F[j]["u"][c] for F in fe]
    conv, err = abs(f[1] / f[0] - 1), p / f[1] - 1
    print("  %-50s PD %.6f  FE %.6f (coarse %+.1e)  PD %+.2f%%" % (what, p, f[1], f[0] / f[1] - 1, 100 * err))
    assert conv <= 2e-3, (what, conv)
    assert abs(err) <= bound, (what, err)
kt_fe = fe[1][8]["stress"][1] / 100
s_pd, s_fe = pd["hole_left"]["syy"], fe[1][6]["stress"][1]
print("  stress concentration s_yy / t at the hole's edge (mid-plane): CalculiX %.2f (Kirsch 3, "
      "Heywood 3.28); one spacing off the side: PD %.1f MPa, CalculiX %.1f MPa (%+.1f%%); PD's "
      "cut node on the edge %.1f MPa" % (kt_fe, s_pd, s_fe, 100 * (s_pd / s_fe - 1), pd["hole_edge"]["syy"]))
assert 3.2 <= kt_fe <= 3.7, kt_fe
assert abs(s_pd / s_fe - 1) <= 0.15, (s_pd, s_fe)
PY
finish pd_plate_calculix
