#!/usr/bin/env bash
# Shapes and holes on PD slabs under mpirun (issue 35; src/pd/grid.c counts a slab's z layers
# by the same cell test as the whole grid, and src/problem/pd_bc.c sums a traction's loaded
# faces over the ranks before scaling them to the true section): the rod of
# verification.pd_shapes (a cylinder along y, its end face cut by the slabs) and the plate with
# a hole of examples/geometry on 2 and 3 ranks give the direct run's node count and load
# exactly and its point displacements to 1e-8 (the matrix-free CG's tolerance; measured 5e-14 to
# 1e-13); the rod with cut cells (`partial_volume: exact`) on 2 ranks also gives the direct
# run's nodes' volume (1e-12: each slab computes its cells' volumes from the geometry).
# Skipped (77) without PETSc. ~20 s on 2 cores.
. "$(dirname "$0")/../tools/mpi_checks.sh"
R=$SRC/tests/models/shapes/rod.yaml
P=$SRC/examples/geometry/plate_hole.yaml
rod_points=(--set 'output.points=[{name: a, at: [0.5, 20.5, 0.5]}, {name: b, at: [3.5, 59.5, 0.5]}]')

"$CUPID" run "$R" -o rod1 --quiet --solver direct "${rod_points[@]}" && ok || bad "the rod, direct"
"$CUPID" run "$P" -o plate1 --quiet --solver direct && ok || bad "the plate, direct"
"$CUPID" run "$R" -o rodcut1 --quiet --solver direct "${rod_points[@]}" \
  --set peridynamics.partial_volume=exact && ok || bad "the rod with cut cells, direct"
"$MPIEXEC" -n 2 "$CUPID" run "$R" -o rodcut2 --quiet "${rod_points[@]}" \
  --set peridynamics.partial_volume=exact && ok || bad "the rod with cut cells on 2 ranks"
for n in 2 3; do
  "$MPIEXEC" -n $n "$CUPID" run "$R" -o "rod$n" --quiet "${rod_points[@]}" && ok || bad "the rod on $n ranks"
  "$MPIEXEC" -n $n "$CUPID" run "$P" -o "plate$n" --quiet && ok || bad "the plate on $n ranks"
done
"$PY" - <<'PY' && ok || bad "the slabs against the direct runs"
import json
for name in ("rod", "plate", "rodcut"):
    ref = json.load(open(name + "1/summary.json"))
    pr = {p["name"]: p for p in ref["points"]}
    for n in ((2,) if name == "rodcut" else (2, 3)):
        s = json.load(open("%s%d/summary.json" % (name, n)))
        assert s["counts"]["pd_nodes"] == ref["counts"]["pd_nodes"], (name, n)
        assert abs(s["applied_load_sum"][1] - ref["applied_load_sum"][1]) <= 1e-12 * abs(ref["applied_load_sum"][1]), (name, n)
        worst = max(abs(p["uy"] - pr[p["name"]]["uy"]) / abs(pr[p["name"]]["uy"]) for p in s["points"])
        print("%s on %d ranks: %d nodes, load %.6f N, displacements within %.1e of the direct run"
              % (name, n, s["counts"]["pd_nodes"], s["applied_load_sum"][1], worst))
        assert worst <= 1e-8, (name, n, worst)
        assert abs(s["pd_volume"] - ref["pd_volume"]) <= 1e-12 * ref["pd_volume"], (name, n)
PY
finish mpi_shapes
