#!/usr/bin/env bash
# PD bodies of other shapes than boxes (issue 35): cylinder and sphere regions and holes, whose
# cells are those with their centres inside; with `partial_volume: exact` each node carries the
# body's volume nearest it (cut cells, src/pd/cut_volume.c). Checks:
#  - a cylinder rod along y (r = 5 h, L = 60 h, LPS with the surface correction) under an end
#    traction t: the load sums to t pi r^2 (the loaded faces scaled to the true section; 1e-4,
#    the section's samples), and the strain between y = 20.5 and 40.5 is within 2% of t / E
#    with whole cells (measured -1.4%: the lattice's section is 1.9% larger than the disc) and
#    with cut cells (measured +0.5%; their volumes sum to pi r^2 L within 1e-3, measured
#    +4.3e-4, the midpoint rule at the section's tangents);
#  - a sphere of radius 5 h off the lattice: `cupid check` reports the nodes' volume within
#    0.5% of 4/3 pi r^3 (issue 35's bound; measured +1.8e-4; whole cells: +5.4%);
#  - a 60 x 60 x 3 plate with a hole (r = 8, LPS with the surface correction) in tension: no
#    node in the hole, the load t x 180 exactly (a box face: scale 1), equilibrium; the far
#    field's y-strain within 5% of t / E (measured -3.5%) and the largest at the hole's side
#    2.6-3.6 times it (measured 2.94 through the thickness; Heywood's gross Kt for d / W = 0.27 is 3.26, Kirsch's 3 in
#    an infinite plate; the node half a spacing off the edge, PD smoothing over the horizon).
. "$(dirname "$0")/../tools/checks.sh"
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
M=$SRC/tests/models/shapes

"$CUPID" run "$M/rod.yaml" -o rod --quiet && ok || bad "the cylinder rod"
"$CUPID" run "$M/rod.yaml" -o rod_cut --quiet --set peridynamics.partial_volume=exact && ok ||
  bad "the cylinder rod with cut cells"
"$PY" - <<'PY' && ok || bad "the rod's load and strain"
import csv, json, math
for out in ("rod", "rod_cut"):
    s = json.load(open(out + "/summary.json"))
    load = s["applied_load_sum"][1]
    exact = 100 * math.pi * 25
    rows = list(csv.DictReader(open(out + "/pd_nodes.csv")))
    def mean_uy(y):
        v = [float(r["uy"]) for r in rows if abs(float(r["y"]) - y) < 1e-9]
        return sum(v) / len(v)
    strain = (mean_uy(40.5) - mean_uy(20.5)) / 20
    vol = s["pd_volume"] / (math.pi * 25 * 60)
    print("%s: load %.3f N against t pi r^2 = %.3f N (%+.1e); strain / (t / E) = %.4f; the nodes' "
          "volume / (pi r^2 L) = %.5f, %d cut cells"
          % (out, load, exact, load / exact - 1, strain / (100 / 200000), vol, s["counts"]["pd_cut_cell_nodes"]))
    assert abs(load / exact - 1) <= 1e-4
    assert abs(strain / (100 / 200000) - 1) <= 0.02
    if out == "rod_cut":
        assert abs(vol - 1) <= 1e-3 and s["counts"]["pd_cut_cell_nodes"] > 0
PY

"$CUPID" check "$M/sphere.yaml" > sphere.txt && ok || bad "cupid check of the sphere"
"$PY" - <<'PY' && ok || bad "the sphere's volume"
import math, re
v = float(re.search(r"PD volume: (\S+)", open("sphere.txt").read()).group(1))
exact = 4 / 3 * math.pi * 125
print("sphere r = 5 h: the nodes' volume %.4f against 4/3 pi r^3 = %.4f (%+.1e)" % (v, exact, v / exact - 1))
assert abs(v / exact - 1) <= 0.005
PY

"$CUPID" run "$M/plate_hole.yaml" -o plate --quiet && ok || bad "the plate with a hole"
"$PY" - <<'PY' && ok || bad "the plate's hole, load and equilibrium"
import csv, json
s = json.load(open("plate/summary.json"))
load, imb = s["applied_load_sum"], s["equilibrium_imbalance"]
rows = list(csv.DictReader(open("plate/pd_nodes.csv")))
r2 = [(float(r["x"]) - 30) ** 2 + (float(r["y"]) - 30) ** 2 for r in rows]
assert min(r2) > 64, min(r2)
assert abs(load[1] - 18000) <= 1e-9 * 18000, load
assert max(abs(v) for v in imb) <= 1e-10 * 18000, imb  # |R + P| in N
u = {(float(r["x"]), float(r["y"]), float(r["z"])): float(r["uy"]) for r in rows}
def strain_at(x, y):  # central difference over the cells at y +- 1, averaged through z
    return sum((u[(x, y + 1, z)] - u[(x, y - 1, z)]) / 2 for z in (0.5, 1.5, 2.5)) / 3
far = sum(strain_at(x + 0.5, y + 0.5) for x in range(60) for y in range(45, 55)) / 600
side = max(strain_at(x, y) for x in (21.5, 38.5) for y in (29.5, 30.5))
print("plate with a hole: %d nodes; far-field y-strain / (t / E) = %.4f; at the hole's side %.2f "
      "times the far field (Heywood's gross Kt 3.26 at d / W = 0.27, Kirsch's 3 in an infinite "
      "plate)" % (len(rows), far / (100 / 70000), side / far))
assert abs(far / (100 / 70000) - 1) <= 0.05  # measured -3.5% (3 cells thick: Poisson, surfaces)
assert 2.6 <= side / far <= 3.6  # measured 2.94, half a spacing off the edge, smoothed over delta
PY
finish pd_shapes
