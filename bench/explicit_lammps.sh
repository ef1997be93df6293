#!/usr/bin/env bash
# Explicit LPS dynamics, whole process, cupid against LAMMPS peri/lps (issue 20, item 3): the
# lattice, physics and loop of bench/run_lammps.sh (an n^3 simple-cubic lattice, h = 1,
# delta = 3.015 h, influence 1/|xi|, PDLAMMPS partial volumes, E = 1e4, nu = 0.25, rho = 1,
# a velocity ramp vx = 1e-3 x / n, 110 velocity-Verlet steps of 1e-3, no breaking), each code
# timed from start to exit: grid and neighbour set-up, the stable-step check (cupid: Lanczos),
# the time loop and the outputs. The runs of both codes are interleaved (paired) and repeated;
# the best of each is compared, and the median of the pairs' ratios. Reported figures, not a
# timed test.
#
#   bench/explicit_lammps.sh [n (40)] [steps (110)] [repeats (3)] [cores ("1 2")]
# Needs build/cupid (scripts/build.sh) and lmp (scripts/install-deps.sh --with-lammps). LAMMPS
# runs `cores` MPI ranks (Debian's build has no OPENMP package), cupid `cores` threads.
set -euo pipefail
n=${1:-40}; steps=${2:-110}; reps=${3:-3}; cores=${4:-"1 2"}
root=$(cd "$(dirname "$0")/.." && pwd)
cupid=$root/build/cupid
command -v lmp >/dev/null || { echo "needs lmp: scripts/install-deps.sh --with-lammps"; exit 2; }
[ -x "$cupid" ] || { echo "needs $cupid (scripts/build.sh)"; exit 2; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
dur=$(awk -v s="$steps" 'BEGIN{printf "%.10g", s*1e-3}')
cat > lps.yaml <<YAML
title: bench explicit LPS ${n}^3
materials:
  m: {E: 10000, nu: 0.25, density: 1.0}
peridynamics:
  spacing: 1.0
  horizon: 3.015
  model: lps
  influence: inverse
  partial_volume: pdlammps
  material: m
  regions:
    - {x: [0, $n], y: [0, $n], z: [0, $n]}
analysis:
  type: dynamic
  dynamic:
    integrator: central
    dt: 1.0e-3
    duration: $dur
    every: $steps
    lumped: true
    initial: {velocity: ["1.0e-3*(x - 0.5)/$n", "0", "0"]}
output: {vtu: false, plots: false}
YAML
hi=$(awk -v n="$n" 'BEGIN { printf "%.1f", n - 0.5 }')
cat > in.lps <<LMP
units           si
boundary        s s s
atom_style      peri
atom_modify     map array
lattice         sc 1.0
region          cube block -0.5 $hi -0.5 $hi -0.5 $hi units box
create_box      1 cube
create_atoms    1 region cube
pair_style      peri/lps
pair_coeff      * * 6666.666666666667 4000.0 3.015 1.0e10 0.0
set             group all density 1.0
set             group all volume 1.0
velocity        all ramp vx 0.0 0.001 x 0.0 $n sum no units box
neighbor        0.1 bin
fix             1 all nve
timestep        1.0e-3
thermo          $steps
run             $steps
LMP
wall() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1 || { echo "failed: $*" >&2; exit 1; }; t1=$(date +%s.%N); awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.3f", b-a}'; }
echo "| cores | case | runs (s) | best s |"
echo "|---|---|---|---|"
for c in $cores; do
  declare -A best=() all=()
  for r in $(seq "$reps"); do
    for k in cupid lammps; do
      case $k in
        cupid) s=$(OMP_NUM_THREADS=$c OPENBLAS_NUM_THREADS=1 wall "$cupid" run lps.yaml -o o --quiet) ;;
        lammps) s=$(OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 wall mpirun --oversubscribe -np "$c" lmp -in in.lps -log none -screen none) ;;
      esac
      all[$k]="${all[$k]:-} $s"
      if [ -z "${best[$k]:-}" ] || awk -v a="$s" -v b="${best[$k]}" 'BEGIN{exit !(a<b)}'; then best[$k]=$s; fi
    done
  done
  for k in cupid lammps; do echo "| $c | $k | ${all[$k]} | ${best[$k]} |"; done
  echo "| $c | cupid/LAMMPS speed (best) | | $(awk -v a="${best[lammps]}" -v b="${best[cupid]}" 'BEGIN{printf "%.1fx", a/b}') |"
  # Each LAMMPS run over the cupid run just before it: the machine's speed drifts between
  # runs, and the median of these pairs moves less with one lucky or unlucky run.
  echo "| $c | cupid/LAMMPS speed (median of the runs' pairs) | | $(awk -v a="${all[cupid]}" -v b="${all[lammps]}" 'BEGIN{n = split(a, x, " "); split(b, y, " "); for (i = 1; i <= n; i++) r[i] = y[i] / x[i]; for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (r[j] < r[i]) { t = r[i]; r[i] = r[j]; r[j] = t } m = n % 2 ? r[(n + 1) / 2] : (r[n / 2] + r[n / 2 + 1]) / 2; printf "%.1fx", m}') |"
  unset best all
done
