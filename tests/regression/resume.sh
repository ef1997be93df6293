#!/usr/bin/env bash
# Interrupted and resumed runs (issue 36; docs/hardening.md, "Checkpoints"). A dynamic run
# stopped by SIGTERM (a checkpoint at the next output step, exit 5) or killed by SIGKILL (the
# last periodic checkpoint) at a pseudo-random moment, then continued with --resume (stopped
# again, sometimes), must end with the files of the run that was never interrupted, byte for
# byte; summary.json to the bit but for its timings, memory and threads (keys *_s, *memory*,
# threads). Covered:
# a free LPS block (central differences with merged half-kicks between outputs), explicit
# fracture with moving grips (PMB and LPS), the Arlequin beam with explicit fracture (and
# model.exo), Newmark with Rayleigh damping, Newmark with a moving grip and a load in t, a
# Lagrange tie, the plots; and crack growth over load steps (the factor rebuilt from its
# journal: downdates, a held node, a tied one; LPS; the Arlequin SENB with model.exo; the SENB with
# fictitious nodes by block elimination, balanced); adaptive PD zones in dynamics and in
# growth, interrupted anywhere and at a conversion's step. And the refusals: a changed model or option (exit 1, naming the line that differs),
# nothing to resume and no intact checkpoint (exit 3), a damaged checkpoint (its previous one is
# used, the results unchanged), a disk that fills while checkpointing (a warning; the run goes
# on), a second signal (stops at once; the last periodic checkpoint resumes).
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0; fail=0
RANDOM=36
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL: $*"; fail=$((fail + 1)); }

# same REF DIR: the same files, byte for byte (summary.json but for timings; tests/tools)
same() { python3 "$SRC/tests/tools/same_outputs.py" "$1" "$2"; } # REF DIR

# interrupt_and_resume NAME MODEL OPTIONS...: a reference run, then runs killed at random moments
# (TERM or KILL, alternately; the resumptions too, twice at most) until one ends; compared.
interrupt_and_resume() {
  local name=$1 model=$2; shift 2
  rm -rf "ref_$name"
  local t0=$(date +%s%N)
  "$CUPID" run "$model" -o "ref_$name" -q "$@" || { bad "$name: the reference run failed"; return; }
  local ms=$(( ($(date +%s%N) - t0) / 1000000 ))
  eval "ms_$name=$ms" # the run's length, for the refusals below
  local trial trials="1 2"
  # a sanitizer build: one interrupted run per model (the code paths, not more random moments)
  [ "${CUPID_TEST_SANITIZED:-0}" = 1 ] && trials=1
  for trial in $trials; do
    local out="run_${name}_$trial" resume="" rc=1 kills=0 sig
    rm -rf "$out" ".$out.cupid-partial"
    while :; do
      "$CUPID" run "$model" -o "$out" -q "$@" $resume 2>err.txt &
      local pid=$!
      if [ $kills -lt 2 ]; then
        sig=$([ $(( (trial + kills) % 2 )) -eq 0 ] && echo KILL || echo TERM)
        sleep "$(awk -v r=$RANDOM -v ms=$ms 'BEGIN { printf "%.3f", (0.15 + 0.7 * r / 32767) * ms / 1000 }')"
        kill -$sig $pid 2>/dev/null
        kills=$((kills + 1))
      fi
      wait $pid 2>/dev/null; rc=$?
      [ $rc -eq 0 ] && break
      if [ $rc -eq 3 ] && grep -q "nothing to resume" err.txt; then resume=""; continue; fi
      # 5: stopped at a checkpoint; 137: killed; 143: a SIGTERM before the first step or after
      # the last (no step to stop at: it stops at once, as any run)
      if [ $rc -ne 5 ] && [ $rc -ne 137 ] && [ $rc -ne 143 ]; then
        bad "$name: exit $rc: $(cat err.txt)"; return
      fi
      resume=--resume
    done
    if msg=$(same "ref_$name" "$out" 2>&1); then ok; else bad "$name trial $trial: $msg"; fi
    [ -e ".$out.cupid-partial" ] && bad "$name: the staging folder stayed after the run ended"
  done
}

cp "$SRC/examples/notched_plate/notched_plate.yaml" plate.yaml
cp "$SRC/examples/notched_plate/notched_plate_lps.yaml" plate_lps.yaml
cp "$SRC/examples/notched_bar/notched_bar_arlequin.yaml" bar.yaml
cp "$SRC/examples/truss/truss_arlequin_damped.yaml" truss_damped.yaml
cp "$SRC/examples/truss/truss_lagrange.yaml" truss_lagrange.yaml
cat > grip.yaml <<'EOF'
title: FE bar, Newmark, a moving grip and a load in t
materials:
  steel: {E: 2.0e11, nu: 0.3, density: 7800}
