#!/usr/bin/env bash
# cupid's matrix-free PD operator against LAMMPS pair_style peri/lps on the same lattice
# (bench/README.md, "PD operator vs LAMMPS"): an n^3 simple-cubic lattice, h = 1,
# delta = 3.015 h, influence 1/|xi| (LAMMPS peri's only one), PDLAMMPS partial volumes
# (LAMMPS's linear volume fraction), E = 1e4, nu = 0.25 (K = 6666.67, G = 4000), rho = 1,
# V = h^3, 110 velocity-Verlet steps (LAMMPS fix nve), no bond breaking (s00 = 1e10).
#
# Usage: bench/run_lammps.sh [n] [procs]   (defaults 40 2). Needs `lmp` (Debian package
# lammps; its build has no OPENMP package, so LAMMPS runs `procs` MPI ranks of 1 thread)
# and a Release build of cupid in build/ (bench_pd_apply). cupid runs OMP_NUM_THREADS=procs
# threads, and for the per-core figures both run once more on 1 core.
# Prints LAMMPS's loop time, its CPU share, the Pair share, cupid's table, and a summary of
# milliseconds per step (CPU time of all cores, and wall time) with the ratios.
set -euo pipefail
n=${1:-40}
np=${2:-2}
here=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD:-$here/build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v lmp >/dev/null || "$(dirname "$0")/../scripts/install-deps.sh" --with-lammps
command -v lmp >/dev/null || { echo "lmp not found: scripts/install-deps.sh --with-lammps" >&2; exit 1; }
[ -x "$build/bench/bench_pd_apply" ] || { echo "build cupid first (cmake --build build)" >&2; exit 1; }

# Atoms at integer points 0 .. n-1: the region's bounds sit half a spacing outside.
hi=$(awk -v n="$n" 'BEGIN { printf "%.1f", n - 0.5 }')
cat >"$work/in.lps" <<EOF
units           si
boundary        s s s
atom_style      peri
atom_modify     map array
lattice         sc 1.0
region          cube block -0.5 $hi -0.5 $hi -0.5 $hi units box
create_box      1 cube
create_atoms    1 region cube
pair_style      peri/lps
# K = E/(3(1-2nu)), G = E/(2(1+nu)) for E = 1e4, nu = 0.25; horizon 3.015 h; s00 huge, alpha 0
pair_coeff      * * 6666.666666666667 4000.0 3.015 1.0e10 0.0
set             group all density 1.0
set             group all volume 1.0
velocity        all ramp vx 0.0 0.001 x 0.0 $n sum no units box
neighbor        0.1 bin
fix             1 all nve
timestep        1.0e-3
thermo          110
run             110
EOF

mpi=(mpirun -np "$np")
[ "$(id -u)" = 0 ] && mpi=(mpirun --allow-run-as-root -np "$np")
run_lammps() { # procs
  local p=$1 launcher=("${mpi[@]}")
  launcher[-1]=$p
  (cd "$work" && OMP_NUM_THREADS=1 "${launcher[@]}" lmp -in in.lps -log log.$p >out.$p 2>&1)
  local loop cpu pair
  loop=$(awk '/^Loop time of/ { print $4 }' "$work/log.$p")
  cpu=$(awk '/% CPU use/ { sub("%", "", $1); print $1 }' "$work/log.$p")
  pair=$(awk '/^Pair  *\|/ { print $5 }' "$work/log.$p")
  awk -v p="$p" -v loop="$loop" -v cpu="$cpu" -v pair="$pair" 'BEGIN {
    fmt = "LAMMPS peri/lps, %d MPI ranks: loop %.3f s wall for 110 steps (%.2f steps/s), CPU use %.1f%% of %d cores (%.3f CPU s, %.2f ms CPU per step), Pair avg %.3f s\n"
    printf fmt, p, loop, 110 / loop, cpu, p, loop * cpu / 100 * p, 1e3 * loop * cpu / 100 * p / 110, pair }'
  grep -E "^(LAMMPS \(|Total # of neighbors|Ave neighs/atom)" "$work/log.$p" || true
}

# Repeats (REPEAT, default 3) alternate the codes; the summary takes each figure's best
# (minimum) over them: on a shared machine the minimum is the least disturbed run.
repeat=${REPEAT:-3}
: >"$work/summary"
for r in $(seq 1 "$repeat"); do
  echo "== repeat $r/$repeat, n = $n, $(nproc) cores, load average: $(cut -d' ' -f1-3 /proc/loadavg)"
  for p in $(printf "%s\n" "$np" 1 | sort -u); do
    line=$(run_lammps "$p")
    echo "$line"
    echo "$line" | awk -v p="$p" '/^LAMMPS peri/ { for (k = 1; k <= NF; k++) if ($k == "CPU" && $(k+1) == "per") print "lammps", p, $(k-2), 1e3 * $7 / 110 }' >>"$work/summary"
    OMP_NUM_THREADS=$p "$build/bench/bench_pd_apply" "$n" 2>/dev/null | tee "$work/cupid.$p" | grep "^| $n "
    # columns: 110 steps stencil s (CPU) = field 11, bond-list = field 12 ("wall (cpu)")
    awk -F'|' -v p="$p" -v n="$n" '$2 == " " n " " {
      split($11, a, /[ ()]+/); split($12, b, /[ ()]+/)
      print "stencil", p, 1e3 * a[3] / 110, 1e3 * a[2] / 110
      print "bondlist", p, 1e3 * b[3] / 110, 1e3 * b[2] / 110 }' "$work/cupid.$p" >>"$work/summary"
  done
done
echo
echo "Best of $repeat (ms per step of 110: CPU time of all cores / wall time):"
sort -k1,1 -k2,2n -k3,3g "$work/summary" | awk '!seen[$1 " " $2]++ { cpu[$1, $2] = $3; wall[$1, $2] = $4;
    printf "  %-8s %d core(s): %8.2f ms CPU, %8.2f ms wall\n", $1, $2, $3, $4; cores[$2] = 1 }
  END { for (p in cores) {
    printf "  %d core(s): stencil vs LAMMPS %.1fx (CPU), %.1fx (wall); bond lists vs LAMMPS %.1fx (CPU); stencil vs bond lists %.1fx (CPU)\n",
      p, cpu["lammps", p] / cpu["stencil", p], wall["lammps", p] / wall["stencil", p],
      cpu["lammps", p] / cpu["bondlist", p], cpu["bondlist", p] / cpu["stencil", p] } }'
echo
echo "Last cupid tables:"
for p in $(printf "%s\n" "$np" 1 | sort -u); do cat "$work/cupid.$p"; echo; done
