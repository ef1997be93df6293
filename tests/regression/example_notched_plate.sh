#!/usr/bin/env bash
# The dynamic fracture example (examples/notched_plate/README.md) runs as documented and writes
# its damage outputs; shortened to 1300 steps (--set analysis.dynamic.duration=6.5e-5), just
# past the first break, on one thread (about 5 s; two threads on a busy 2-core machine spend
# most of it spinning at OpenMP barriers). The physics against LAMMPS is checked in full by
# verification.fracture_notched_plate; here:
#  1. both models pass `cupid check`;
#  2. summary.json: 1310 pre-crack bonds, first break at step 1265 at the notch tip (10.5, 20);
#  3. damage.csv: its columns, 198 nodes damaged by the pre-crack alone, no broken bond up to
#     step 1250, 6 at step 1300 (LAMMPS: 6, fracture_lammps/README.md);
#  4. pd_nodes.csv has the damage column and as many damaged nodes as damage.csv's last row;
#     the VTU series (model.pvd, 27 frames) carries the damage array; damage.png (with gnuplot);
#  5. render_damage.py (software backend: no display needed) writes its three pictures.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
E=$SRC/examples/notched_plate
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}

for m in notched_plate notched_plate_lps; do
  out=$("$CUPID" check "$E/$m.yaml" 2>&1) && ok || bad "cupid check $m.yaml: $out"
  # check reports the notch's bonds and the limit (s0 from G0 for the LPS one: 1.0000e-3)
  grep -q "pre-cracks: 1, 1310 bonds removed" <<<"$out" && grep -qE "fracture: critical stretch 0\.001" <<<"$out" \
    && ok || bad "cupid check $m.yaml does not report the pre-crack and the limit: $out"
done
"$CUPID" run "$E/notched_plate.yaml" -o run --quiet --threads 1 --set analysis.dynamic.duration=6.5e-5 \
  && ok || bad "cupid run notched_plate.yaml (shortened)"

"$PY" - run <<'PY' && ok || bad "damage outputs of the example"
import csv, json, os, sys
out = sys.argv[1]
fr = json.load(open(os.path.join(out, "summary.json")))["fracture"]
assert fr["precrack_bonds_removed"] == 1310, fr
assert fr["first_break_step"] == 1265, "first break at step %s, expected 1265" % fr.get("first_break_step")
x = fr["first_break_at"]
assert abs(x[0] - 10.5) <= 1.0 and abs(x[1] - 20.0) <= 1.0, "first break at %s, not the notch tip" % x
rows = list(csv.DictReader(open(os.path.join(out, "damage.csv"))))
cols = ["step", "t", "broken_bonds", "damaged_nodes", "max_damage", "nodes_broken"]
assert list(rows[0].keys()) == cols, list(rows[0].keys())
assert [int(r["step"]) for r in rows] == list(range(0, 1301, 50)), "damage.csv steps"
assert int(rows[0]["damaged_nodes"]) == 198 and int(rows[0]["broken_bonds"]) == 0, rows[0]
assert all(int(r["broken_bonds"]) == 0 for r in rows if int(r["step"]) <= 1250)
assert int(rows[-1]["broken_bonds"]) == 6, "broken bonds at step 1300: %s (LAMMPS 6)" % rows[-1]["broken_bonds"]
nodes = list(csv.DictReader(open(os.path.join(out, "pd_nodes.csv"))))
assert len(nodes) == 4800 and "damage" in nodes[0], "pd_nodes.csv: no damage column"
damaged = sum(float(r["damage"]) > 0 for r in nodes)
assert damaged == int(rows[-1]["damaged_nodes"]), (damaged, rows[-1]["damaged_nodes"])
pvd = open(os.path.join(out, "model.pvd")).read()
assert pvd.count("<DataSet") == 27, "model.pvd: %d frames, expected 27" % pvd.count("<DataSet")
with open(os.path.join(out, "pd_001300.vtu")) as f:
    assert 'Name="damage"' in f.read(4000), "pd_001300.vtu has no damage array"
print("first break at step %d at %s; %s broken bonds, %d damaged nodes at step 1300"
      % (fr["first_break_step"], x, rows[-1]["broken_bonds"], damaged))
PY

if command -v gnuplot > /dev/null; then
  [ -s run/damage.png ] && ok || bad "plots: true wrote no damage.png"
fi

out=$("$PY" "$E/render_damage.py" run -o pics --backend software 2>&1) && ok || bad "render_damage.py: $out"
for p in mid end strip; do
  [ -s "pics/damage_field_$p.png" ] && ok || bad "render_damage.py wrote no damage_field_$p.png"
done

finish example_notched_plate