beam:
  material: steel
  axis: {y: [0, 1], elements: [20], type: B3}
  section:
    expansion: TE1
    components:
      - {x: [-0.05, 0.05], z: [-0.05, 0.05]}
constraints:
  - displacement: {box: {y: [0, 0]}, value: [0, "1e-4*sin(2000*t)", 0]}
loads:
  - point: {at: [0, 1, 0], value: [0, 0, "1e3*t"]}
analysis:
  type: dynamic
  dynamic: {integrator: newmark, dt: 2.0e-6, duration: 0.02, every: 200, lumped: true}
output:
  vtu: true
  points:
    - {name: tip, at: [0, 1, 0]}
  plots: false
EOF
cat > free.yaml <<'EOF'
title: a free LPS block in vibration (central differences merge the half-kicks between outputs)
materials:
  m: {E: 1000, nu: 0.25, density: 1.0e-3}
peridynamics:
  spacing: 1.0
  horizon: 3.015
  model: lps
  material: m
  regions:
    - {x: [0, 24], y: [0, 24], z: [0, 12]}
analysis:
  type: dynamic
  dynamic:
    integrator: central
    dt: 1.0e-4
    duration: 0.15
    every: 100
    lumped: true
    initial: {displacement: ["0", "0", "0"], velocity: ["1e-3*(x-12)", "0", "-1e-3*(z-6)"]}
output:
  vtu: true
  points:
    - {name: corner, at: [0.5, 0.5, 0.5]}
  plots: false
EOF
P=(--set output.plots=false --set output.checkpoint=0.05)
# model.exo (output.exodus, issue 35) where the build has Exodus II: a resumption reopens the
# partial database and writes on from the checkpoint's time step
EXO=()
"$CUPID" check free.yaml --set output.exodus=true >/dev/null 2>&1 && EXO=(--set output.exodus=true)
interrupt_and_resume free free.yaml "${P[@]}"
interrupt_and_resume pmb plate.yaml "${P[@]}"
interrupt_and_resume lps plate_lps.yaml "${P[@]}"
interrupt_and_resume arlequin bar.yaml "${P[@]}" "${EXO[@]}"
interrupt_and_resume damped truss_damped.yaml --set analysis.dynamic.duration=0.5 "${P[@]}"
interrupt_and_resume grip grip.yaml --set output.checkpoint=0.05
interrupt_and_resume lagrange truss_lagrange.yaml --set analysis.dynamic.duration=0.3 "${P[@]}"
interrupt_and_resume plots plate.yaml --set output.checkpoint=0.05

# crack growth over load steps: the factor downdated by every round of breaks (a node held), LPS
# (CG on the last factor), the Arlequin SENB; checkpoints after load steps
cp "$SRC/tests/models/growth/plate.yaml" growth.yaml
cp "$SRC/examples/fracture/senb_coupled.yaml" senb.yaml
GP=(--set "peridynamics.regions=[{x: [0, 30], y: [0, 24], z: [0, 2]}]"
    --set "peridynamics.precracks=[{normal: y, at: 12, x: [0, 8], z: [0, 2]}]"
    --set analysis.steps=20 --set output.checkpoint=0.05)
interrupt_and_resume growth growth.yaml "${GP[@]}"
interrupt_and_resume growth_lps growth.yaml "${GP[@]}" --set peridynamics.model=lps \
  --set "peridynamics.fracture={criterion: energy, energy_release_rate: 0.01}" \
  --set "peridynamics.regions=[{x: [0, 20], y: [0, 24], z: [0, 2]}]" --set analysis.steps=10
interrupt_and_resume senb senb.yaml --set peridynamics.spacing=1.6666666666666667 \
  --set peridynamics.horizon=5.025 "${P[@]}" "${EXO[@]}"
interrupt_and_resume senb_fictitious senb.yaml --set "coupling={method: fictitious}" \
  --set peridynamics.spacing=1.6666666666666667 --set peridynamics.horizon=5.025 "${P[@]}"

# adaptive PD zones (issue 37): the checkpoint holds the zone, and --resume lays it out again
# before the run reads its state; the notched bar whose zone grows in explicit dynamics
# (conversions at steps 320, 500 and 560), the SENB whose zone grows under load (steps 6, 7)
cp "$SRC/examples/notched_bar/notched_bar_adaptive.yaml" bar_adaptive.yaml
cp "$SRC/tests/models/adaptive/senb.yaml" senb_adaptive.yaml
AD=(--set 'peridynamics.adaptive={threshold: 0.1, margin: 1, within: {y: [20, 70]}}' --set output.vtu=true
    --set output.checkpoint=0.05)
