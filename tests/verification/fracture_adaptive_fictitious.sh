#!/usr/bin/env bash
# Adaptive PD zones with paper 000's coupling by fictitious nodes (issue 37) on the coarse SENB
# of tests/models/adaptive/senb.yaml with PD on [25, 65] (the fictitious-node coupling zone, a
# fictitious FE element and a horizon inside each interface, must stay clear of the pre-crack
# at y = 45): the zone's region is its core (no overlaps), and the beam next to a zone turns
# by its strain or by the coupling zone's bonds across the interface.
#  1. a trigger that never fires gives the fixed zone's results to the bit;
#  2. on a linear model (critical stretch 1, a pull on the beam's end) the coupling zone's bonds
#     turn [20, 25] and [65, 70] at step 7 and then [15, 20] and [70, 75] (within [15, 75]):
#     steps 1-6 equal the initial zone's rows, steps 7-10 those of the model that had [15, 75]
#     from the start, to 1e-9 (each solve is linear);
#  3. 1 and 2 threads convert the same elements at the same steps; so does PETSc's matrix-free
#     path where the build has it (its rows to the solver's tolerance);
#  4. a zone over part of the section is refused with fictitious nodes, naming its line.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, expect, finish
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
export PYTHONPATH=$SRC/tests/tools  # adaptive_rows.py
M=$SRC/tests/models/adaptive/senb.yaml
grep -v "^  adaptive:" "$M" > fixed.yaml
fict=(--set 'coupling={method: fictitious}' --set 'peridynamics.regions=[{x: [0, 20], y: [25, 65], z: [0, 5]}]')
wide=(--set 'peridynamics.regions=[{x: [0, 20], y: [15, 75], z: [0, 5]}]')
pull=(--set 'loads=[{traction: {y: 90, value: [0, 0.01, 0]}}]')
linear=(--set 'peridynamics.fracture={criterion: stretch, critical_stretch: 1}' --set analysis.steps=10 "${pull[@]}")
lin_at=(--set 'peridynamics.adaptive={threshold: 5e-5, margin: 0, within: {y: [15, 75]}}')

"$CUPID" run "$M" -o never --quiet "${fict[@]}" --set 'peridynamics.adaptive={threshold: 1, margin: 0}' \
  && ok || bad "run: never fires"
"$CUPID" run fixed.yaml -o fixed --quiet "${fict[@]}" && ok || bad "run: fixed zone"
"$CUPID" run "$M" -o lin --quiet "${fict[@]}" "${linear[@]}" "${lin_at[@]}" && ok || bad "run: linear, grown"
OMP_NUM_THREADS=1 "$CUPID" run "$M" -o lin_t1 --quiet --threads 1 "${fict[@]}" "${linear[@]}" "${lin_at[@]}" \
  && ok || bad "run: linear, one thread"
petsc=0
if "$CUPID" --version 2>&1 | grep -q petsc; then
  petsc=1
  "$CUPID" run "$M" -o lin_petsc --quiet --solver petsc "${fict[@]}" "${linear[@]}" "${lin_at[@]}" \
    && ok || bad "run: linear, petsc"
fi
"$CUPID" run fixed.yaml -o lin_fixed --quiet "${fict[@]}" "${linear[@]}" && ok || bad "run: linear, [25, 65]"
"$CUPID" run fixed.yaml -o lin_wide --quiet "${fict[@]}" "${wide[@]}" "${linear[@]}" && ok || bad "run: linear, [15, 75]"

"$PY" - "$petsc" <<'PY' && ok || bad "adaptive results with fictitious nodes against the fixed zones"
import sys
from adaptive_rows import rows, summary, same, without_nodes, conversions
petsc = sys.argv[1] == "1"
conv = lambda d: conversions(d, "step", "y_from", "y_to", "pd_nodes", "trigger")
# 1
assert conv("never") == []
assert without_nodes("never") == without_nodes("fixed")
assert summary("never")["fracture"]["peak_reactions"] == summary("fixed")["fracture"]["peak_reactions"]
print("1. never fires: the fixed zone's rows and peak to the bit")
# 2
c = conv("lin")
z = "stretch in the coupling zone"
assert c == [(7, 20, 70, 1080, z), (7, 15, 75, 1296, z)], c
assert summary("lin")["adaptive"]["regions"] == [{"x": [0, 20], "y": [15, 75], "z": [0, 5]}]
assert summary("lin")["adaptive"]["overlaps"] == []
assert [int(r["pd_nodes"]) for r in rows("lin")] == [864] * 6 + [1296] * 4
same("lin", "lin_fixed", 1e-9, set(range(1, 7)), "2. steps 1-6 against [25, 65]")
same("lin", "lin_wide", 1e-9, set(range(7, 11)), "2. steps 7-10 against [15, 75]")
# 3
assert conv("lin_t1") == c
same("lin_t1", "lin", 1e-9, what="3. one thread against two")
if petsc:  # GMRES on the LU of a bond-based twin, to its tolerance
    assert conv("lin_petsc") == c, conv("lin_petsc")
    same("lin_petsc", "lin", 1e-5, what="3. PETSc matrix-free against direct")
PY

expect 1 "adaptive zones over part of the section grow with Arlequin's overlaps" -- "$CUPID" check "$M" \
  --set 'coupling={method: fictitious}' --set 'peridynamics.regions=[{x: [0, 10], y: [25, 65], z: [0, 5]}]'
finish verification.fracture_adaptive_fictitious
