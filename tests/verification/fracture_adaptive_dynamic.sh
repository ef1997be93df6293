#!/usr/bin/env bash
# Adaptive PD zones in explicit dynamics (issue 37) on tests/models/adaptive/bar_dynamic.yaml:
# the notched glass bar under a sudden end traction, PD on [35, 65] of a CUF beam, Arlequin.
# The trigger is tested every 20 steps; where it fires the run stops at that step, the zone
# grows (the new nodes take u and v from the beam's field), and central differences go on from
# there on the new layout: its acceleration, mass and stable step made again, and the energy the
# conversion added booked in energies.csv's conversion_added column.
#  1. a trigger that never fires gives the fixed zone's energies, damage and history to the
#     bit (the run stops at step 600, before the crack reaches an overlap);
#  2. the zone grows where the wave's strain reaches 0.4 s0 ([60, 70] at step 320) and where
#     the crack's overlap bonds near their limit ([35, 40] at 500, [30, 35] at 560); damage.csv's
#     pd_nodes follows; the energy balance through the conversions stays at the fixed zone's
#     level (2.3e-5 of the run's energy against 1.6e-5; bound 5e-5) while the conversions'
#     energy (-1.63, 250 times the worst balance) would break it were it not booked;
#  3. with the bar moving sideways at 10 m/s from t = 0 a conversion's energy stays below a
#     tenth of the kinetic energy its new nodes carry (a new node at rest would lose all of it);
#  4. 1 and 2 threads convert the same elements at the same steps;
#  5. max_nodes stops the run at the conversion (exit 2) with the time series so far (also the
#     beam alone of a zone that starts empty); `every` with a static analysis is a model error;
#  6. a zone that starts empty (`regions: []`): with the pre-crack, the set-up lays [40, 60]
#     around it and, the trigger never firing in 540 steps, the run is the fixed zone
#     [40, 60]'s to the bit; without it, the beam alone runs (its assembled K, no bond) until
#     the wave's strain turns [65, 70] at step 320, and central differences go on on the coupled
#     model's operator: eight conversions, each one's energy booked, the balance within 1e-4.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, expect, finish
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
export PYTHONPATH=$SRC/tests/tools  # adaptive_rows.py
M=$SRC/tests/models/adaptive/bar_dynamic.yaml
grep -v "^  adaptive:" "$M" > fixed.yaml
short=(--set analysis.dynamic.duration=1.5e-5)

"$CUPID" run "$M" -o never --quiet "${short[@]}" --set 'peridynamics.adaptive={threshold: 1, margin: 0}' \
  && ok || bad "run: never fires"
"$CUPID" run fixed.yaml -o fixed_short --quiet "${short[@]}" && ok || bad "run: fixed zone, short"
"$CUPID" run "$M" -o grow --quiet && ok || bad "run: grows"
"$CUPID" run fixed.yaml -o fixed --quiet && ok || bad "run: fixed zone"
OMP_NUM_THREADS=1 "$CUPID" run "$M" -o grow_t1 --quiet --threads 1 && ok || bad "run: one thread"
"$CUPID" run "$M" -o moving --quiet --set 'analysis.dynamic.initial={velocity: [1.0e4, 0, 0]}' \
  && ok || bad "run: moving sideways"
empty=(--set 'peridynamics.regions=[]' --set 'coupling.arlequin.overlap=[]')
"$CUPID" run "$M" -o empty_crack --quiet "${empty[@]}" --set 'peridynamics.adaptive={threshold: 1, margin: 0}' \
  --set analysis.dynamic.duration=1.35e-5 && ok || bad "run: empty start, pre-crack"
"$CUPID" run fixed.yaml -o fixed_4060 --quiet --set 'peridynamics.regions=[{x: [0, 10], y: [40, 60], z: [0, 10]}]' \
  --set 'coupling.arlequin.overlap=[{y: [40, 45]}, {y: [55, 60]}]' --set analysis.dynamic.duration=1.35e-5 \
  && ok || bad "run: fixed [40, 60]"
"$CUPID" run "$M" -o empty --quiet "${empty[@]}" --set 'peridynamics.precracks=[]' && ok || bad "run: empty start"

"$PY" - <<'PY' && ok || bad "adaptive zones in dynamics"
import csv
from adaptive_rows import summary, conversions

def table(d, f, drop=()):
    with open(d + "/" + f) as h:
        return [{k: v for k, v in r.items() if k not in drop} for r in csv.DictReader(h)]