interrupt_and_resume adaptive_dynamic bar_adaptive.yaml "${P[@]}" --set analysis.dynamic.duration=2.0e-5
interrupt_and_resume adaptive_growth senb_adaptive.yaml "${AD[@]}"
# and at the step of a conversion: the dynamic run's checkpoint at step 320 comes before the
# trigger's test there (which grows the zone), the growth's at step 6 after the conversions
stop_at() { # stop_at NAME STEP MODEL OPTIONS...: stopped there, resumed, against ref_NAME
  local name=$1 step=$2 model=$3; shift 3
  rm -rf "at_$name" ".at_$name.cupid-partial"
  CUPID_TEST_INTERRUPT_STEP=$step "$CUPID" run "$model" -o "at_$name" -q "$@" 2>/dev/null; local rc=$?
  "$CUPID" run "$model" -o "at_$name" -q "$@" --resume 2>err.txt; local rc2=$?
  local msg=""
  [ $rc -eq 5 ] && [ $rc2 -eq 0 ] && msg=$(same "ref_$name" "at_$name" 2>&1) && ok ||
    bad "$name stopped at step $step: exit $rc, then $rc2: $msg $(head -2 err.txt)"
}
stop_at adaptive_dynamic 320 bar_adaptive.yaml "${P[@]}" --set analysis.dynamic.duration=2.0e-5
stop_at adaptive_growth 6 senb_adaptive.yaml "${AD[@]}"
# (and at its last step: the end's zone frame is at the last row's load factor, which the
# checkpoint keeps; a random interrupt found it at 0)
stop_at adaptive_growth 20 senb_adaptive.yaml "${AD[@]}"
# a dynamic zone that starts empty: stopped while the beam runs alone (a checkpoint of no PD
# region) and at the step its first conversion comes
EMPTY=("${P[@]}" --set analysis.dynamic.duration=2.0e-5 --set 'peridynamics.regions=[]'
       --set 'coupling.arlequin.overlap=[]' --set 'peridynamics.precracks=[]')
"$CUPID" run bar_adaptive.yaml -o ref_adaptive_empty -q "${EMPTY[@]}" || bad "adaptive_empty: the reference run failed"
stop_at adaptive_empty 280 bar_adaptive.yaml "${EMPTY[@]}"
stop_at adaptive_empty 320 bar_adaptive.yaml "${EMPTY[@]}"

# a tie (growth.c, tie_mechanisms): the plate pulled twice as far is cut at step 9, whose last
# ligament's node is tied by a weak spring in a downdated round; stopped there and after it, the
# factor's journal replays the tie's rank-three update (the ties are the journal's DOFs -1 - d)
TIE=("${GP[@]}" --set "constraints[1].displacement.value=[0, 0.04, 0]")
"$CUPID" run growth.yaml -o ref_tie -q "${TIE[@]}" || bad "tie: the reference run failed"
python3 -c "import json, sys; f = json.load(open('ref_tie/summary.json'))['fracture']; \
sys.exit(not (f.get('tied_nodes') == 1 and f['solves']['factorisations'] == 1))" && ok ||
  bad "tie: the reference run ties no node in a downdated round"
stop_at tie 9 growth.yaml "${TIE[@]}"
stop_at tie 12 growth.yaml "${TIE[@]}"

# stopped at the last step (CUPID_TEST_INTERRUPT_STEP: a signal during that step, made
# deterministic): the resumption takes no step, and its report still reads the conditions of
# the last one (the applied load, the reactions: issue 36, found by a SIGTERM that came there)
rm -rf last .last.cupid-partial
CUPID_TEST_INTERRUPT_STEP=10000 "$CUPID" run grip.yaml -o last -q --set output.checkpoint=0.05 2>/dev/null
rc=$?
"$CUPID" run grip.yaml -o last -q --set output.checkpoint=0.05 --resume 2>err.txt; rc2=$?
[ $rc -eq 5 ] && [ $rc2 -eq 0 ] && msg=$(same ref_grip last 2>&1) && ok ||
  bad "grip stopped at its last step: exit $rc, then $rc2: ${msg:-} $(head -2 err.txt)"
rm -rf glast .glast.cupid-partial
CUPID_TEST_INTERRUPT_STEP=20 "$CUPID" run growth.yaml -o glast -q "${GP[@]}" 2>/dev/null; rc=$?
"$CUPID" run growth.yaml -o glast -q "${GP[@]}" --resume 2>err.txt; rc2=$?
[ $rc -eq 5 ] && [ $rc2 -eq 0 ] && msg=$(same ref_growth glast 2>&1) && ok ||
  bad "growth stopped at its last step: exit $rc, then $rc2: ${msg:-} $(head -2 err.txt)"

