#!/usr/bin/env bash
# Interrupted runs (docs/hardening.md): SIGINT or SIGTERM at a random moment of a run that takes
# about a second (mostly writing 50 MB of VTU and CSV, and gnuplot) must leave no temporary
# file and no partial file: every output file that exists afterwards is complete (summary.json
# parses, CSVs have every row, the VTU passes tests/tools/read_vtu.py, PNGs end with IEND).
# Half of the trials start from the complete outputs of an earlier run (a final file is then
# the old one or the new one, never a mix), half from nothing. Signals go either to cupid alone
# (`kill PID`) or to its whole process group, gnuplot included, as Ctrl-C in a terminal does.
# The moments are pseudo-random with a fixed seed, spread over the measured length of a run.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0; fail=0
TRIALS=${CUPID_SIGNAL_TRIALS:-8}
RANDOM=2024

cat > model.yaml <<'EOF'
title: interrupted run
materials:
  m: {E: 1000, nu: 0.25}
peridynamics:
  spacing: 1.0
  horizon: 1.5
  model: bond
  partial_volume: none
  material: m
  regions:
    - {x: [0, 50], y: [0, 60], z: [0, 50]}
analysis:
  type: evaluate
  field: ["1e-3*x*y", "1e-3*sin(z)", "1e-4*x*x"]
output:
  vtu: true
  pd_nodes: true
  plots: true
  lines:
    - {name: a, from: [0, 0, 0], to: [50, 60, 50], points: 2000}
    - {name: b, from: [25, 0, 25], to: [25, 60, 25], points: 2000}
  points:
    - {name: centre, at: [25, 30, 25], stress: true}
EOF

# check_outputs DIR: no temporary file; every file present is complete.
check_outputs() {
  python3 - "$1" "$SRC/tests/tools" <<'EOF'
import glob, json, os, sys
d, tools = sys.argv[1], sys.argv[2]
sys.path.insert(0, tools)
import read_vtu
bad = []
nodes = 50 * 60 * 50
for f in sorted(os.listdir(d)) if os.path.isdir(d) else []:
    p = os.path.join(d, f)
    try:
        if ".tmp" in f:
            bad.append(f"temporary file {f} left behind")
        elif f == "summary.json":
            s = json.load(open(p))
            if s["counts"]["pd_nodes"] != nodes: bad.append("summary.json: wrong node count")
        elif f == "pd_nodes.csv" or f.startswith("line_") and f.endswith(".csv"):
            text = open(p).read()
            rows = text.split("\n")
            want = nodes if f == "pd_nodes.csv" else 2000
            if not text.endswith("\n") or len(rows) != want + 2 or rows[-1] != "":
                bad.append(f"{f}: {len(rows) - 2} rows, expected {want}")
            elif len({r.count(",") for r in rows[:-1]}) != 1:
                bad.append(f"{f}: rows of different lengths")
        elif f.endswith(".vtu"):
            try:
                npts, _, _ = read_vtu.read(p)
                if npts != nodes: bad.append(f"{f}: {npts} points")
            except SystemExit as e:
                bad.append(f"{f}: {e}")
        elif f.endswith(".pvd"):
            import xml.etree.ElementTree as ET
            ET.parse(p)
        elif f.endswith(".png"):
            data = open(p, "rb").read()
            if not data.startswith(b"\x89PNG") or not data.endswith(b"IEND\xaeB`\x82"):
                bad.append(f"{f}: truncated PNG ({len(data)} bytes)")
        elif f.endswith(".gp"):
            if not open(p).read().endswith("\n"): bad.append(f"{f}: truncated")
        else:
            bad.append(f"unexpected file {f}")
    except Exception as e:  # a parse error is a partial file
        bad.append(f"{f}: {type(e).__name__}: {e}")
for m in bad: print("  " + m)
sys.exit(1 if bad else 0)
EOF
}

