#!/usr/bin/env bash
# Adaptive PD zones on PD slabs under mpirun (issue 37: "grow inside the slabs"): the coarse
# SENB of tests/models/adaptive/senb.yaml (PD on [35, 55], 3 z layers) on the PETSc engine's
# matrix-free growth, one process against 2 and 3 slabs. Each rank keeps the z layers of its
# first slab as the zone grows along y (pd.slab_window), so each old node, halo included, has
# its place in the new slab of the same rank; the trigger reads the bonds and the damage of the
# nodes each rank owns, and the ranks agree on the marks.
#  1. the trigger at 0.1 s0 within [20, 70]: the zone grows away from the pre-crack at set-up,
#     then by its overlaps' stretch at steps 6 and 7 to [20, 70] (1080 nodes); on 2 slabs the
#     same conversions, the same broken bonds in every row, the reactions and the load point
#     within 1e-8 of the largest (each solve stops at a relative residual of 1e-10),
#     adaptive.pvd written (measured on 3 slabs too: 2.6e-10, 80 s oversubscribed);
#  2. a linear model (critical stretch 1, a pull) converted at step 9 on 2 and 3 slabs, and with
#     fictitious nodes (PD on [25, 65]; two conversions at step 7 by the coupling zone's
#     bonds): their rows within 1e-8 of the one process's;
#  3. refused with a model error naming the line: a zone that starts empty, a zone over part
#     of the section (tests/models/adaptive/wall.yaml), and --replicate.
# Skipped (77) without PETSc. About 60 s on 2 cores.
. "$(dirname "$0")/../tools/mpi_checks.sh"
export PYTHONPATH=$SRC/tests/tools  # adaptive_rows.py
M=$SRC/tests/models/adaptive/senb.yaml
grow=(--quiet --set 'peridynamics.adaptive={threshold: 0.1, margin: 1, within: {y: [20, 70]}}'
      --set output.vtu=true)
linear=(--quiet --set 'peridynamics.fracture={criterion: stretch, critical_stretch: 1}'
        --set analysis.steps=10 --set 'loads=[{traction: {y: 90, value: [0, 0.01, 0]}}]'
        --set 'peridynamics.adaptive={threshold: 3e-4, margin: 0}')
fict=(--set 'coupling={method: fictitious}' --set 'peridynamics.regions=[{x: [0, 20], y: [25, 65], z: [0, 5]}]'
      --set 'peridynamics.adaptive={threshold: 5e-5, margin: 0, within: {y: [15, 75]}}')

"$CUPID" run "$M" -o one "${grow[@]}" --solver petsc && ok || bad "one process"
"$MPIEXEC" -n 2 "$CUPID" run "$M" -o slab2 "${grow[@]}" && ok || bad "2 slabs"
"$CUPID" run "$M" -o lin1 "${linear[@]}" --solver petsc && ok || bad "linear, one process"
"$MPIEXEC" -n 2 "$CUPID" run "$M" -o lin2 "${linear[@]}" && ok || bad "linear, 2 slabs"
"$MPIEXEC" -n 3 "$CUPID" run "$M" -o lin3 "${linear[@]}" && ok || bad "linear, 3 slabs"
"$CUPID" run "$M" -o fict1 "${linear[@]}" "${fict[@]}" --solver petsc && ok || bad "fictitious, one process"
"$MPIEXEC" -n 2 "$CUPID" run "$M" -o fict2 "${linear[@]}" "${fict[@]}" && ok || bad "fictitious, 2 slabs"

"$PY" - <<'PY' && ok || bad "slabs against one process"
import os
from adaptive_rows import rows, same, conversions
conv = lambda d: conversions(d, "step", "y_from", "y_to", "pd_nodes", "trigger")
c = conv("one")
o = "stretch in an overlap"
assert c == [(0, 35, 55, 648, "pre-crack near an overlap"), (6, 30, 35, 756, o), (6, 25, 30, 864, o),
             (7, 55, 60, 972, o), (7, 60, 65, 1080, o)], c
for d in ("slab2",):
    assert conv(d) == c, (d, conv(d))
    assert [r["broken_bonds"] for r in rows(d)] == [r["broken_bonds"] for r in rows("one")], d
    assert [r["pd_nodes"] for r in rows(d)] == [r["pd_nodes"] for r in rows("one")], d
    same(d, "one", 1e-8, None, "1. %s against one process" % d)
    assert os.path.exists(d + "/adaptive.pvd"), d
assert conv("lin2") == conv("lin1") == conv("lin3") and len(conv("lin1")) == 1, conv("lin1")
same("lin2", "lin1", 1e-8, None, "2. linear, 2 slabs against one process")
same("lin3", "lin1", 1e-8, None, "2. linear, 3 slabs (a middle rank: halos on both sides)")
z = "stretch in the coupling zone"
assert conv("fict1") == [(7, 20, 70, 1080, z), (7, 15, 75, 1296, z)], conv("fict1")
assert conv("fict2") == conv("fict1"), conv("fict2")
same("fict2", "fict1", 1e-8, None, "2. fictitious nodes, 2 slabs against one process")
PY

expect 1 "senb.yaml:[0-9]+:[0-9]+: peridynamics.adaptive: under mpirun an adaptive zone grows on PD slabs" -- \
  "$MPIEXEC" -n 2 "$CUPID" run "$M" -o empty --set 'peridynamics.regions=[]' \
  --set 'coupling.arlequin.overlap=[]' --set 'peridynamics.precracks=[]'
expect 1 "wall.yaml:[0-9]+:[0-9]+: peridynamics.adaptive: under mpirun an adaptive zone grows over the whole section" -- \
  "$MPIEXEC" -n 2 "$CUPID" run "$SRC/tests/models/adaptive/wall.yaml" -o wall
expect 1 "under mpirun an adaptive zone grows on PD slabs" -- \
  "$MPIEXEC" -n 2 "$CUPID" run "$M" -o replicated --replicate
finish mpi_fracture_adaptive
