#!/usr/bin/env bash
# Static LPS cube solves with the PETSc engine, matrix-free (issue 6; docs/scale.md): N^3 body
# nodes (+ a fixed layer one horizon thick), delta = 3h, Gaussian influence, PDLAMMPS partial
# volumes, 100 MPa traction on the far face. Prints one line per run: N, ranks, PD nodes,
# iterations, setup and solve seconds, wall seconds, peak memory per rank (GB).
# Usage: bench/scale_petsc.sh [BUILD_DIR] [N...]   (default build-petsc, 20 40 60)
# Extra PETSc options: PETSC_OPTS="-cupid_pc_radius 2 -ksp_monitor" bench/scale_petsc.sh
# RANKS="1 2" by default. Reported, not timed as a test.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-petsc}
shift || true
sizes=${*:-20 40 60}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%5s %5s %9s %5s %8s %8s %8s %8s  %s\n' N ranks nodes its setup_s solve_s wall_s GB/rank pc
for n in $sizes; do
  cat > "$tmp/cube$n.yaml" <<YAML
title: LPS cube $n^3 (bench/scale_petsc.sh)
materials:
  steel: {E: 200000, nu: 0.3}
peridynamics:
  spacing: 1.0
  horizon: 3.0
  model: lps
  influence: gaussian
  partial_volume: pdlammps
  material: steel
  regions:
    - {x: [0, $n], y: [-3, $n], z: [0, $n]}
constraints:
  - fix: {box: {y: [-3, 0]}}
loads:
  - traction: {y: $n, value: [0, 100, 0]}
analysis: {type: static, solver: petsc}
output:
  directory: $tmp/out$n
  points:
    - {name: tip, at: [$((n / 2)), $n, $((n / 2))]}
YAML
  for r in ${RANKS:-1 2}; do
    threads=$((2 / r)); [ "$threads" -ge 1 ] || threads=1
    /usr/bin/time -f "%e %M" -o "$tmp/time" env OMP_NUM_THREADS=$threads \
      mpiexec -n "$r" "$build/cupid" run "$tmp/cube$n.yaml" -q ${PETSC_OPTS:-} > "$tmp/log" 2>&1 ||
      { cat "$tmp/log"; exit 1; }
    read -r wall kb < "$tmp/time"
    python3 - "$tmp/out$n/summary.json" "$n" "$r" "$wall" "$kb" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); v = s["solver"]; ph = s["phases"]
n, r, wall, kb = sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5])
print(f"{n:>5} {r:>5} {s['counts']['pd_nodes']:>9} {v['iterations']:>5} "
      f"{ph['factorisation']['time_s']:8.2f} {ph['solve']['time_s']:8.2f} {wall:8.2f} "
      f"{kb / 1e6:8.2f}  {v['ksp_type']}+{v['pc_type']} res {v['residual']:.1e}")
PY
  done
done
