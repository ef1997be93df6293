#!/usr/bin/env bash
# Adaptive PD zones over part of the section (issue 37) on the thin wall of
# tests/models/adaptive/wall.yaml (PD on z [4, 16] of its 20 mm, bent in its plane; linear):
#  1. a trigger that never fires gives the fixed zone's results to the bit;
#  2. the zone grows at step 6 by the beam's strain at the tension edge (z [0, 4] near the
#     clamp: the element between it and the core joins too, an overlap cannot sit between two
#     parts of the core) and at step 10 by its overlap's bonds along y; the rows of each step
#     equal those of the model that had the zone of that step from the start (written from
#     summary.json's regions and overlaps, bounded overlaps with `along` included), to 1e-9;
#  3. 1 and 2 threads convert the same units at the same steps; PETSc's matrix-free path
#     where the build has it;
#  4. an overlap across the section two section elements wide is refused, naming its line, and
#     so is a beam element that may turn and is longer than 10 horizons;
#  5. a small C-beam (tests/models/adaptive/cbeam.yaml) bent about x: the zone runs down its
#     web, takes the web's corner element (its far face is free) and steps into the flange
#     beyond, whose first element is the next overlap (along x, a bounded slab); four
#     conversions, each step's rows those of the model that had that step's zone from the
#     start, to 1e-9.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, expect, finish
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
export PYTHONPATH=$SRC/tests/tools  # adaptive_rows.py
M=$SRC/tests/models/adaptive/wall.yaml
grep -v "^  adaptive:" "$M" > fixed.yaml

"$CUPID" run "$M" -o never --quiet --set 'peridynamics.adaptive.threshold=1' && ok || bad "run: never fires"
"$CUPID" run fixed.yaml -o fixed --quiet && ok || bad "run: fixed zone"
"$CUPID" run "$M" -o grown --quiet && ok || bad "run: grown"
"$CUPID" run "$M" -o grown9 --quiet --set analysis.steps=9 --set 'loads=[{traction: {y: 60, value: [0, 0, 0.009]}}]' \
  && ok || bad "run: grown, 9 steps (the zone after the first conversion)"
OMP_NUM_THREADS=1 "$CUPID" run "$M" -o grown_t1 --quiet --threads 1 && ok || bad "run: one thread"
petsc=0
if "$CUPID" --version 2>&1 | grep -q petsc; then
  petsc=1
  "$CUPID" run "$M" -o grown_petsc --quiet --solver petsc && ok || bad "run: petsc"
fi
# the models that had each zone from the start
for d in grown9 grown; do
  mapfile -t z < <("$PY" "$SRC/tests/tools/adaptive_rows.py" zone "$d")
  "$CUPID" run fixed.yaml -o "fixed_$d" --quiet --set "${z[0]}" --set "${z[1]}" && ok || bad "run: the zone of $d from the start"
done

"$PY" - "$petsc" <<'PY' && ok || bad "adaptive results over part of the section against the fixed zones"
import sys
from adaptive_rows import rows, summary, same, without_nodes, conversions
petsc = sys.argv[1] == "1"
conv = lambda d: conversions(d, "step", "y_from", "y_to", "z_from", "z_to", "pd_nodes")
# 1: to the bit
assert conv("never") == []
assert without_nodes("never") == without_nodes("fixed")
print("1. never fires: the fixed zone's rows to the bit")
# 2: two conversions
c = conv("grown")
assert c == [(6, 20, 35, 0, 12, 800), (10, 35, 40, 0, 12, 960)], c
a = summary("grown")["adaptive"]
assert a["regions"] == [{"x": [0, 2], "y": [15, 45], "z": [0, 12]}, {"x": [0, 2], "y": [15, 45], "z": [12, 16]}], a["regions"]
assert a["overlaps"] == [{"x": [0, 2], "y": [15, 45], "z": [12, 16], "along": "z"}, {"y": [15, 20]}, {"y": [40, 45]}], a["overlaps"]
assert [int(r["pd_nodes"]) for r in rows("grown")] == [480] * 5 + [800] * 4 + [960]
same("grown", "fixed", 1e-9, set(range(1, 6)), "2. steps 1-5 against the initial zone")
assert conv("grown9") == c[:1], conv("grown9")
same("grown", "fixed_grown9", 1e-9, set(range(6, 10)), "2. steps 6-9 against the zone of step 6")
same("grown", "fixed_grown", 1e-9, {10}, "2. step 10 against the final zone")
# 3: threads, PETSc
assert conv("grown_t1") == c
same("grown_t1", "grown", 1e-9, what="3. one thread against two")
if petsc:
    assert conv("grown_petsc") == c, conv("grown_petsc")
    same("grown_petsc", "grown", 1e-5, what="3. PETSc matrix-free against direct")
