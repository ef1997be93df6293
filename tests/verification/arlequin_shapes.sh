#!/usr/bin/env bash
# Shaped PD zones in a coupled model (issue 35): examples/geometry/tube_notch.yaml, a tube as a
# CUF beam with a Gmsh-meshed section (curved L9) and PD only around a notch, the PD zone the
# tube itself over y in [88, 112] (a cylinder region less a cylinder hole, cut-cell volumes),
# joined by the Arlequin method. Checks:
#  - the PD nodes lie in the tube's wall and their volumes sum to pi (R^2 - r^2) L within 1e-3
#    (measured 2.5e-5); equilibrium (|R + P| / |P| <= 1e-8, the matrix-free CG's tolerance);
#  - without the notch, the tip's deflection against the beam alone (the same beam without PD):
#    within 2% (measured -1.6%: the uncorrected PD wall, three cells thick, is stiffer than the
#    continuum) and within 0.5% with the surface correction (measured +0.08%);
#  - the notch makes the tube more compliant: the tip deflects more with it than without
#    (measured +0.43%), and the beam alone gives Euler-Bernoulli's F L^3 / (3 E I) within 1%
#    (measured +0.8%: shear);
#  - fictitious nodes and Lagrange multipliers refuse the shapes (their interfaces are built on
#    box regions), naming arlequin.
# ~20 s on 2 cores.
. "$(dirname "$0")/../tools/checks.sh"
# under ASan (build-asan), what Gmsh's library keeps at exit is not cupid's (the file says why)
export LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}suppressions=$SRC/tests/tools/lsan_gmsh.supp"
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
T=$SRC/examples/geometry/tube_notch.yaml
"$PY" - "$T" <<'PY' && ok || bad "the beam-only model"
import sys
s = open(sys.argv[1]).read().replace("../sections/tube_section.geo",
                                     sys.argv[1].rsplit("/", 2)[0] + "/sections/tube_section.geo")
a, b = s.index("peridynamics:"), s.index("constraints:")
open("beam_only.yaml", "w").write(s[:a] + s[b:])
PY
"$CUPID" run "$T" -o notch --quiet --set output.pd_nodes=true && ok || bad "the notched tube"
"$CUPID" run "$T" -o plain --quiet --set 'peridynamics.precracks=[]' && ok || bad "the tube without the notch"
"$CUPID" run "$T" -o corrected --quiet --set 'peridynamics.precracks=[]' \
  --set peridynamics.surface_correction=energy && ok || bad "the tube with the surface correction"
"$CUPID" run beam_only.yaml -o beam --quiet && ok || bad "the beam alone"
"$PY" - <<'PY' && ok || bad "the tube's checks"
import csv, json, math
def tip(d):
    return [p for p in json.load(open(d + "/summary.json"))["points"] if p["name"] == "tip"][0]["uz"]
s = json.load(open("notch/summary.json"))
rows = list(csv.DictReader(open("notch/pd_nodes.csv")))
r = [math.hypot(float(q["x"]), float(q["z"])) for q in rows]
assert 8 <= min(r) and max(r) <= 10 and all(88 < float(q["y"]) < 112 for q in rows)
vol = s["pd_volume"] / (math.pi * (100 - 64) * 24)
imb = max(abs(v) for v in s["equilibrium_imbalance"]) / abs(s["applied_load_sum"][2])
beam, plain, corr, notch = tip("beam"), tip("plain"), tip("corrected"), tip("notch")
F, I = 10 * math.pi * 36, math.pi / 4 * (1e4 - 8 ** 4)
eb = -F * 200 ** 3 / (3 * 200000 * I)
print("tube: %d PD nodes, volume / (pi (R^2 - r^2) L) = %.6f, imbalance %.1e" % (len(rows), vol, imb))
print("tip u_z: beam alone %.5f (Euler-Bernoulli %.5f, %+.2f%%); coupled without the notch %.5f "
      "(%+.2f%%), with the surface correction %.5f (%+.2f%%); with the notch %.5f (%+.2f%% on "
      "without)" % (beam, eb, 100 * (beam / eb - 1), plain, 100 * (plain / beam - 1), corr,
                    100 * (corr / beam - 1), notch, 100 * (notch / plain - 1)))
assert abs(vol - 1) <= 1e-3 and imb <= 1e-8
assert abs(beam / eb - 1) <= 0.01
assert abs(plain / beam - 1) <= 0.02 and abs(corr / beam - 1) <= 0.005
assert notch < plain  # downward: more deflection
PY
for method in fictitious lagrange; do
  out=$("$CUPID" check "$T" --set "coupling={method: $method}" 2>&1)
  [ $? -eq 1 ] && grep -q "need coupling.method: arlequin with a beam" <<<"$out" && ok ||
    bad "$method refuses the shapes: $out"
done
finish arlequin_shapes
