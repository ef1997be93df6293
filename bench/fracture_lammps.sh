#!/usr/bin/env bash
# Explicit dynamic fracture on an n^3 lattice (default n = 40: 64,000 nodes), cupid against
# LAMMPS peri/pmb on the same lattice, the same cores and the same physics (issue 16,
# "Performance"): bond-based PMB with cupid's micromodulus (c = 18 K / S, PDLAMMPS partial
# volumes, constant influence; tests/verification/fracture_lammps/README.md), delta = 3.015 h,
# glass (E = 72 GPa, nu = 1/4, rho = 2440), critical stretch 1e-3, the top and bottom three
# layers pulled apart at 1 m/s each (a crack-free bar that starts breaking at its grips late in
# the run: the bond check runs every step either way), dt = 5e-8 s. Whole-process wall time,
# the runs of each case interleaved (paired) and repeated; cupid is timed with and without
# bond breaking (`fracture:` removed). Reported figures, not a timed test.
#
#   bench/fracture_lammps.sh [n (40)] [steps (200)] [repeats (3)] [cores (1 2)]
# Needs build/cupid (scripts/build.sh) and lmp (scripts/install-deps.sh --with-lammps). Prints a markdown
# table: steps/s per case and core count, cupid/LAMMPS per core, fracture/no-fracture.
set -euo pipefail
n=${1:-40}; steps=${2:-200}; reps=${3:-3}; cores=${4:-"1 2"}
root=$(cd "$(dirname "$0")/.." && pwd)
cupid=$root/build/cupid
command -v lmp >/dev/null || { echo "needs lmp: scripts/install-deps.sh --with-lammps"; exit 2; }
[ -x "$cupid" ] || { echo "needs $cupid (scripts/build.sh)"; exit 2; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
dt=5e-8; dur=$(awk -v s="$steps" -v d="$dt" 'BEGIN{printf "%.10g", s*d}')
top=$((n - 3))
cat > frac.yaml <<YAML
title: bench fracture ${n}^3
materials:
  glass: {E: 72000, nu: 0.25, density: 2.44e-9}
peridynamics:
  spacing: 1.0
  horizon: 3.015
  model: bond
  influence: constant
  partial_volume: pdlammps
  material: glass
  regions:
    - {x: [0, $n], y: [0, $n], z: [0, $n]}
  fracture: {criterion: stretch, critical_stretch: 1.0e-3}
constraints:
  - displacement: {box: {y: [$top, $n]}, value: [0, "1000*t", 0]}
  - displacement: {box: {y: [0, 3]}, value: [0, "-1000*t", 0]}
analysis:
  type: dynamic
  dynamic: {integrator: central, dt: $dt, duration: $dur, every: $steps, lumped: true}
output: {vtu: false, plots: false}
YAML
grep -v "fracture:" frac.yaml > elastic.yaml
L=$(awk -v n="$n" 'BEGIN{printf "%.6f", n/1000}')
T=$(awk -v t="$top" 'BEGIN{printf "%.6f", t/1000}')
cat > in.bench <<LMP
units si
dimension 3
boundary s s s
atom_style peri
atom_modify map array
lattice sc 0.001 origin 0.5 0.5 0.5
region box block 0 $L 0 $L 0 $L units box
create_box 1 box
create_atoms 1 region box
set group all density 2440
set group all volume 1.0e-9
pair_style peri/pmb
pair_coeff * * 3.741338239838e+21 3.015e-3 1.0e-3 0.0
neighbor 0.0005 bin
neigh_modify every 1 delay 0 check yes
region rtop block INF INF $T INF INF INF units box
region rbot block INF INF INF 0.003 INF INF units box
group top region rtop
group bot region rbot
group grips union top bot
velocity all set 0 0 0 units box
velocity top set 0 1.0 0 units box
velocity bot set 0 -1.0 0 units box
fix integ all nve
fix hold grips setforce 0 0 0
timestep $dt
thermo $steps
run $steps
LMP
wall() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1 || { echo "failed: $*" >&2; exit 1; }; t1=$(date +%s.%N); awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.3f", b-a}'; }
echo "| cores | case | runs (s) | best s | steps/s (best) |"
echo "|---|---|---|---|---|"
for c in $cores; do
  declare -A best=() all=()
  for r in $(seq "$reps"); do
    for k in cupid_fracture cupid_elastic lammps; do
      case $k in
        cupid_fracture) s=$(OMP_NUM_THREADS=$c OPENBLAS_NUM_THREADS=1 wall "$cupid" run frac.yaml -o o1 --quiet) ;;
        cupid_elastic) s=$(OMP_NUM_THREADS=$c OPENBLAS_NUM_THREADS=1 wall "$cupid" run elastic.yaml -o o2 --quiet) ;;
        lammps) s=$(OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 wall mpirun --oversubscribe -np "$c" lmp -in in.bench -log none -screen none) ;;
      esac
      all[$k]="${all[$k]:-} $s"
      if [ -z "${best[$k]:-}" ] || awk -v a="$s" -v b="${best[$k]}" 'BEGIN{exit !(a<b)}'; then best[$k]=$s; fi
    done
  done
  for k in cupid_fracture cupid_elastic lammps; do
    echo "| $c | $k | ${all[$k]} | ${best[$k]} | $(awk -v s="$steps" -v t="${best[$k]}" 'BEGIN{printf "%.1f", s/t}') |"
  done
  echo "| $c | cupid/LAMMPS speed (fracture, best) | | | $(awk -v a="${best[lammps]}" -v b="${best[cupid_fracture]}" 'BEGIN{printf "%.2fx", a/b}') |"
  echo "| $c | cupid fracture / elastic time | | | $(awk -v a="${best[cupid_fracture]}" -v b="${best[cupid_elastic]}" 'BEGIN{printf "%.2f", a/b}') |"
  unset best all
done