# Wait until no process of group $1 is left (gnuplot may outlive a cupid killed alone).
wait_group() {
  local pgid=$1 i p left line
  for i in $(seq 1 300); do
    left=0
    for p in /proc/[0-9]*/stat; do
      # /proc/PID/stat: "pid (name) state ppid pgrp ...": the group follows the ")"
      read -r line 2>/dev/null < "$p" || continue
      line=${line##*) }
      set -- $line
      [ "${3:-}" = "$pgid" ] && { left=1; break; }
    done
    [ "$left" -eq 0 ] && return 0
    sleep 0.1
  done
  return 1
}

# Reference runs: the shorter (warm) one sets the window of the signals; the outputs seed half
# the trials.
length_ms=1000000
for i in 1 2; do
  t0=$(date +%s%N)
  if ! "$CUPID" run model.yaml -o reference --quiet; then echo "FAIL: reference run"; exit 1; fi
  t1=$(( ($(date +%s%N) - t0) / 1000000 ))
  [ "$t1" -lt "$length_ms" ] && length_ms=$t1
done
if check_outputs reference; then pass=$((pass+1)); else echo "FAIL: reference outputs"; fail=$((fail+1)); fi
echo "reference run: $length_ms ms"

killed=0
for trial in $(seq 1 "$TRIALS"); do
  dir=out$trial
  i=$((trial - 1)) # the 8 combinations of start, signal and target in turn
  sig=$([ $(((i / 2) % 2)) -eq 0 ] && echo INT || echo TERM)
  group=$([ $(((i / 4) % 2)) -eq 0 ] && echo group || echo pid)
  want=$([ "$sig" = INT ] && echo 130 || echo 143)
  delay_ms=$(( 20 + RANDOM % (length_ms * 9 / 10 + 1) ))
  # A run that ends before its signal (the machine got faster than the reference) is checked,
  # then tried again with half the delay, up to 3 times.
  for attempt in 1 2 3; do
    rm -rf "$dir"
    if [ $((i % 2)) -eq 0 ]; then cp -r reference "$dir"; fi
    setsid "$CUPID" run model.yaml -o "$dir" --quiet &
    pid=$!
    sleep "$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))"
    if [ "$group" = group ]; then kill -s "$sig" -- "-$pid" 2>/dev/null; else kill -s "$sig" "$pid" 2>/dev/null; fi
    wait "$pid"; rc=$?
    wait_group "$pid" || { echo "FAIL: trial $trial: processes of the run still alive"; fail=$((fail+1)); }
    case $rc in
      0) ;;                                   # finished before the signal
      "$want") killed=$((killed+1)) ;;
      *) echo "FAIL: trial $trial: exit $rc after SIG$sig (expected 0 or $want)"; fail=$((fail+1)) ;;
    esac
    if check_outputs "$dir"; then
      pass=$((pass+1))
    else
      echo "FAIL: trial $trial (SIG$sig to the $group after $delay_ms ms, exit $rc): partial outputs"
      fail=$((fail+1))
    fi
    # nor the run's lock or staging folder (issue 33: both stayed, the folder empty)
    left=$(ls -A | grep -E "^\.$dir\.cupid-(lock|run-)" || true)
    if [ -n "$left" ]; then
      echo "FAIL: trial $trial (SIG$sig to the $group, exit $rc): left behind: $left"; fail=$((fail+1))
    else
      pass=$((pass+1))
    fi
    echo "trial $trial: SIG$sig to $group at $delay_ms ms: exit $rc, $(ls "$dir" 2>/dev/null | wc -l) files"
    [ "$rc" -ne 0 ] && break
    delay_ms=$((delay_ms / 2))
  done
  rm -rf "$dir"
done
# Deterministic: a stand-in gnuplot writes half a PNG, then stalls; the signal arrives while it
# stalls. The half PNG must be gone afterwards whether the signal killed gnuplot too (group) or
# only cupid (which must then stop gnuplot itself, or it would finish the file later or leave
# half of it).
mkdir -p fakebin
cat > fakebin/gnuplot <<'PY'
#!/usr/bin/env python3
import os, re, sys, time
out = re.search(r"^set output '(.*)'$", open(sys.argv[1]).read(), re.M).group(1)
with open(out, "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n" + b"\0" * 1000)
    f.flush()
    open(os.environ["CUPID_FAKE_MARK"], "w").close()
    time.sleep(5)
    f.write(b"IEND\xaeB`\x82")
PY
chmod +x fakebin/gnuplot
sed -e 's/x: \[0, 50\], y: \[0, 60\], z: \[0, 50\]/x: [0, 6], y: [0, 8], z: [0, 6]/' \
    -e '/name: b,/d' -e 's/points: 2000/points: 50/' -e 's/\[25, 30, 25\]/[3, 4, 3]/' model.yaml > small.yaml
for target in group pid; do
  for sig in INT TERM; do
    rm -rf fake_out mark
    CUPID_FAKE_MARK=$work/mark PATH=$work/fakebin:$PATH setsid "$CUPID" run small.yaml -o fake_out --quiet &
    pid=$!
    for i in $(seq 1 200); do [ -e mark ] && break; sleep 0.05; done
    if [ "$target" = group ]; then kill -s "$sig" -- "-$pid"; else kill -s "$sig" "$pid"; fi
    wait "$pid"; rc=$?
    wait_group "$pid"
    want=$([ "$sig" = INT ] && echo 130 || echo 143)
    if [ ! -e mark ] || [ "$rc" -ne "$want" ]; then
      echo "FAIL: stalled gnuplot, SIG$sig to the $target: exit $rc (expected $want)"; fail=$((fail+1))
    elif [ -e fake_out/line_a.png ]; then
      echo "FAIL: stalled gnuplot, SIG$sig to the $target: half-made line_a.png left behind"; fail=$((fail+1))
    elif [ -n "$(find fake_out -name '*.tmp*')" ]; then
      echo "FAIL: stalled gnuplot, SIG$sig to the $target: temporary files left"; fail=$((fail+1))
    elif [ -n "$(ls -A | grep -E '^\.fake_out\.cupid-(lock|run-)')" ]; then
      echo "FAIL: stalled gnuplot, SIG$sig to the $target: the lock or the staging folder left"; fail=$((fail+1))
    else
      pass=$((pass+1))
    fi
  done
done

# The signals must really have interrupted runs, not only arrived after them.
if [ "$killed" -ge $((TRIALS / 2)) ]; then pass=$((pass+1)); else echo "FAIL: only $killed of $TRIALS runs were interrupted"; fail=$((fail+1)); fi

echo "signals: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
