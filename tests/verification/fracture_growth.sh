#!/usr/bin/env bash
# Load steps and quasi-static crack growth (analysis.steps; issue 17, first part) on a notched
# bond-based plate pulled by a prescribed displacement (tests/models/growth/plate.yaml):
#  1. linear limit: with a critical stretch no bond reaches, no bond breaks and every step's
#     reaction is k/N times the last one (1e-10 relative: each step is its own solve); without
#     fracture the N steps are one solve scaled, and the last equals a plain static run (1e-12);
#  2. the first break at the load factor the linear solution predicts (s0 / s_max): loaded
#     1e-9 below it (one step) nothing breaks, 1e-9 above it a bond does;
#  3. growth: bonds break, the crack crosses, a node left loose is held instead of a singular
#     matrix, the reaction falls to zero once the plate is cut (and no next break or peak is
#     read off the round-off left); 1 and 2 threads give the same damage.csv byte for byte;
#     the Krylov re-solves break the bonds that refactorising does; a SENB cut through keeps
#     the peak it had before the cut;
#  4. errors: steps outside type static, fracture in type evaluate.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
M=$SRC/tests/models/growth/plate.yaml

# 1. linear limit
"$CUPID" run "$M" -o lin --quiet --set peridynamics.fracture.critical_stretch=1 && ok || bad "run with s0 = 1"
"$PY" - lin <<'PY' && ok || bad "linear limit with fracture on"
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/damage.csv")))
assert len(rows) == 10 and all(int(r["broken_bonds"]) == 0 for r in rows), "a bond broke"
last = float(rows[-1]["reaction_0_y"])
for k, r in enumerate(rows, 1):
    assert abs(float(r["reaction_0_y"]) - k / 10 * last) <= 1e-10 * abs(last), (k, r["reaction_0_y"], last)
PY
sed -e '/  fracture:/d' "$M" > nofrac.yaml
sed -e '/  precracks:/,+1d' nofrac.yaml > intact.yaml
"$CUPID" run intact.yaml -o intact --quiet && [ -s intact/load_steps.csv ] && [ ! -e intact/damage.csv ] && ok || bad "load_steps.csv of an intact model"
"$CUPID" run nofrac.yaml -o steps --quiet && ok || bad "run without fracture, 10 steps"
sed -e 's/analysis: {type: static, steps: 10}/analysis: {type: static}/' nofrac.yaml > plain.yaml
"$CUPID" run plain.yaml -o plain --quiet && ok || bad "plain static run"
"$PY" - steps plain <<'PY' && ok || bad "N steps against one static solve"
import csv, sys
a = list(csv.DictReader(open(sys.argv[1] + "/pd_nodes.csv")))
b = list(csv.DictReader(open(sys.argv[2] + "/pd_nodes.csv")))
scale = max(abs(float(r["uy"])) for r in b)
for r, s in zip(a, b):
    for c in ("ux", "uy", "uz"):
        assert abs(float(r[c]) - float(s[c])) <= 1e-12 * scale, (r, s)
# pre-cracks without fracture: the steps go to damage.csv (load_steps.csv without damage)
rows = list(csv.DictReader(open(sys.argv[1] + "/damage.csv")))
assert len(rows) == 10 and sum(int(r["iterations"]) for r in rows) == 1, "more than one solve"
PY

# 2. the first break, by scaling
"$CUPID" run "$M" -o grow2 --quiet --threads 2 && ok || bad "growth run (2 threads)"
lam=$("$PY" -c "import json,sys; print(repr(json.load(open('grow2/summary.json'))['fracture']['first_break_load_factor']))")
for side in below above; do
  f=$("$PY" -c "l=$lam; print(repr(0.02 * l * (1 - 1e-9 if '$side' == 'below' else 1 + 1e-9)))")
  "$CUPID" run "$M" -o "$side" --quiet --set analysis.steps=1 --set "constraints[1].displacement.value=[0, $f, 0]" \
    && ok || bad "run at the first-break load ($side)"
done
"$PY" - below above <<'PY' && ok || bad "first break at s0 / s_max"
import json, sys
b = json.load(open(sys.argv[1] + "/summary.json"))["fracture"]["broken_bonds"]
a = json.load(open(sys.argv[2] + "/summary.json"))["fracture"]["broken_bonds"]
print("first break: 1e-9 below the predicted load %d bonds, above %d" % (b, a))
assert b == 0 and a > 0
PY

# 3. growth, and determinism
"$CUPID" run "$M" -o grow1 --quiet --threads 1 && ok || bad "growth run (1 thread)"
cmp -s grow1/damage.csv grow2/damage.csv && ok || bad "1 and 2 threads differ (damage.csv)"
"$PY" - grow2 <<'PY' && ok || bad "growth"
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/damage.csv")))
fr = json.load(open(sys.argv[1] + "/summary.json"))["fracture"]
peak = max(abs(float(r["reaction_0_y"])) for r in rows)
print("growth: %d bonds broken, first at load factor %.6f, %s nodes held, peak reaction %.4g, last %.3g"
      % (fr["broken_bonds"], fr["first_break_load_factor"], rows[-1]["released_nodes"], peak,
         float(rows[-1]["reaction_0_y"])))
assert fr["broken_bonds"] > 100
assert abs(float(rows[-1]["reaction_0_y"])) < 1e-6 * peak, "the plate still carries load"
# once cut, no next break (the stretches left are round-off, which 1 / ratio would blow up)
cut = [r for r in rows if abs(float(r["reaction_0_y"])) < 1e-6 * peak]
assert cut and all(float(r["next_break_load_factor"]) == 0.0 for r in cut), cut
assert fr["peak_reactions"][0]["step"] < int(cut[0]["step"]), fr["peak_reactions"][0]
PY

