#!/usr/bin/env bash
# The command line: options, exit codes and error messages (model-format.md, "Command line"),
# and the promise that a failed run never leaves a file behind.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
M=$SRC/tests/models/run_errors
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0; fail=0

# expect CODE PATTERN -- command...: exit status CODE and stderr+stdout matching PATTERN.
expect() {
  local code=$1 pattern=$2; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" -ne "$code" ]; then
    echo "FAIL: $* -> exit $rc, expected $code"; echo "$out" | head -5; fail=$((fail+1)); return
  fi
  if ! grep -qE -- "$pattern" <<<"$out"; then
    echo "FAIL: $* -> output does not match '$pattern':"; echo "$out" | head -5; fail=$((fail+1)); return
  fi
  pass=$((pass+1))
}

expect 0 '^cupid [0-9]+\.[0-9]+\.[0-9]+ \(solvers: direct(, petsc)?\)$' -- "$CUPID" --version
expect 0 'cupid run MODEL.yaml' -- "$CUPID" --help
expect 1 'usage: cupid run' -- "$CUPID"
expect 1 "unknown command 'frobnicate'" -- "$CUPID" frobnicate
expect 1 'missing the model file' -- "$CUPID" run
expect 1 "unknown option '--bogus'" -- "$CUPID" run "$M/good_small.yaml" --bogus
expect 1 "unknown solver 'magic'" -- "$CUPID" run "$M/good_small.yaml" --solver magic
expect 1 'expected a positive integer' -- "$CUPID" run "$M/good_small.yaml" --threads -2
expect 1 'expected a positive number of GB' -- "$CUPID" run "$M/good_small.yaml" --max-memory zero
expect 3 'no_such_model.yaml' -- "$CUPID" run no_such_model.yaml
# Without the engine `--solver petsc` is refused; with it (build-petsc/) the same model solves.
if "$CUPID" --version | grep -q petsc; then
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    expect 0 '' -- "$CUPID" run "$M/good_small.yaml" --solver petsc -o out_petsc
  rm -rf out_petsc   # a successful run; the check below is for failed ones
else
  expect 1 'no PETSc engine' -- "$CUPID" run "$M/good_small.yaml" --solver petsc -o out_petsc
fi

# Semantic errors found after reading: the file, line and key of the culprit.
expect 2 'unconstrained' -- "$CUPID" run "$M/unconstrained.yaml" -o o1
expect 2 'unconstrained: no constraint fixes the y z displacement' -- "$CUPID" run "$M/fixed_only_x.yaml" -o o2
# progress in a batch log (stderr not a terminal): of 2000 load steps the first, the last,
# every tenth and at most one a second (issue 33, item 9: a line a step, 11 MB at 10^5 steps)
out=$("$CUPID" run "$SRC/tests/models/growth/plate.yaml" -o o_steps --set analysis.steps=2000 \
      --set peridynamics.fracture.critical_stretch=1 2>&1 >/dev/null)
n=$(grep -c "growth: step" <<<"$out")
t=$(python3 -c "import json; print(int(json.load(open('o_steps/summary.json'))['total_time_s']) + 1)")
if [ "$n" -ge 11 ] && [ "$n" -le $((11 + t)) ] && grep -q "growth: step 1 / 2000" <<<"$out" \
   && grep -q "growth: step 2000 / 2000" <<<"$out"; then pass=$((pass+1))
