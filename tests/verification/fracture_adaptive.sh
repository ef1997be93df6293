#!/usr/bin/env bash
# Adaptive PD zones (issue 37) on the coarse SENB of tests/models/adaptive/senb.yaml (h = 5/3,
# CUF beam of 5 mm elements, PD on [35, 55] joined by Arlequin):
#  1. a trigger that never fires gives the fixed zone's results to the bit (damage.csv's every
#     column but pd_nodes, the peaks);
#  2. a zone that grew away from the pre-crack (margin 1: at set-up, "step 0") gives the results
#     of the model that had that zone ([30, 60]) from the start, to 1e-10 (the same lattice, the
#     same crack, the same peak);
#  3. on a linear model (critical stretch 1: nothing breaks; a pull on the beam's end, whose
#     DOFs move when PD nodes are added before them), a zone that the trigger grew at step 9
#     (an overlap's bonds at the threshold) gives from then on the rows of the model that had
#     the final zone from the start, and before it the initial zone's, to 1e-9 (each solve is
#     linear: the conversion must leave nothing of the old layout behind);
#  4. 1 and 2 threads convert the same elements at the same steps;
#  5. where the build has PETSc, its matrix-free path converts as the direct one, and its rows
#     agree to the solver's tolerance;
#  6. max_nodes stops the run (exit 2, results written), and the refusals name their line;
#  7. a zone that starts empty (regions: []), on the linear model: the rows before its first
#     conversion are the beam's alone, those after each conversion the fixed zone's, to 1e-9
#     (its overlaps span a horizon, 5.025: two beam elements of 5 mm);
#  8. a notched beam that starts empty grows over its pre-crack at set-up and then runs as the
#     model that had that zone from the start (1e-10).
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, expect, finish
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
M=$SRC/tests/models/adaptive/senb.yaml
# the model without its adaptive key (a fixed zone); one whose zone starts empty; the beam alone
grep -v "^  adaptive:" "$M" > fixed.yaml
sed -e '/^    - {x: \[0, 20\], y: \[35, 55\]/d' -e 's/^  regions:$/  regions: []/' \
    -e 's/overlap: \[{y: \[35, 40\]}, {y: \[50, 55\]}\]/overlap: []/' "$M" > empty_notched.yaml
sed -e '/^  precracks:/,+1d' empty_notched.yaml > empty.yaml
sed -e '/^peridynamics:/,/^constraints:/{/^constraints:/!d}' "$M" > beam.yaml
zone() { # --set arguments of the fixed zone [$1, $2] with overlaps $3 wide
  zone_args=(--set "peridynamics.regions=[{x: [0, 20], y: [$1, $2], z: [0, 5]}]"
             --set "coupling.arlequin.overlap=[{y: [$1, $(($1 + $3))]}, {y: [$(($2 - $3)), $2]}]")
}
zone 30 60 5; zone30=("${zone_args[@]}")
zone 30 55 5; zone3055=("${zone_args[@]}")
zone 20 70 10; zone20=("${zone_args[@]}")
zone 15 75 10; zone15=("${zone_args[@]}")
# (with a pull on the beam's end too: loads on the beam's DOFs, which move when PD nodes are
# added before them)
pull=(--set 'loads=[{traction: {y: 90, value: [0, 0.01, 0]}}]')
linear=(--set 'peridynamics.fracture={criterion: stretch, critical_stretch: 1}' --set analysis.steps=10 "${pull[@]}")

# 1. never fires: margin 0 (the pre-crack's cut bonds lie in the core), threshold 1
"$CUPID" run "$M" -o never --quiet --set 'peridynamics.adaptive={threshold: 1, margin: 0}' && ok || bad "run: never fires"
"$CUPID" run fixed.yaml -o fixed --quiet && ok || bad "run: fixed zone"
# 2. grown at set-up against the zone [30, 60] from the start
"$CUPID" run "$M" -o grown --quiet && ok || bad "run: grown at set-up"
"$CUPID" run fixed.yaml -o fixed30 --quiet "${zone30[@]}" && ok || bad "run: fixed zone [30, 60]"
# 3. linear, grown at step 9 (the lower overlap's bonds reach the threshold: the pull adds to
# the bending there)
lin_at=(--set 'peridynamics.adaptive={threshold: 3e-4, margin: 0}')
"$CUPID" run "$M" -o lin --quiet "${linear[@]}" "${lin_at[@]}" && ok || bad "run: linear, grown"
"$CUPID" run fixed.yaml -o lin_fixed --quiet "${linear[@]}" && ok || bad "run: linear, fixed zone"
"$CUPID" run fixed.yaml -o lin_fixed3055 --quiet "${linear[@]}" "${zone3055[@]}" && ok || bad "run: linear, zone [30, 55]"
# 4. one thread
OMP_NUM_THREADS=1 "$CUPID" run "$M" -o lin_t1 --quiet --threads 1 "${linear[@]}" "${lin_at[@]}" \
  && ok || bad "run: linear, one thread"
