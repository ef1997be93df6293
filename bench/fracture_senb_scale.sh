#!/usr/bin/env bash
# Crack growth at scale (issue 38, items 2 and 4): the coupled SENB of examples/fracture
# (senb_coupled.yaml: CUF beam + PD around the notch, Arlequin, surface-corrected, a/W = 0.5)
# with PD on y in [35, 55] (overlaps [35, 40] and [50, 55]) at spacings that give about 10^4,
# 3 x 10^4 and 10^5 PD nodes, each against one static solve of the same model:
#   h = 1/2   16,000 PD nodes     h = 5/12   27,648     h = 1/4 (PD on [38.75, 51.25], the
#   issue's model: 80,000 PD nodes, overlaps 1.25 mm)
# For each: the growth run's seconds and its ratio to one static solve (the same model with a
# fracture energy no bond reaches (G0 = 10^6), one load step: assembly, factorisation, solve), seconds per
# broken bond, solves, factorisations, downdates, CG iterations, peak memory, and the peak
# load against ASTM E399's P_c = 31.5 N. A model whose growth on the direct path `cupid check`
# estimates above the memory limit (default 8 GB: the issue's) is not run: its row gives the
# estimate.
# Reported figures, not a timed test.
#
#   bench/fracture_senb_scale.sh [spacings...]   default "1/2 5/12 1/4"; needs build/cupid
#   CUPID_BENCH_LIMIT_GB=8 CUPID_BENCH_THREADS=2
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cupid=$root/build/cupid
[ -x "$cupid" ] || { echo "needs $cupid (scripts/build.sh)"; exit 2; }
spacings=${*:-1/2 5/12 1/4}
limit=${CUPID_BENCH_LIMIT_GB:-8}
threads=${CUPID_BENCH_THREADS:-2}
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
model=$root/examples/fracture/senb_coupled.yaml
echo "| h | PD nodes | static solve s | growth s | growth / static | broken bonds | s / bond | solves | factorisations | downdates | CG iterations | memory GB | peak N | peak / P_c |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for h in $spacings; do
  hv=$(python3 -c "from fractions import Fraction as F; print(repr(float(F('$h'))))")
  dv=$(python3 -c "print(repr(3.015 * $hv))")
  # the PD zone and its overlaps: [35, 55], or the issue's [38.75, 51.25] at h = 1/4
  if [ "$h" = 1/4 ]; then
    ax='{y: [0, 5, 38.75, 40, 50, 51.25, 85, 90], elements: [1, 7, 1, 2, 1, 7, 1], type: B4}'
    lo=38.75 hi=51.25 o1='[38.75, 40]' o2='[50, 51.25]'
  else
    ax='{y: [0, 5, 35, 40, 50, 55, 85, 90], elements: [1, 6, 1, 2, 1, 6, 1], type: B4}'
    lo=35 hi=55 o1='[35, 40]' o2='[50, 55]'
  fi
  set=(--quiet --threads "$threads" --set peridynamics.surface_correction=energy
       --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" --set "beam.axis=$ax"
       --set "peridynamics.regions=[{x: [0, 20], y: [$lo, $hi], z: [0, 5]}]"
       --set "coupling.arlequin.overlap=[{y: $o1}, {y: $o2}]"
       --set output.vtu=false --set output.plots=false)
  # the direct path's peak memory as `cupid check` estimates it for a growth run (the factor
  # copied for its downdates; session 35), or for a static solve from an older build
  checked=$("$cupid" check "$model" "${set[@]}" 2>&1)
  gb=$(sed -n 's/^estimated peak memory, crack growth on the direct path: \([0-9.e+]*\) GB.*/\1/p' <<<"$checked")
  [ -n "$gb" ] || gb=$(sed -n 's/^estimated peak memory, direct path: \([0-9.e+]*\) GB.*/\1/p' <<<"$checked")
  gb=${gb:-nan}
  if python3 -c "import sys; sys.exit(0 if $gb == $gb and $gb > $limit else 1)" 2>/dev/null; then
    n=$(python3 -c "print(round(20 / $hv) * round(5 / $hv) * round(($hi - $lo) / $hv))")
    # the factor's size measured by CHOLMOD's symbolic analysis (no factor formed), its best
    # ordering: whether any ordering would make it fit
    fill=
    if [ -x "$root/build/bench/bench_factor_fill" ]; then
      fill=$("$root/build/bench/bench_factor_fill" "$model" "${set[@]/--quiet/}" | python3 -c "
import sys
rows = [l.split('|') for l in sys.stdin if l.startswith('| ') and 'ordering' not in l]
best = min(rows, key=lambda r: float(r[2]))
print(f'; symbolic analysis: {float(best[2]):.3g} factor entries at best ({best[1].strip()}), '
      f'{best[4].strip()} GB of values, {best[6].strip()} GB for growth')")
    fi
    echo "| $h | $n | not run: \`cupid check\` estimates $gb GB for its growth on the direct path, over $limit GB$fill | | | | | | | | | | | |"
    continue
  fi
  t0=$(date +%s.%N)
  "$cupid" run "$model" -o "$work/static" "${set[@]}" --set analysis.steps=1 \
    --set peridynamics.fracture.energy_release_rate=1e6
  t1=$(date +%s.%N)
  "$cupid" run "$model" -o "$work/grow" "${set[@]}"
  t2=$(date +%s.%N)
  python3 - "$h" "$work" "$t0" "$t1" "$t2" <<'PY'
import json, sys
h, w, t0, t1, t2 = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:6])
g = json.load(open(w + "/grow/summary.json"))
f, v = g["fracture"], g["fracture"]["solves"]
ts, tg = t1 - t0, t2 - t1
peak = -f["peak_reactions"][0]["reaction"][0]
print(f"| {h} | {g['counts']['pd_nodes']} | {ts:.1f} | {tg:.1f} | {tg / ts:.1f} | {f['broken_bonds']} | "
      f"{tg / f['broken_bonds']:.4f} | {v['solves']} | {v['factorisations']} | {v['downdates']} | "
      f"{v['cg_iterations']} | {g['peak_memory_bytes'] / 1e9:.2f} | {peak:.2f} | {peak / 31.5:.3f} |")
PY
done
