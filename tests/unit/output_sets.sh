#!/usr/bin/env bash
# A run's output files as a set (issue 19 item 3; io.h cupid_output_set): a failed rerun leaves
# the previous results byte for byte (a gnuplot that fails half-way used to leave a 0-byte PNG
# in their place); a shorter dynamic rerun removes the longer run's numbered VTU files but not
# the user's own files; a second run into a folder being written is refused; the staging
# folder of a run killed with SIGKILL is removed by the next run. Each check fails on the tree
# before issue 19 (the files were written in place, one by one).
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
M=$SRC/tests/models
PY=/usr/bin/python3

# 1. A failed rerun (its gnuplot fails after truncating the PNG) leaves the old set intact.
sed 's/^  plots: false/  plots: true/' "$M/run_errors/good_small.yaml" > good.yaml
grep -q "plots: true" good.yaml || printf '  plots: true\n' >> good.yaml
"$CUPID" run good.yaml -o D --quiet || bad "first run failed"
before=$(cd D && sha256sum * | sort)
mkdir -p fakebin
cat > fakebin/gnuplot <<'SH'
#!/bin/sh
# a gnuplot that opens its PNG (truncating it, as the real one does) and then fails
for f in *.gp; do png=$(sed -n "s/^set output '\(.*\)'.*/\1/p" "$f"); [ -n "$png" ] && : > "$png"; done
echo "gnuplot: simulated failure" >&2
exit 1
SH
chmod +x fakebin/gnuplot
if PATH=$PWD/fakebin:$PATH "$CUPID" run good.yaml -o D --quiet 2>err.txt; then
  bad "the run with a failing gnuplot succeeded"
else
  after=$(cd D && sha256sum * | sort)
  [ "$before" = "$after" ] && ok || bad "a failed rerun changed the previous results: $(diff <(echo "$before") <(echo "$after") | head -5)"
fi
[ -z "$(ls -A . | grep -E '^\.D\.cupid-run' )" ] && ok || bad "the failed run left its staging folder"

# 2. A shorter dynamic rerun: the longer run's numbered VTU files go, the user's file stays.
"$CUPID" run "$M/dynamics/pd_truss.yaml" -o T --quiet || bad "dynamic run failed"
n1=$(ls T/pd_*.vtu | wc -l)
echo "my notes" > T/notes.txt
sed 's/duration: 0.02234/duration: 0.01/' "$M/dynamics/pd_truss.yaml" > short.yaml
"$CUPID" run short.yaml -o T --quiet || bad "short dynamic run failed"
n2=$(ls T/pd_*.vtu | wc -l)
pvd=$(grep -c "<DataSet" T/model.pvd)
[ "$n2" -lt "$n1" ] && [ "$n2" -eq "$pvd" ] && ok || bad "stale VTU files: $n1 then $n2 files, model.pvd lists $pvd"
[ -f T/notes.txt ] && ok || bad "the user's file was removed"

# 3. A second run into a folder that a run is writing is refused (exit 3, the pid named).
$PY - "$PWD" <<'PYX' &
import fcntl, os, sys, time
fd = os.open(os.path.join(sys.argv[1], ".L.cupid-lock"), os.O_RDWR | os.O_CREAT)
fcntl.flock(fd, fcntl.LOCK_EX)
os.write(fd, b"4242\n")
open(os.path.join(sys.argv[1], "locked"), "w").close()
time.sleep(20)
PYX
holder=$!
for _ in $(seq 100); do [ -e locked ] && break; sleep 0.1; done
out=$("$CUPID" run good.yaml -o L --quiet 2>&1); rc=$?
kill $holder 2>/dev/null; wait $holder 2>/dev/null
[ $rc -eq 3 ] && grep -q "another cupid run (pid 4242) is writing into 'L'" <<<"$out" && ok || bad "concurrent run: exit $rc: $out"
[ ! -e L ] && ok || bad "the refused run created its output folder"

# 4. The staging folder of a killed run (a pid that no longer exists) is removed by the next.
mkdir -p .D.cupid-run-999999999 && echo partial > .D.cupid-run-999999999/summary.json
"$CUPID" run good.yaml -o D --quiet || bad "run after a killed one failed"
[ ! -e .D.cupid-run-999999999 ] && ok || bad "a dead run's staging folder was left"
finish output_sets
