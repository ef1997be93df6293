#!/usr/bin/env bash
# Quasi-static crack growth on the single-edge-notched beam of examples/fracture (issue 17,
# performance): the CUF beam with PD around the notch (senb_coupled.yaml, Arlequin) with each
# way of re-solving after bonds break, and its PD-only twin (senb_pd.yaml) with the default:
#   downdate  the last CHOLMOD factor downdated by the broken bonds (the default),
#   krylov    CG preconditioned by the last factor, renewed by operation counts,
#   factor    a new factorisation after every round of breaks,
#   petsc     the PETSc engine on one process, matrix-free: the kept CG with the Cholesky
#             factor of the bond-based twin (growth_matrix_free.c), needs build-petsc/cupid,
#   slabs     the same on 2 PD slabs under mpirun (2 ranks of one thread),
#   lagrange  the same beam coupled by Lagrange multipliers instead (issue 34), the default
#             re-solves,
#   fictitious  the same beam coupled by fictitious nodes (paper 000; issue 34, the default
#             balance: each interface balanced), the block factor (CHOLMOD of the PD block,
#             the beam's LU, growth_block.c) downdated by the broken bonds,
#   fictitious_slabs  the same on 2 PD slabs under mpirun (matrix-free).
# Prints per run: seconds, PD nodes, load steps, solves, broken bonds, the time per broken bond
# and per load step, the factorisations, downdates, CG solves, peak memory, and the peak load
# (which must agree between the ways: the same bonds break). Reported figures, not a timed
# test.
#
#   bench/fracture_senb.sh [h] [ways...]   h: grid spacing (default 1; m = 3), ways: default
#                                          "downdate krylov factor", and "petsc slabs" when
#                                          build-petsc/cupid and mpiexec exist; needs
#                                          build/cupid
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cupid=$root/build/cupid
[ -x "$cupid" ] || { echo "needs $cupid (scripts/build.sh)"; exit 2; }
h=${1:-1}; shift || true
pcupid=$root/build-petsc/cupid
mpiexec=$(command -v mpiexec || true)
more=""
[ -x "$pcupid" ] && [ -n "$mpiexec" ] && more=" petsc slabs"
ways=${*:-downdate krylov factor$more}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
hv=$(python3 -c "from fractions import Fraction as F; print(repr(float(F('$h'))))")
dv=$(python3 -c "print(repr(3.015 * $hv))")
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
echo "| model | re-solves | run s | PD nodes | steps | solves | broken bonds | s / bond | s / step | factorisations | downdates | CG solves | memory MB | peak N |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
row() { # model, way, dir, seconds
  python3 - "$@" <<'PY'
import csv, json, sys
model, way, d, t = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
label = {"petsc": "matrix-free, 1 process", "slabs": "matrix-free, 2 slabs",
         "lagrange": "Lagrange multipliers, downdate",
         "fictitious": "fictitious nodes, block factor downdated",
         "fictitious_slabs": "fictitious nodes, matrix-free, 2 slabs"}
s = json.load(open(d + "/summary.json"))
f = s["fracture"]; v = f["solves"]
steps = len(list(csv.DictReader(open(d + "/damage.csv"))))
b = f["broken_bonds"]
print(f"| {model} | {label.get(way, v['resolve'])} | {t:.1f} | {s['counts']['pd_nodes']} | {steps} | {v['solves']} | {b} | "
      f"{t / b:.4f} | {t / steps:.2f} | {v['factorisations']} | {v['downdates']} | {v['cg_solves']} | "
      f"{s['peak_memory_bytes'] / 2**20:.0f} | {-f['peak_reactions'][0]['reaction'][0]:.3f} |")
PY
}
run() { # model file, way
  local d=$work/$1_$2 t0 t1
  local m=$root/examples/fracture/senb_$1.yaml
  local set=(--quiet --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv")
  t0=$(date +%s.%N)
  case $2 in
    petsc) OMP_NUM_THREADS=1 "$pcupid" run "$m" -o "$d" "${set[@]}" --solver petsc ;;
    slabs) OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$pcupid" run "$m" -o "$d" "${set[@]}" ;;
    lagrange) "$cupid" run "$m" -o "$d" "${set[@]}" --set 'coupling={method: lagrange}' ;;
    fictitious) "$cupid" run "$m" -o "$d" "${set[@]}" --set 'coupling={method: fictitious}' ;;
    fictitious_slabs) OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$pcupid" run "$m" -o "$d" "${set[@]}" \
                        --set 'coupling={method: fictitious}' ;;
    *) CUPID_GROWTH_RESOLVE=$2 "$cupid" run "$m" -o "$d" "${set[@]}" ;;
  esac
  t1=$(date +%s.%N)
  row "$1" "$2" "$d" "$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.3f", b-a}')"
}
for way in $ways; do run coupled "$way"; done
run pd downdate
