#!/usr/bin/env bash
# Adaptive PD zones (issue 37) against a fixed zone and the all-PD beam, on the beams of
# examples/fracture at spacing h (default 1; horizon 3.015 h): the notched SENB
# (senb_adaptive.yaml: PD on [40, 50] at the start) and the beam without a notch
# (beam_adaptive.yaml: no PD at the start), each against the CUF beam with PD fixed on [30, 60]
# (senb_coupled.yaml) and the all-PD beam (senb_pd.yaml, its example supports). Prints per run:
# wall seconds, peak memory, PD nodes at the end, conversions, broken bonds and the peak load;
# then the notched bar of examples/notched_bar in explicit dynamics, fixed zone and adaptive.
# Reported figures, not a timed test: run it alone on the machine.
#
#   bench/fracture_adaptive.sh [h]     needs build/cupid (scripts/build.sh)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cupid=$root/build/cupid
[ -x "$cupid" ] || { echo "needs $cupid (scripts/build.sh)"; exit 2; }
h=${1:-1}
hv=$(python3 -c "from fractions import Fraction as F; print(repr(float(F('$h'))))")
dv=$(python3 -c "print(repr(3.015 * $hv))")
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
ex=$root/examples/fracture
unnotched=(--set 'peridynamics.precracks=[]' --set 'constraints[0].displacement.value=[-0.09, null, null]')
echo "| beam | model | wall s | memory MB | PD nodes at the end | conversions | broken bonds | peak N |"
echo "|---|---|---|---|---|---|---|---|"
run() { # beam label, model label, model file, extra arguments...
  local beam=$1 label=$2 model=$3 d=$work/$RANDOM t0 t1
  shift 3
  t0=$(date +%s.%N)
  # a run the crack stops (exit 2) has its results up to there
  "$cupid" run "$model" -o "$d" --quiet --set peridynamics.spacing="$hv" \
    --set peridynamics.horizon="$dv" "$@" || [ $? -eq 2 ]
  t1=$(date +%s.%N)
  python3 - "$beam" "$label" "$d" "$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.3f", b-a}')" <<'PY'
import json, sys
beam, label, d, t = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
s = json.load(open(d + "/summary.json"))
f = s["fracture"]
conv = len(s.get("adaptive", {}).get("conversions", []))
print(f"| {beam} | {label} | {t:.1f} | {s['peak_memory_bytes'] / 2**20:.0f} | {s['counts']['pd_nodes']} | "
      f"{conv} | {f['broken_bonds']} | {-f['peak_reactions'][0]['reaction'][0]:.3f} |")
PY
}
run notched "CUF + adaptive PD" "$ex/senb_adaptive.yaml"
run notched "CUF + PD on [30, 60]" "$ex/senb_coupled.yaml"
run notched "all PD" "$ex/senb_pd.yaml"
run "no notch" "CUF + adaptive PD (none at the start)" "$ex/beam_adaptive.yaml"
run "no notch" "CUF + PD on [30, 60]" "$ex/senb_coupled.yaml" "${unnotched[@]}"
run "no notch" "all PD" "$ex/senb_pd.yaml" "${unnotched[@]}"

# explicit dynamics (issue 37): the notched glass bar of examples/notched_bar under a 30 MPa
# step, 1600 steps, its PD fixed on [30, 70] against the adaptive zone (PD on [40, 60] at the
# start); the spacing of the model files (h = 1: the argument above is not applied)
echo
echo "| bar (explicit dynamics) | model | wall s | memory MB | PD nodes at the end | conversions | broken bonds | energy balance | conversions' energy |"
echo "|---|---|---|---|---|---|---|---|---|"
run_dynamic() { # model label, model file
  local label=$1 model=$2 d=$work/$RANDOM t0 t1
  t0=$(date +%s.%N)
  "$cupid" run "$model" -o "$d" --quiet --set output.vtu=false --set output.plots=false
  t1=$(date +%s.%N)
  python3 - "$label" "$d" "$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.3f", b-a}')" <<'PY'
import json, sys
label, d, t = sys.argv[1], sys.argv[2], float(sys.argv[3])
s = json.load(open(d + "/summary.json"))
dy, f = s["dynamic"], s["fracture"]
conv = s.get("adaptive", {}).get("conversions", [])
added = dy["final_energy"].get("conversion_added", 0.0)
print(f"| notched bar | {label} | {t:.1f} | {s['peak_memory_bytes'] / 2**20:.0f} | {s['counts']['pd_nodes']} | "
      f"{len(conv)} | {f['broken_bonds']} | {dy['max_energy_balance_relative']:.1e} | {added:.3g} |")
PY
}
run_dynamic "CUF + PD on [30, 70]" "$root/examples/notched_bar/notched_bar_arlequin.yaml"
run_dynamic "CUF + adaptive PD, [40, 60] at the start" "$root/examples/notched_bar/notched_bar_adaptive.yaml"
