#!/usr/bin/env bash
# `cupid run` with type: dynamic (issue 5) on small trusses (paper 004 material): the output
# files, the energy balance, the tip history against the exact triangle wave, and the model
# errors (unstable central step, consistent mass with central, missing density).
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, expect, finish
M=$SRC/tests/models/dynamics

for m in fe_truss pd_truss; do
  expect 0 '' -- "$CUPID" run "$M/$m.yaml" -o "$m" --quiet
  for f in history.csv energies.csv model.pvd summary.json; do
    [ -s "$m/$f" ] && ok || bad "$m/$f missing"
  done
  ls "$m"/*_000100.vtu >/dev/null 2>&1 && ok || bad "$m: no VTU at step 100"
done

# Checks on the numbers (python3, standard library only):
#  - FE Newmark average acceleration, undamped: energy balance to round-off (tolerance 1e-9
#    relative) and the tip within 3 % RMS of the exact triangle wave of period 4L/c
#    (40 elements, 2 periods: measured 0.8 %);
#  - PD damped: the balance with the dissipated energy holds (1e-9), the dissipated energy is
#    positive, the final total (kinetic + strain) is below the initial 500 J, and the initial
#    strain energy is the stretched bar's.
python3 - "$work" <<'PY' && ok || bad "history/energy checks"
import csv, json, math, sys
w = sys.argv[1]
fe = json.load(open(w + "/fe_truss/summary.json"))["dynamic"]
assert fe["max_energy_balance_relative"] < 1e-9, fe
T = 4 / math.sqrt(1e9 / 7800)
def tri(t):
    s = (t / T) % 1.0
    return 1e-3 * (1 - 4 * s) if s < 0.5 else 1e-3 * (-1 + 4 * (s - 0.5))
rows = list(csv.DictReader(open(w + "/fe_truss/history.csv")))
rms = math.sqrt(sum((float(r["tip_uy"]) - tri(float(r["t"]))) ** 2 for r in rows) / len(rows)) / 1e-3
print("FE tip RMS error vs triangle wave: %.4f" % rms)
assert rms < 0.03, rms
pd = json.load(open(w + "/pd_truss/summary.json"))["dynamic"]
assert pd["max_energy_balance_relative"] < 1e-9, pd
e = pd["final_energy"]
assert e["damping_dissipated"] > 0 and e["kinetic"] + e["strain"] < 500, e
rows = list(csv.DictReader(open(w + "/pd_truss/energies.csv")))
# initial strain energy E A eps0^2 L / 2 = 500 J less the PD surface effect: the last horizon
# before the free end has incomplete families (measured 480.03 J): within 5 %
assert abs(float(rows[0]["strain"]) - 500) < 0.05 * 500, rows[0]
PY

expect 1 'central_unstable.yaml:[0-9]+:[0-9]+: analysis.dynamic: .*unstable with dt = 0.0001' -- "$CUPID" run "$M/central_unstable.yaml" -o cu
[ ! -e cu/summary.json ] && ok || bad "a refused run left summary.json"
expect 1 'central_consistent.yaml:[0-9]+:[0-9]+: analysis.dynamic: integrator: central needs a diagonal mass' -- "$CUPID" run "$M/central_consistent.yaml" -o cc
expect 1 "no_density.yaml:[0-9]+:[0-9]+: materials.steel: needs a density for a dynamic analysis" -- "$CUPID" run "$M/no_density.yaml" -o nd

# Loads and prescribed displacements that change with t on a beam (issue 34: refused before,
# "a model with a beam applies its loads at t = 0"): the truss under a sine tip force keeps
# Newmark's exact energy balance (1e-10; the load's work by the mean of each step's two loads);
# a tip force ramped over 18 periods ends at F L / (E A) within 1% (the ramp's leftover
# oscillation, 1 / (omega_1 T) = 0.9%); a tip moved 1e-6 m the same way (lumped mass) ends
# there exactly, the grip's work balancing the energies; with the consistent mass a moving
# grip on the beam is a model error.
"$CUPID" run "$M/time_load.yaml" -o tl --quiet && ok || bad "the truss under a sine tip force"
"$CUPID" run "$M/time_ramp.yaml" -o tr --quiet && ok || bad "the truss under a ramped tip force"
"$CUPID" run "$M/time_grip.yaml" -o tg --quiet && ok || bad "the truss under a ramped tip displacement"
"${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}" - <<'PY' && ok || bad "time-dependent conditions on a beam"
import json
tl, tr, tg = (json.load(open(d + "/summary.json")) for d in ("tl", "tr", "tg"))
u = tr["points"][0]["uy"]
print("sine force: energy balance %.2e; ramped force: tip %.6e against 1e-6 (%+.2f%%); ramped grip: "
      "tip %.6e, energy balance %.2e" % (tl["energy_balance"], u, 100 * (u / 1e-6 - 1),
                                         tg["points"][0]["uy"], tg["energy_balance"]))
assert tl["energy_balance"] <= 1e-10 and tg["energy_balance"] <= 1e-10
assert abs(u / 1e-6 - 1) <= 0.01
assert abs(tg["points"][0]["uy"] / 1e-6 - 1) <= 1e-12
PY
expect 1 'time_grip.yaml:[0-9]+:[0-9]+: constraints\[1\]: a prescribed displacement that changes with t on the beam needs analysis.dynamic.lumped: true' -- "$CUPID" run "$M/time_grip.yaml" -o tgc --set analysis.dynamic.lumped=false

finish dynamics_truss