else echo "FAIL: $n progress lines of 2000 load steps in $t s"; fail=$((fail+1)); fi
# threads wait passively unless the user chose (issue 33, item 14: spinning threads on a busy
# machine made a 6 s run take 71 s): summary.json records the policy the run had
env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$CUPID" run "$M/good_small.yaml" -o o_wait --quiet
env -u GOMP_SPINCOUNT OMP_WAIT_POLICY=active "$CUPID" run "$M/good_small.yaml" -o o_wait_active --quiet
if python3 -c "import json, sys
a = json.load(open('o_wait/summary.json'))['omp_wait_policy']
b = json.load(open('o_wait_active/summary.json'))['omp_wait_policy']
sys.exit(not (a == 'PASSIVE' and b == 'active'))"; then pass=$((pass+1))
else echo "FAIL: the OpenMP wait policy (default PASSIVE, the user's kept)"; fail=$((fail+1)); fi
# Lagrange multipliers hold cracks now (issue 34), whose tie is their coupling zone: a pre-crack
# that reaches it is a model error naming its line; so do fictitious nodes, whose zone is the
# span of their fictitious FE elements and the families of their fictitious nodes
expect 1 'senb_coupled.yaml: --set peridynamics.precracks\[0\].at=32: peridynamics.precracks\[0\] \(.*senb_coupled.yaml:[0-9]+:[0-9]+\): a pre-crack reaches the coupling zone at the PD node \(0.5, 30.5, 0.5\) \(coupling method lagrange' -- "$CUPID" check "$SRC/examples/fracture/senb_coupled.yaml" --set 'coupling={method: lagrange}' --set 'peridynamics.precracks[0].at=32'
expect 1 'senb_coupled.yaml: --set peridynamics.precracks\[0\].at=36: peridynamics.precracks\[0\] \(.*senb_coupled.yaml:[0-9]+:[0-9]+\): a pre-crack reaches the coupling zone at the PD node .* \(coupling method fictitious: the fictitious-node coupling zone of PD region 0 \(peridynamics.regions\[0\], line [0-9]+' -- "$CUPID" check "$SRC/examples/fracture/senb_coupled.yaml" --set 'coupling={method: fictitious}' --set 'peridynamics.precracks[0].at=36'
expect 0 'the model is valid' -- "$CUPID" check "$SRC/examples/fracture/senb_coupled.yaml" --set 'coupling={method: fictitious}'
# check runs every check that run runs before solving (issue 33, item 7: check said "valid"):
# the constraints of a static model, and the stable step of central differences
expect 2 'unconstrained: no constraint fixes the y z displacement' -- "$CUPID" check "$M/fixed_only_x.yaml"
expect 1 'notched_plate.yaml: --set analysis.dynamic.dt=1e-5: analysis.dynamic \(.*\): central differences are unstable with dt = 1e-05' -- "$CUPID" check "$SRC/examples/notched_plate/notched_plate.yaml" --set analysis.dynamic.dt=1e-5
expect 0 'the model is valid' -- "$CUPID" check "$SRC/examples/notched_plate/notched_plate.yaml"
expect 2 'singular|not positive definite' -- "$CUPID" run "$M/two_blocks_apart.yaml" -o o3
expect 1 'constraint_empty.yaml:[0-9]+:[0-9]+: constraints\[0\].*no PD node' -- "$CUPID" run "$M/constraint_empty.yaml" -o o4
expect 1 'point_outside.yaml:[0-9]+:[0-9]+: output.points\[0\].*outside' -- "$CUPID" run "$M/point_outside.yaml" -o o5
expect 1 'traction_no_face.yaml:[0-9]+:[0-9]+: loads\[0\].*no free PD surface' -- "$CUPID" run "$M/traction_no_face.yaml" -o o6
expect 1 'point_load_outside.yaml:[0-9]+:[0-9]+: loads\[0\].*outside every PD region' -- "$CUPID" run "$M/point_load_outside.yaml" -o o7
expect 1 'off_lattice.yaml:[0-9]+:[0-9]+: peridynamics.regions\[1\]' -- "$CUPID" run "$M/off_lattice.yaml" -o o8
# shapes (issue 35): a sphere between the lattice's cell centres; holes that remove the body
expect 1 'shape_no_centre.yaml:[0-9]+:[0-9]+: peridynamics.regions\[1\]: the sphere holds no cell centre of the lattice' -- "$CUPID" check "$M/shape_no_centre.yaml"
expect 1 'hole_removes_all.yaml:[0-9]+:[0-9]+: peridynamics: the regions hold no node: the holes remove all of them' -- "$CUPID" run "$M/hole_removes_all.yaml" -o o8
# Arlequin: PD regions may touch but not share a volume, and no face may meet the beam and
# another region (a re-entrant corner facing the beam)
expect 1 'arlequin_regions_overlap.yaml:[0-9]+:[0-9]+: peridynamics.regions\[1\]: this PD region shares a volume with PD region 0' -- "$CUPID" run "$M/arlequin_regions_overlap.yaml" -o o8
expect 1 'arlequin_reentrant_face.yaml:[0-9]+:[0-9]+: peridynamics.regions\[0\]: the face y = 16 of this PD region meets another PD region on part of it and the beam on the rest' -- "$CUPID" run "$M/arlequin_reentrant_face.yaml" -o o8
# `cupid check` resolves constraints and loads through the run's code (issue 19): what run
# refuses for a model error, check refuses too, with the same message.
expect 1 'constraint_empty.yaml:[0-9]+:[0-9]+: constraints\[0\].*no PD node' -- "$CUPID" check "$M/constraint_empty.yaml"
expect 1 'traction_no_face.yaml:[0-9]+:[0-9]+: loads\[0\].*no free PD surface' -- "$CUPID" check "$M/traction_no_face.yaml"
expect 1 'point_load_outside.yaml:[0-9]+:[0-9]+: loads\[0\].*outside every PD region' -- "$CUPID" check "$M/point_load_outside.yaml"
# Non-finite values are failures, never results (issue 19): from the model, a model error at
# the expression's key and the point; from the numerics, exit 2.
expect 1 'load_nan.yaml:13:5: loads\[0\]: the load is not finite \(-?nan\) at PD node \(0.5, 5.5, 0.5\)' -- "$CUPID" run "$M/load_nan.yaml" -o o9
expect 1 'load_inf.yaml:13:5: loads\[0\]: the load is not finite \(inf\)' -- "$CUPID" run "$M/load_inf.yaml" -o o9
expect 1 'displacement_nan.yaml:11:5: constraints\[0\]: the prescribed displacement is not finite' -- "$CUPID" run "$M/displacement_nan.yaml" -o o9
# ... and one that turns non-finite mid-run (issue 33: was "DOF 3598 is not finite at t = ...",
# exit 2, without the constraint or the node)
expect 1 'displacement_blowup.yaml:12:5: constraints\[1\]: at t = 0.005 the prescribed displacement is not finite \(inf\) at PD node \(0.5, 6.5, 0.5\), component y' -- "$CUPID" run "$M/displacement_blowup.yaml" -o o9
expect 1 'initial_nan.yaml:[0-9]+:[0-9]+: analysis.dynamic: the initial velocity is not finite' -- "$CUPID" run "$M/initial_nan.yaml" -o o9
expect 2 'not finite' -- "$CUPID" run "$M/newmark_unstable.yaml" -o o9
expect 2 'numerical error' -- "$CUPID" run "$M/rayleigh_huge.yaml" -o o9
# --set key.path=value overrides a value of the model file, validated as the file's (issue 19).
"$CUPID" run "$M/good_small.yaml" -o s1 --quiet && "$CUPID" run "$M/good_small.yaml" -o s2 --quiet \
  --set 'loads[0].traction.value=[0, 2, 0]' --set analysis.solver=direct