# 5. PETSc's matrix-free path
petsc=0
if "$CUPID" --version 2>&1 | grep -q petsc; then
  petsc=1
  "$CUPID" run "$M" -o lin_petsc --quiet --solver petsc "${linear[@]}" "${lin_at[@]}" \
    && ok || bad "run: linear, petsc"
fi

# 7. starts empty, linear: the strain turns [40, 50] at step 8; then the overlaps' bonds (their
# stretch past the beam's strain next to the core) turn [30, 40] and [50, 60] at step 8 and
# [25, 30] and [60, 65] at step 9
empty_lin=(--set 'peridynamics.adaptive={threshold: 3e-4, margin: 0, within: {y: [15, 75]}}')
"$CUPID" run empty.yaml -o empty --quiet "${linear[@]}" "${empty_lin[@]}" && ok || bad "run: starts empty"
"$CUPID" run beam.yaml -o beam --quiet --set analysis.steps=10 "${pull[@]}" && ok || bad "run: the beam alone"
grep -v "^  precracks:\|^    - {normal: y" fixed.yaml > fixed_plain.yaml
"$CUPID" run fixed_plain.yaml -o plain20 --quiet "${linear[@]}" "${zone20[@]}" && ok || bad "run: [20, 70], no pre-crack"
"$CUPID" run fixed_plain.yaml -o plain15 --quiet "${linear[@]}" "${zone15[@]}" && ok || bad "run: [15, 75], no pre-crack"
# 8. starts empty, notched (margin 1: the pre-crack's reach and a margin, 2 horizons either side)
"$CUPID" run empty_notched.yaml -o empty_notched --quiet && ok || bad "run: notched, starts empty"
"$CUPID" run fixed.yaml -o fixed20 --quiet "${zone20[@]}" && ok || bad "run: fixed zone [20, 70]"

"$PY" - "$petsc" <<'PY' && ok || bad "adaptive results against the fixed zones"
import csv, json, sys
petsc = sys.argv[1] == "1"
def rows(d):
    import os
    name = "/damage.csv" if os.path.exists(d + "/damage.csv") else "/load_steps.csv"
    with open(d + name) as f:
        r = list(csv.DictReader(f))
    return r
def summary(d):
    return json.load(open(d + "/summary.json"))
def same(a, b, tol, cols=None, steps=None, what=""):
    ra, rb = rows(a), rows(b)
    assert len(ra) == len(rb), (what, len(ra), len(rb))
    cols = [c for c in (cols or rb[0].keys()) if c != "pd_nodes" and c in ra[0]]
    # each column against the largest value of its group (the reactions; the output point's
    # displacements): round-off about zero (a symmetric u_z) counts as such
    top = {c: max(abs(float(y[c])) for y in rb) for c in cols}
    group = lambda c: c.split("_")[0]
    scale = {c: max([top[d] for d in cols if group(d) == group(c)] + [1e-300]) for c in cols}
    worst = 0.0
    for x, y in zip(ra, rb):
        k = int(x["step"])
        if steps and k not in steps: continue
        for c in cols:
            u, v = float(x[c]), float(y[c])
            worst = max(worst, abs(u - v) / scale[c])
    print("%s: worst relative difference %.2e (bound %.0e)" % (what, worst, tol))
    assert worst <= tol, what