# ---- refusals, on the PMB plate stopped half-way
# half-way through the plate's 2500 steps: at step 1250 by the tests' deterministic signal
# (CUPID_TEST_INTERRUPT_STEP: exit 5 with a checkpoint there, the periodic ones of every
# 0.05 s before it). A sleep of half the run measured at the start stopped none once, under
# the load of other tests that came and went since (the run had ended: exit 0).
stop_half() { # stop_half DIR: a run of the plate stopped half-way (exit 5), periodic checkpoints
  rm -rf "$1"
  CUPID_TEST_INTERRUPT_STEP=1250 "$CUPID" run plate.yaml -o "$1" -q "${P[@]}" 2>/dev/null
}
stop_half h; rc=$?
[ $rc -eq 5 ] && [ -f .h.cupid-partial/.checkpoint ] && ok || bad "SIGTERM: exit $rc, no checkpoint"

sed 's/E: 72000/E: 72001/' plate.yaml > plate2.yaml && cp plate.yaml keep.yaml && cp plate2.yaml plate.yaml
"$CUPID" run plate.yaml -o h -q "${P[@]}" --resume 2>err.txt; rc=$?
cp keep.yaml plate.yaml
[ $rc -eq 1 ] && grep -q "belongs to another run" err.txt && grep -q "CRC-32" err.txt && ok ||
  bad "a changed model: exit $rc: $(cat err.txt)"
"$CUPID" run plate.yaml -o h -q "${P[@]}" --set analysis.dynamic.every=25 --resume 2>err.txt; rc=$?
[ $rc -eq 1 ] && grep -q "every=25" err.txt && ok || bad "a changed option: exit $rc: $(cat err.txt)"
"$CUPID" run plate.yaml -o nowhere -q "${P[@]}" --resume 2>err.txt; rc=$?
[ $rc -eq 3 ] && grep -q "nothing to resume" err.txt && ok || bad "nothing to resume: exit $rc: $(cat err.txt)"

# a damaged checkpoint: its previous one (the run's periodic one before it) resumes, here on
# 1 thread where the run had 2 (--threads is not in the identity: results do not depend on it)
if [ -f .h.cupid-partial/.checkpoint.prev ]; then
  printf '\x55' | dd of=.h.cupid-partial/.checkpoint bs=1 seek=5000 conv=notrunc 2>/dev/null
  "$CUPID" run plate.yaml -o h "${P[@]}" --resume --threads 1 2>err.txt; rc=$? # 2 before
  [ $rc -eq 0 ] && grep -q "previous one is used" err.txt && same ref_pmb h && ok ||
    bad "a damaged checkpoint: exit $rc: $(grep -v '^cupid \[' err.txt)"
else
  bad "no previous checkpoint half-way through the run at a 0.05 s period"
fi
stop_half h2
for f in .h2.cupid-partial/.checkpoint .h2.cupid-partial/.checkpoint.prev; do
  [ -f $f ] && printf '\x55' | dd of=$f bs=1 seek=3000 conv=notrunc 2>/dev/null
done
"$CUPID" run plate.yaml -o h2 -q "${P[@]}" --resume 2>err.txt; rc=$?
[ $rc -eq 3 ] && grep -q "no intact checkpoint" err.txt && ok || bad "both damaged: exit $rc: $(cat err.txt)"

# a disk that fills while checkpointing (files may not grow past 650 KiB: every output file
# fits, the 690 KB checkpoint does not): warnings, and the results of the uninterrupted run
( trap '' XFSZ; ulimit -f 650; "$CUPID" run plate.yaml -o full "${P[@]}" 2>err.txt ); rc=$?
[ $rc -eq 0 ] && grep -q "could not be written" err.txt && same ref_pmb full && ok ||
  bad "a full disk: exit $rc: $(head -3 err.txt)"

# a second signal stops at once (no checkpoint at the next step); the periodic one resumes.
# Half of the plate's run measured now (the load of the other tests changes over this script)
t0=$(date +%s%N)
"$CUPID" run plate.yaml -o again -q "${P[@]}" 2>/dev/null
half=$(awk -v ms=$(( ($(date +%s%N) - t0) / 1000000 )) 'BEGIN { printf "%.3f", 0.5 * ms / 1000 }')
rm -rf twice
"$CUPID" run plate.yaml -o twice -q "${P[@]}" 2>/dev/null &
pid=$!
sleep "$half"; kill -TERM $pid; kill -TERM $pid; wait $pid; rc=$?
if [ $rc -eq 5 ]; then ok # the checkpoint was written before the second signal came: fine
elif [ $rc -eq 143 ]; then
  "$CUPID" run plate.yaml -o twice -q "${P[@]}" --resume 2>err.txt; rc=$?
  [ $rc -eq 0 ] && same ref_pmb twice && ok || bad "after a second signal: exit $rc: $(cat err.txt)"
else bad "a second signal: exit $rc"; fi

echo "resume: $pass passed, $fail failed"
[ $fail -eq 0 ]