PY

# 5. the small C-beam: the zone runs down the web, takes its corner and steps into each
# flange; the runs stopped after each conversion give each zone, run again from the start
C=$SRC/tests/models/adaptive/cbeam.yaml
grep -v "^  adaptive:" "$C" > cfixed.yaml
"$CUPID" run "$C" -o c10 --quiet && ok || bad "run: C-beam, grown"
for k in 6 7 9; do
  "$CUPID" run "$C" -o "c$k" --quiet --set analysis.steps=$k \
    --set "loads=[{traction: {y: 40, value: [0, 0, 0.00$k]}}]" && ok || bad "run: C-beam, $k steps"
done
"$CUPID" run cfixed.yaml -o cfixed --quiet && ok || bad "run: C-beam, fixed zone"
for k in 6 7 9 10; do
  mapfile -t z < <("$PY" "$SRC/tests/tools/adaptive_rows.py" zone "c$k")
  "$CUPID" run cfixed.yaml -o "cfixed$k" --quiet --set "${z[0]}" --set "${z[1]}" && ok || bad "run: the C-beam's zone of c$k from the start"
done
"$PY" - <<'PY' && ok || bad "the C-beam's rows against its fixed zones"
from adaptive_rows import summary, same, conversions
c = conversions("c10", "step", "x_from", "x_to", "z_from", "z_to", "pd_nodes")
assert c == [(5, 0, 2, -10, -4, 880), (7, 2, 10, -10, -8, 1040), (8, 0, 2, 4, 10, 1280),
             (10, 2, 10, 8, 10, 1440)], c
# the final zone: the whole section over y [15, 25], no ring left
a = summary("c10")["adaptive"]
assert a["overlaps"] == [{"y": [10, 15]}, {"y": [25, 30]}], a["overlaps"]
for ref, steps in (("cfixed", range(1, 5)), ("cfixed6", range(5, 7)), ("cfixed7", [7]),
                   ("cfixed9", [8, 9]), ("cfixed10", [10])):
    same("c10", ref, 1e-9, set(steps), "5. C-beam steps %s against %s" % (list(steps), ref))
PY

# 4. refusals
expect 1 "peridynamics.regions\[0\]: with adaptive an overlap across the section is one section element wide" -- \
  "$CUPID" check "$M" --set 'peridynamics.regions=[{x: [0, 2], y: [20, 40], z: [0, 16]}]' \
  --set 'coupling.arlequin.overlap=[{y: [20, 25]}, {y: [35, 40]}, {z: [8, 16]}]'
# a beam element that may turn and is longer than 10 horizons (20 mm, 13.3 horizons)
expect 1 "the beam element on y in \[0, 20\] may turn to PD and is 20 long, 13.3 horizons" -- \
  "$CUPID" check "$M" --set 'beam.axis={y: [0, 20, 40, 60], elements: [1, 4, 1], type: B2}' \
  --set 'peridynamics.adaptive={threshold: 1e-4}'
finish verification.fracture_adaptive_section