# 1
assert summary("never")["adaptive"]["conversions"] == []
for f in ("energies.csv", "damage.csv", "history.csv"):
    assert table("never", f, ("conversion_added", "pd_nodes")) == table("fixed_short", f), f
print("1. never fires: energies.csv, damage.csv and history.csv of the fixed zone to the bit")
# 2
conv = lambda d: conversions(d, "step", "y_from", "y_to", "pd_nodes", "trigger")
c = conv("grow")
assert c == [(320, 60, 70, 4000, "strain"), (500, 35, 40, 4500, "stretch in an overlap"),
             (560, 30, 35, 5000, "stretch in an overlap")], c
s = summary("grow")
nodes = {int(r["step"]): int(r["pd_nodes"]) for r in table("grow", "damage.csv")}
assert nodes[320] == 3000 and nodes[360] == 4000 and nodes[560] == 4500 and nodes[600] == 5000
e = table("grow", "energies.csv")
booked = float(e[-1]["conversion_added"])
each = sum(x["energy"] for x in s["adaptive"]["conversions"])
assert abs(booked - each) <= 1e-9 * abs(each), (booked, each)  # the csv's 11 digits
level = max(float(r["kinetic"]) + float(r["strain"]) for r in e)
worst = max(abs(float(r["balance"])) for r in e)
rel, rel_fixed = s["dynamic"]["max_energy_balance_relative"], summary("fixed")["dynamic"]["max_energy_balance_relative"]
print("2. conversions %s; balance %.2e of the run's energy (fixed zone %.2e, bound 5e-5); the "
      "conversions added %.4g (%.1e of %.4g), %.0f times the worst balance %.2e"
      % ([x[0] for x in c], rel, rel_fixed, booked, abs(booked) / level, level, abs(booked) / worst, worst))
assert rel <= 5e-5 and rel_fixed <= 5e-5
assert abs(booked) >= 50 * worst
# 3
h, rho, v0 = 1.0, 2.44e-9, 1.0e4
for x in summary("moving")["adaptive"]["conversions"]:
    carried = 0.5 * x["added_nodes"] * h ** 3 * rho * v0 ** 2
    print("3. moving: the conversion at step %d added %.4g; its new nodes carry about %.4g"
          % (x["step"], x["energy"], carried))
    assert abs(x["energy"]) <= 0.1 * carried
assert len(summary("moving")["adaptive"]["conversions"]) >= 1
# 4
assert conv("grow_t1") == c
print("4. one thread: the same conversions")
# 6
assert conversions("empty_crack", "step", "y_from", "y_to") == [(0, 45, 55)]
for f in ("energies.csv", "damage.csv", "history.csv"):
    assert table("empty_crack", f, ("conversion_added", "pd_nodes")) == table("fixed_4060", f), f
s = summary("empty")
c = conv("empty")
assert c[0][:4] == (320, 65, 70, 1500) and c[0][4] == "strain" and len(c) == 8, c
e = table("empty", "energies.csv")
each = sum(x["energy"] for x in s["adaptive"]["conversions"])
assert abs(float(e[-1]["conversion_added"]) - each) <= 1e-9 * abs(each)
assert s["dynamic"]["max_energy_balance_relative"] <= 1e-4
print("6. empty start: the pre-crack's zone = the fixed [40, 60] to the bit; without it %d "
      "conversions from step %d, %.4g booked, balance %.2e"
      % (len(c), c[0][0], each, s["dynamic"]["max_energy_balance_relative"]))
PY

expect 2 "the dynamic run stopped at step 320 \(t = 8e-06\): the adaptive zone would grow to 4000 PD nodes, over peridynamics.adaptive.max_nodes = 3800" -- \
  "$CUPID" run "$M" -o capped --set 'peridynamics.adaptive.max_nodes=3800'
[ -f capped/energies.csv ] && [ "$(tail -1 capped/energies.csv | cut -d, -f2)" = 320 ] && ok \
  || bad "capped: the time series up to step 320"
expect 2 "the dynamic run stopped at step 320 \(t = 8e-06\): the adaptive zone would grow to 1500 PD nodes" -- \
  "$CUPID" run "$M" -o capped_empty --set 'peridynamics.regions=[]' --set 'coupling.arlequin.overlap=[]' \
  --set 'peridynamics.precracks=[]' --set output.vtu=true --set 'peridynamics.adaptive.max_nodes=1000'
expect 1 "peridynamics.adaptive.every: .every. is the time steps between two tests of the trigger in dynamics" -- \
  "$CUPID" check "$SRC/tests/models/adaptive/senb.yaml" --set 'peridynamics.adaptive={every: 10}'
finish fracture_adaptive_dynamic