if /usr/bin/python3 -c "
import json, sys
a, b = (json.load(open(d + '/summary.json')) for d in sys.argv[1:3])
sys.exit(not (abs(b['points'][0]['uy'] - 2 * a['points'][0]['uy']) <= 1e-9 * abs(a['points'][0]['uy'])
              and b['solver']['method'] == 'cholmod'))" s1 s2; then pass=$((pass+1)); else echo "FAIL: --set did not double the load"; fail=$((fail+1)); fi
expect 1 'good_small.yaml: --set peridynamics.spacing=-1: peridynamics.spacing: must be > 0, got -1' -- "$CUPID" run "$M/good_small.yaml" -o o9 --set peridynamics.spacing=-1
expect 1 "--set analysis.solvr=direct: analysis.solvr: unknown key; did you mean 'solver'" -- "$CUPID" run "$M/good_small.yaml" -o o9 --set analysis.solvr=direct
expect 1 '--set loads\[3\].traction.value=1: loads\[3\] does not exist \(1 items\)' -- "$CUPID" run "$M/good_small.yaml" -o o9 --set 'loads[3].traction.value=1'
expect 1 '--set nokey: expected key.path=value' -- "$CUPID" run "$M/good_small.yaml" -o o9 --set nokey
# an error about an item of the file whose value an override gave cites the override, and the
# item's line (issue 33: it cited the file's line alone)
expect 1 'good_small.yaml: --set loads\[0\].traction.y=9: loads\[0\] \(.*good_small.yaml:[0-9]+:[0-9]+\): ' -- "$CUPID" check "$M/good_small.yaml" --set 'loads[0].traction.y=9'
expect 0 'cupid run MODEL.yaml' -- "$CUPID" run --help
expect 1 'option -o needs a directory' -- "$CUPID" run "$M/good_small.yaml" -o ""
for d in out_petsc o1 o2 o3 o4 o5 o6 o7 o8 o9; do
  if [ -e "$d" ]; then echo "FAIL: failed run left $d behind"; fail=$((fail+1)); else pass=$((pass+1)); fi
done

# A good run, `check`, and quiet output.
expect 0 '' -- "$CUPID" run "$M/good_small.yaml" -o good --quiet
for f in summary.json line_axis.csv pd_nodes.csv pd.vtu model.pvd; do
  if [ -s "good/$f" ]; then pass=$((pass+1)); else echo "FAIL: good/$f missing"; fail=$((fail+1)); fi
