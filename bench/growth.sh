#!/usr/bin/env bash
# Quasi-static crack growth (issue 17, item 3): the re-solves after bonds break with the last
# factorisation downdated by the broken bonds (the default), by CG preconditioned by the last
# factorisation without downdates (CUPID_GROWTH_RESOLVE=krylov), and with a new factorisation
# every time (CUPID_GROWTH_RESOLVE=factor). The model: the notched plate of
# tests/models/growth/plate.yaml at twice the size (24 x 48 x 3 mm, h = 1 mm: 3,456 nodes,
# bond-based, notch x in [0, 6] at y = 24), the top layers pulled 0.04 mm in 10 load steps,
# every bond over its limit breaking at once (per_iteration: all). Prints, for each way,
# the whole run's seconds, the solves, factorisations, downdates (and the bonds in them), CG
# solves and iterations, the seconds in factorisations, downdates and CG, and the broken bonds
# (which must agree). Reported figures,
# not a timed test.
#
#   bench/growth.sh        needs build/cupid (scripts/build.sh); the second table
#                          build-petsc/cupid (scripts/build.sh --with-petsc)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cupid=$root/build/cupid
[ -x "$cupid" ] || { echo "needs $cupid (scripts/build.sh)"; exit 2; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
sed -e 's/x: \[0, 12\], y: \[0, 24\], z: \[0, 2\]/x: [0, 24], y: [0, 48], z: [0, 3]/' \
    -e 's/at: 12, x: \[0, 3\], z: \[0, 2\]/at: 24, x: [0, 6], z: [0, 3]/' \
    -e 's/y: \[21, 24\]/y: [45, 48]/' -e 's/value: \[0, 0.02, 0\]/value: [0, 0.04, 0]/' \
    -e 's/at: \[6, 22.5, 1\]/at: [12, 46.5, 1.5]/' "$root/tests/models/growth/plate.yaml" > plate.yaml
echo "| re-solves | run s | solves | factorisations | downdates (bonds) | CG solves | CG iterations | factorisation s | downdate s | CG s | broken bonds |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for how in downdate krylov factor; do
  t0=$(date +%s.%N)
  CUPID_GROWTH_RESOLVE=$how "$cupid" run plate.yaml -o "$how" --quiet
  t1=$(date +%s.%N)
  python3 - "$how" "$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')" <<'PY'
import json, sys
f = json.load(open(sys.argv[1] + "/summary.json"))["fracture"]
s = f["solves"]
print(f"| {s['resolve']} | {sys.argv[2]} | {s['solves']} | {s['factorisations']} | "
      f"{s['downdates']} ({s['downdate_columns']}) | {s['cg_solves']} | {s['cg_iterations']} | "
      f"{s['factorisation_s']:.1f} | {s['downdate_s']:.1f} | {s['cg_s']:.1f} | {f['broken_bonds']} |")
PY
done

# On PD slabs under mpirun (issue 17, item 5): the same plate turned along z (the axis the
# slabs cut), the direct path with its downdates on one process (1 and 2 threads), the kept
# matrix-free CG + GAMG of growth_matrix_free.c on 2 ranks of one thread (slabs) and on one
# process (--solver petsc), and the PETSc engine's CG + GAMG on the assembled K, set up afresh
# for every re-solve (--solver petsc --assembled). Needs build-petsc/cupid
# (scripts/build.sh --with-petsc); skipped without it.
pcupid=$root/build-petsc/cupid
mpiexec=$(command -v mpiexec || true)
if [ -x "$pcupid" ] && [ -n "$mpiexec" ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  export OMPI_MCA_rmaps_base_oversubscribe=1
  sed -e 's/x: \[0, 12\], y: \[0, 2\], z: \[0, 24\]/x: [0, 24], y: [0, 3], z: [0, 48]/' \
      -e 's/at: 12, x: \[0, 3\], y: \[0, 2\]/at: 24, x: [0, 6], y: [0, 3]/' \
      -e 's/z: \[21, 24\]/z: [45, 48]/' -e 's/value: \[0, 0, 0.02\]/value: [0, 0, 0.04]/' \
      -e 's/at: \[6, 1, 22.5\]/at: [12, 1.5, 46.5]/' "$root/tests/models/growth/plate_z.yaml" > plate_z.yaml
  echo
  echo "| path (plate along z) | ranks x threads | run s | solves | CG iterations | set-up s | solve s | broken bonds |"
  echo "|---|---|---|---|---|---|---|---|"
  for run in "direct 1 1" "direct 1 2" "slabs 2 1" "petsc 1 1" "assembled 1 1"; do
    set -- $run
    t0=$(date +%s.%N)
    case $1 in
      direct) OMP_NUM_THREADS=$3 "$pcupid" run plate_z.yaml -o "z$1$2$3" --quiet --solver direct ;;
      slabs) OMP_NUM_THREADS=$3 "$mpiexec" -n "$2" "$pcupid" run plate_z.yaml -o "z$1$2$3" --quiet ;;
      petsc) OMP_NUM_THREADS=$3 "$pcupid" run plate_z.yaml -o "z$1$2$3" --quiet --solver petsc ;;
      assembled) OMP_NUM_THREADS=$3 "$pcupid" run plate_z.yaml -o "z$1$2$3" --quiet --solver petsc --assembled ;;
    esac
    t1=$(date +%s.%N)
    python3 - "z$1$2$3" "$1" "$2 x $3" "$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')" <<'PY'
import json, sys
f = json.load(open(sys.argv[1] + "/summary.json"))["fracture"]
s = f["solves"]
print(f"| {sys.argv[2]} ({s['resolve']}) | {sys.argv[3]} | {sys.argv[4]} | {s['solves']} | "
      f"{s['cg_iterations']} | {s['factorisation_s']:.1f} | {s['cg_s'] + s['downdate_s']:.1f} | "
      f"{f['broken_bonds']} |")
PY
  done
fi
