#!/usr/bin/env bash
# Hostile and oversized inputs (docs/hardening.md): every model of tests/models/limits/ and
# tests/models/bad/ must be answered with the expected exit status and message, quickly (each
# run under `timeout`), without allocating its size (a 1 GB address-space limit, except under
# ASan, whose shadow memory needs terabytes of address space) and without writing any output.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
L=$SRC/tests/models/limits
asan=0
if ldd "$CUPID" 2>/dev/null | grep -q libasan; then asan=1; fi


# run_case CMD MODEL EXIT MAX_SECONDS PATTERN [ARGS...]: `cupid CMD MODEL -o out ARGS` exits with
# EXIT within MAX_SECONDS, its output matches PATTERN (grep -E), and (unless EXIT is 0) out/ and
# temporary files are absent afterwards.
run_case() {
  local cmd=$1 model=$2 code=$3 max_s=$4 pattern=$5; shift 5
  local t0 t1 out rc ms
  rm -rf out
  t0=$(date +%s%N)
  if [ "$asan" -eq 0 ]; then
    out=$( (ulimit -v 1000000; exec timeout 60 "$CUPID" "$cmd" "$model" -o out "$@") 2>&1); rc=$?
  else
    out=$(timeout 60 "$CUPID" "$cmd" "$model" -o out "$@" 2>&1); rc=$?
  fi
  t1=$(date +%s%N)
  ms=$(( (t1 - t0) / 1000000 ))
  local name; name=$(basename "$model")
  if [ "$rc" -ne "$code" ]; then bad "$cmd $name -> exit $rc, expected $code: $(head -c 400 <<<"$out")"; return; fi
  if ! grep -qE -- "$pattern" <<<"$out"; then bad "$cmd $name: output does not match '$pattern': $(head -c 400 <<<"$out")"; return; fi
  if [ "$ms" -gt $((max_s * 1000)) ]; then bad "$cmd $name took $ms ms (limit $max_s s)"; return; fi
  if [ "$code" -ne 0 ] && [ -e out ]; then bad "$cmd $name left out/ behind"; rm -rf out; return; fi
  if [ -n "$(find . -name '*.tmp*' | head -1)" ]; then bad "$cmd $name left temporary files"; find . -name '*.tmp*' -delete; return; fi
  ok
}

# The catalogue of models that read fine but must be refused (or fail) when run:
# command ~ model ~ exit ~ seconds ~ pattern (grep -E) ~ extra arguments
while IFS='~' read -r cmd model code secs pattern args; do
  [ -z "$cmd" ] && continue
  # shellcheck disable=SC2086
  run_case "$cmd" "$L/$model" "$code" "$secs" "$pattern" $args