# 3a. a crack that cuts the load path of a grip-loaded beam: the coupled SENB of
# examples/fracture at h = 5/3 without its no-fail box, its load line pushed to -0.2 mm, so
# that the crack runs through the height. After the cut the stretches are the solve's
# round-off (1e-12 of the first solve's per unit load), and scaling them to a "next break"
# made a peak of round-off times 10^11: 60 N at load factor 8e10 against the true 16.3 N. The
# peak must be the largest reaction times next_break / load factor over the steps before the
# cut, and next_break 0 after it.
sed -e '/    no_fail:/,/^coupling:/{/^coupling:/!d}' "$SRC/examples/fracture/senb_coupled.yaml" > cut.yaml
"$CUPID" run cut.yaml -o cut --quiet --set analysis.steps=20 \
  --set "constraints[0].displacement.value=[-0.2, null, null]" \
  --set peridynamics.spacing=1.6666666666666667 --set peridynamics.horizon=5.025 \
  --set output.vtu=false --set output.plots=false && ! grep -q no_fail cut.yaml && ok || bad "the SENB cut through"
"$PY" - cut <<'PY' && ok || bad "the peak of a beam cut through"
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/damage.csv")))
fr = json.load(open(sys.argv[1] + "/summary.json"))["fracture"]
top = max(abs(float(r["reaction_0_x"])) for r in rows)
cut = [r for r in rows if abs(float(r["reaction_0_x"])) < 1e-6 * top]
assert len(cut) >= 5, "the beam was not cut through"
before = [r for r in rows if int(r["step"]) < int(cut[0]["step"])]
env = max(abs(float(r["reaction_0_x"])) * float(r["next_break_load_factor"]) / float(r["load_factor"])
          for r in before)
p = fr["peak_reactions"][0]
print("cut at step %s; peak %.6g N at step %d (envelope %.6g)" % (cut[0]["step"], -p["reaction"][0], p["step"], env))
# 1e-9: damage.csv holds 11 significant digits of each of the three factors
assert abs(abs(p["reaction"][0]) - env) <= 1e-9 * env and p["step"] < int(cut[0]["step"]), p
assert all(float(r["next_break_load_factor"]) == 0.0 for r in cut)
PY

# 3b. the re-solves after breaks: the last factor downdated by the broken bonds' rank-one
# terms (the default), CG preconditioned by the last factor (krylov), and a new factorisation
# every time (factor): the same bonds in the same steps, reactions within 1e-9 (CG stops at
# 1e-12 of the residual); a mechanism that only a factorisation finds is held at the next
# load step's factorisation instead of at once (released_nodes may lag a step)
CUPID_GROWTH_RESOLVE=factor "$CUPID" run "$M" -o growf --quiet --threads 2 && ok || bad "growth run, refactorising"
CUPID_GROWTH_RESOLVE=krylov "$CUPID" run "$M" -o growk --quiet --threads 2 && ok || bad "growth run, Krylov re-solves"
"$PY" - grow2 growk growf <<'PY' && ok || bad "downdates and Krylov re-solves against refactorisation"
import csv, json, sys
runs = [list(csv.DictReader(open(d + "/damage.csv"))) for d in sys.argv[1:]]
assert all(len(r) == 10 for r in runs)
peak = max(abs(float(r["reaction_0_y"])) for r in runs[2])
for a in runs[:2]:
    for r, s in zip(a, runs[2]):
        for c in ("iterations", "broken_bonds", "damaged_nodes", "nodes_broken"):
            assert r[c] == s[c], (r["step"], c, r[c], s[c])
        assert abs(float(r["reaction_0_y"]) - float(s["reaction_0_y"])) <= 1e-9 * peak, r["step"]
kd, kk, kf = (json.load(open(d + "/summary.json"))["fracture"]["solves"] for d in sys.argv[1:])
print("re-solves: downdate %d factorisations + %d downdates (%d bonds) + %d CG solves (%d "
      "iterations); krylov %d factorisations + %d CG solves (%d iterations); factor %d "
      "factorisations" % (kd["factorisations"], kd["downdates"], kd["downdate_columns"],
                          kd["cg_solves"], kd["cg_iterations"], kk["factorisations"],
                          kk["cg_solves"], kk["cg_iterations"], kf["factorisations"]))
assert kd["resolve"] == "downdate" and kk["resolve"] == "krylov" and kf["resolve"] == "factor"
# a downdated factor is the current K's: one CG iteration checks each solve
assert kd["downdates"] > 0 and kd["cg_iterations"] <= kd["cg_solves"] + 2
assert kd["factorisations"] < kk["factorisations"] < kf["factorisations"] == kf["solves"]
PY

# 4. errors
out=$("$CUPID" check "$M" --set analysis.type=dynamic 2>&1); rc=$?
[ $rc -eq 1 ] && grep -q "analysis.steps: is only used with type: static" <<<"$out" && ok || bad "steps with type dynamic: $out"
out=$("$CUPID" run "$M" -o ev --set analysis='{type: evaluate, field: [0, 0, 0]}' 2>&1); rc=$?
[ $rc -eq 1 ] && grep -q "bond breaking needs type: static" <<<"$out" && ok || bad "fracture with type evaluate: $out"

finish fracture_growth