done
expect 0 'PD nodes: 128' -- "$CUPID" check "$M/good_small.yaml"
[ -e out/good_small ] && { echo "FAIL: check wrote outputs"; fail=$((fail+1)); } || pass=$((pass+1))
expect 1 'more than the limit' -- "$CUPID" run "$M/good_small.yaml" -o o9 --max-memory 0.000001

# An output directory that cannot be created: I/O error, exit 3, nothing half-written.
touch blocker
expect 3 'blocker' -- "$CUPID" run "$M/good_small.yaml" -o blocker/out
# A file that cannot be replaced: summary.json is a directory, so its rename fails.
mkdir -p busy/summary.json
expect 3 'summary.json' -- "$CUPID" run "$M/good_small.yaml" -o busy
leftovers=$(find . -name '*.tmp*' | wc -l)
if [ "$leftovers" -eq 0 ]; then pass=$((pass+1)); else echo "FAIL: $leftovers temporary files left"; find . -name '*.tmp*'; fail=$((fail+1)); fi

# The Poisson-locking correction (beam.poisson_correction): cupid check names it when it is on
# (TE0/TE1 under auto), summary.json's beam block records it, --set beam.poisson_correction=off
# turns it off, and 'on' with TE2 is refused at the key.
T=$SRC/examples/truss/truss_fe.yaml
expect 0 'Poisson-locking correction on' -- "$CUPID" check "$T"
expect 0 '' -- "$CUPID" run "$T" -o pc_auto --quiet --set analysis.dynamic.duration=1e-4 --set output.vtu=false --set output.plots=false
expect 0 '' -- "$CUPID" run "$T" -o pc_off --quiet --set analysis.dynamic.duration=1e-4 --set output.vtu=false --set output.plots=false --set beam.poisson_correction=off
expect 0 '"poisson_correction": true' -- cat pc_auto/summary.json
expect 0 '"poisson_correction": false' -- cat pc_off/summary.json
expect 0 '"expansion": "TE0"' -- cat pc_off/summary.json
expect 1 "beam.poisson_correction: 'on' applies to TE0 and TE1 only" -- "$CUPID" check "$SRC/examples/bar/bar_fe_te2.yaml" --set beam.poisson_correction=on

# Every malformed model of the catalogue: exit 1 with file:line:col, never a crash, no output.
for f in "$SRC"/tests/models/bad/*.yaml; do
  [ -e "$f" ] || continue
  out=$("$CUPID" run "$f" -o bad_out 2>&1); rc=$?
  name=$(basename "$f")
  if [ "$rc" -ne 1 ]; then echo "FAIL: $name -> exit $rc, expected 1: $out"; fail=$((fail+1)); continue; fi
  if ! grep -qE "$name:[0-9]+:[0-9]+: " <<<"$out"; then echo "FAIL: $name: no file:line:col in '$out'"; fail=$((fail+1)); continue; fi
  if [ -e bad_out ]; then echo "FAIL: $name left output"; rm -rf bad_out; fail=$((fail+1)); continue; fi
  pass=$((pass+1))
done

# Crack growth's peak on the direct path (estimate.c, GROWTH_COPY_BYTES_PER_ENTRY): CHOLMOD's
# factor copied into its simplicial form for the downdates. `check` prints it; auto keeps the
# factorisation for growth while it stays within three quarters of the limit (here 4.98 GB, so
# a limit of 6.5 GB puts the growth on krylov, 7 GB on direct: with the static peak of 3.13 GB
# alone both would say direct); `--solver direct` refuses a growth that would pass the limit.
S=$SRC/examples/fracture/senb_coupled.yaml
h2=(--set peridynamics.spacing=0.5 --set peridynamics.horizon=1.5075)
expect 0 'direct path: 3\.13 GB' -- "$CUPID" check "$S" "${h2[@]}"
expect 0 'crack growth on the direct path: 4\.98 GB' -- "$CUPID" check "$S" "${h2[@]}"
expect 0 'solver auto would pick: krylov' -- "$CUPID" check "$S" "${h2[@]}" --max-memory 6.5
expect 0 'solver auto would pick: direct' -- "$CUPID" check "$S" "${h2[@]}" --max-memory 7
expect 1 'factor .* copied for crack growth' -- "$CUPID" run "$S" -o big "${h2[@]}" --solver direct --max-memory 4
[ -e big ] && { echo "FAIL: the refused run left big/"; fail=$((fail+1)); } || pass=$((pass+1))

echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