done <<'EOF'
check~huge_cells.yaml~1~1~huge_cells.yaml:[0-9]+:[0-9]+: peridynamics: the model has at least 100000000000000 PD nodes.*more than the limit of~
run~huge_cells.yaml~1~1~at least 100000000000000 PD nodes.*more than the limit of [0-9.e+]+ GB; use --max-memory~
check~huge_nodes.yaml~1~1~at least 2000000000 PD nodes and .* bonds and needs at least [0-9.e+]+ GB \(grid 96 GB~
run~huge_nodes.yaml~1~1~at least 2000000000 PD nodes.*stiffness matrix and factor~--solver direct
check~nodes_5e8.yaml~1~1~at least 500000000 PD nodes.*needs at least 815 GB \(grid 24 GB, neighbour lists 755 GB\), more than the limit of 64 GB~--max-memory 64
run~nodes_5e8.yaml~1~1~at least 500000000 PD nodes.*more than the limit of 64 GB~--max-memory 64
run~nodes_5e8.yaml~1~1~at least 500000000 PD nodes.*more than the limit of~
check~wide_horizon_bond.yaml~1~1~at least 8000000 PD nodes and 4.63e\+11 bonds~
run~wide_horizon_lps.yaml~1~1~horizon/spacing = 25 gives an LPS stencil of 6.53e\+04 offsets~
check~horizon_ratio_100.yaml~1~1~horizon_ratio_100.yaml:[0-9]+:[0-9]+: peridynamics.horizon: horizon/spacing = 100 is beyond the supported 64~
check~overlapping_regions.yaml~1~1~overlapping_regions.yaml:5:3: peridynamics: the 1001 PD regions overlap so much that building the grid would visit 1e\+09 cells~
run~line_points_total.yaml~1~1~line_points_total.yaml:13:3: output: the output lines hold 110000000 points in all, more than 100000000~
run~sampling_work.yaml~1~1~sampling the 10000000 output points against the 2001 PD regions would take 2e\+10 region tests~
check~line_outside.yaml~1~1~line_outside.yaml:13:7: output.lines\[0\]: the line from \(100, 0, 0\) to \(100, 10, 0\) lies outside the model~
run~spacing_denormal.yaml~1~1~spacing_denormal.yaml:8:7: peridynamics.regions\[0\]: x upper bound 4 is not on the lattice~
run~unconstrained_1d.yaml~2~10~the model is unconstrained: no constraint fixes the y~
run~unconstrained_line.yaml~2~10~singular or not positive definite.*check that every PD region is constrained~
check~beam_pd_unaligned.yaml~1~1~beam_pd_unaligned.yaml:[0-9]+:[0-9]+: (beam: CUF beam models are not yet supported|peridynamics.regions\[0\]: its bound y = 25 is not a beam-element end)~
check~beam_huge.yaml~1~1~beam_huge.yaml:[0-9]+:[0-9]+: ~
run~beam_huge.yaml~1~1~beam_huge.yaml:[0-9]+:[0-9]+: ~
run~dynamic_output_huge.yaml~1~5~dynamic_output_huge.yaml:[0-9]+:[0-9]+: analysis.dynamic: this run would take about .* hours and write about 486 GB in 1.12e\+08 files .*--allow-large~
check~dynamic_output_huge.yaml~0~5~dynamic run: about .* s of time stepping, 486 GB of output in 111700001 files \(over the limits~
run~explicit_pd_block.yaml~0~20~^$~--quiet --max-memory 0.2
run~../run_errors/good_small.yaml~1~1~good_small.yaml:[0-9]+:[0-9]+: peridynamics: the model has at least 128 PD nodes .*more than the limit of 1e-06 GB~--max-memory 0.000001
EOF

# Every malformed model of the catalogue: exit 1 with file:line:col, fast, no output.
n_bad=0
for f in "$SRC"/tests/models/bad/*.yaml; do
  run_case run "$f" 1 5 "$(basename "$f"):[0-9]+:[0-9]+: "
  n_bad=$((n_bad+1))
done
[ "$n_bad" -ge 50 ] && ok || bad "only $n_bad malformed models in tests/models/bad"

# Files that are not models.
run_case run /dev/zero 1 5 'the model file is too large \(more than 16 MiB\)'
head -c 17000000 /dev/zero | tr '\0' '#' > big.yaml
run_case run big.yaml 1 5 'big.yaml:1:1: the model file is too large'
: > empty.yaml
run_case run empty.yaml 1 1 'empty.yaml:1:1: the model file is empty'
run_case run "$SRC/tests/models" 3 1 'tests/models'
run_case run no_such.yaml 3 1 'no_such.yaml'
# A pipe works like a file (process substitution, generated models).
run_case check <(cat "$SRC/tests/models/run_errors/good_small.yaml") 0 5 'PD nodes: 128'
# An output directory that cannot exist: I/O error, nothing written.
run_case run "$SRC/tests/models/run_errors/good_small.yaml" 3 10 'proc' --quiet -o /proc/cupid_cannot_write_here
rm -f big.yaml empty.yaml

finish limits
