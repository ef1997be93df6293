#!/usr/bin/env bash
# Reruns every LAMMPS case of README.md (about 4 minutes on one core). Needs the Debian
# package lammps and /usr/bin/python3 with numpy.
set -euo pipefail
cd "$(dirname "$0")"
/usr/bin/python3 make_deck.py --json derived.json
run() { tag=$1; shift; nice lmp -in in.notched_plate -log log_$tag.lammps -screen none -var tag $tag "$@"; }
run base                                  # v = 0.1 m/s, s0 = 1e-3, dt = 5e-8 s, 2500 steps
run v_plus    -var v 0.1001 -var final 0  # grip speed * (1 + 1e-3)
run s0_plus   -var s0 1.001e-3 -var final 0  # critical stretch * (1 + 1e-3)
run dt_half   -var dt 2.5e-8 -var nsteps 5000 -var final 0
# exact first-break steps (every step checked; the run stops there)
for c in "base" "v_plus -var v 0.1001" "s0_plus -var s0 1.001e-3" "dt_half -var dt 2.5e-8 -var nsteps 5000"; do
  set -- $c; tag=$1; shift
  nice lmp -in in.notched_plate -screen none -log first_$tag.log -var tag first_$tag -var final 0 -var halt 1 "$@"
  grep FIRST_BREAK_STEP first_$tag.log | tail -1 | sed "s/^/$tag: /"
  rm -f first_$tag.log damage_first_$tag.csv
done | tee first_break.txt
# the logs are kept trimmed: thermo table and bond statistics only
for f in log_*.lammps; do
  grep -E "^ +[0-9]+ |Step|total # of bonds|bonds/atom|Loop time|LAMMPS \(" "$f" > "$f.tmp" && mv "$f.tmp" "$f"
done
# the micromodulus check (uniform dilatation: 9/2 K eps^2) and the elastic pre-check's LAMMPS side
nice lmp -in in.dilatation_check -log none -screen none -echo none > /dev/null
nice lmp -in in.dilatation_check -log none | grep '^ENERGY_DENSITY_CORE' | tee dilatation_check.txt
nice lmp -in in.elastic_check -log none -screen none