conv = lambda d: [(c["step"], c["y_from"], c["y_to"], c["pd_nodes"]) for c in summary(d)["adaptive"]["conversions"]]
# 1: to the bit, no conversion
assert conv("never") == [], conv("never")
same("never", "fixed", 0.0, what="1. never fires against the fixed zone")
assert summary("never")["fracture"]["peak_reactions"] == summary("fixed")["fracture"]["peak_reactions"]
# 2: grown at set-up to [30, 60]
assert conv("grown") == [(0, 35, 55, 648)], conv("grown")
assert summary("grown")["adaptive"]["regions"] == [{"x": [0, 20], "y": [30, 60], "z": [0, 5]}]
same("grown", "fixed30", 1e-10, what="2. grown at set-up against [30, 60] from the start")
assert summary("grown")["fracture"]["broken_bonds"] == summary("fixed30")["fracture"]["broken_bonds"]
assert summary("grown")["counts"]["pd_nodes"] == summary("fixed30")["counts"]["pd_nodes"] == 648
# 3: linear, grown at step 9 (the lower side)
c = conv("lin")
assert c == [(9, 35, 40, 540)], c
cols = [k for k in rows("lin")[0] if k.startswith("reaction") or k.startswith("load_u")]
same("lin", "lin_fixed", 1e-9, cols, set(range(1, 9)), "3. linear, steps 1-8 against the initial zone")
same("lin", "lin_fixed3055", 1e-9, cols, {9, 10}, "3. linear, steps 9-10 against the final zone")
assert [int(r["pd_nodes"]) for r in rows("lin")] == [432] * 8 + [540] * 2
# adaptive.pvd: the zone before each conversion and at the end
import re
pvd = open("lin/adaptive.pvd").read()
frames = re.findall(r'timestep="([^"]+)"[^>]*file="(adaptive_pd_\d+\.vtu)"', pvd)
points = [(float(t), int(re.search(r'NumberOfPoints="(\d+)"', open("lin/" + f).read()).group(1)))
          for t, f in frames]
assert points == [(0.9, 432), (1.0, 540)], points
# 4: threads
assert conv("lin_t1") == c, (conv("lin_t1"), c)
same("lin_t1", "lin", 1e-9, cols, what="4. one thread against two")
# 7: starts empty
ce = conv("empty")
assert ce == [(8, 40, 50, 648), (8, 35, 55, 864), (8, 30, 60, 1080), (9, 25, 65, 1296)], ce
assert summary("empty")["adaptive"]["initial_pd_nodes"] == 0
assert summary("empty")["adaptive"]["overlaps"] == [{"y": [15, 25]}, {"y": [65, 75]}]
same("empty", "beam", 1e-9, cols, set(range(1, 8)), "7. starts empty, steps 1-7 against the beam alone")
same("empty", "plain20", 1e-9, cols, {8}, "7. starts empty, step 8 against [20, 70]")
same("empty", "plain15", 1e-9, cols, {9, 10}, "7. starts empty, steps 9-10 against [15, 75]")
# 8: notched, starts empty
assert conv("empty_notched") == [(0, 30, 60, 1080)], conv("empty_notched")
same("empty_notched", "fixed20", 1e-10, what="8. notched, starts empty, against [20, 70] from the start")
assert summary("empty_notched")["fracture"]["broken_bonds"] == summary("fixed20")["fracture"]["broken_bonds"]
# 5: PETSc
if petsc:
    assert conv("lin_petsc") == c, (conv("lin_petsc"), c)
    same("lin_petsc", "lin", 1e-5, cols, what="5. PETSc matrix-free against direct")
PY

# 6. max_nodes: the run stops at the conversion that would pass it, with the steps before
expect 2 "adaptive zone would grow to 540 PD nodes, over peridynamics.adaptive.max_nodes = 500" -- \
  "$CUPID" run "$M" -o capped "${linear[@]}" --set 'peridynamics.adaptive={threshold: 3e-4, margin: 0, max_nodes: 500}'
[ "$(tail -n +2 capped/damage.csv | wc -l)" -eq 8 ] && ok || bad "max_nodes: 8 steps written before the stop"
# cupid check: the settings and the largest zone within allows
out=$("$CUPID" check "$M" --set 'peridynamics.adaptive={threshold: 0.5, within: {y: [20, 70]}}' 2>&1)
grep -q "adaptive: threshold 0.5 x s0" <<<"$out" && grep -q "the largest \`within\` allows: 1080 PD nodes" <<<"$out" \
  && ok || { bad "cupid check's adaptive lines"; echo "$out" | grep adaptive; }
# refusals
expect 1 "adaptive zones grow with the coupling methods arlequin and fictitious.*method lagrange" -- "$CUPID" check "$M" --set 'coupling={method: lagrange}'
expect 1 "no beam element can turn to PD" -- "$CUPID" check "$M" --set 'peridynamics.adaptive={within: {y: [35, 55]}}'
expect 1 "senb.yaml:33:13: peridynamics.adaptive: model.exo" -- "$CUPID" check "$M" --set output.exodus=true
finish verification.fracture_adaptive
