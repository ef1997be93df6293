#!/usr/bin/env bash
# Explicit dynamics under mpirun with the PD grid in z slabs (issue 16, item 6): one process
# against 2 ranks (each steps its slab, exchanges its halo every step, rank 0 writes), on the
# notched plate turned so that its crack runs along z, across the slab boundary
# (tests/models/mpi/plate_slabs.yaml):
#  1. PMB with breaking (critical stretch): the same bonds broken in the same steps
#     (damage.csv byte for byte), the same first break, the final damage field and the output
#     points' histories within 1e-9 of the largest value (round-off: the energies and the
#     stable step are sums in another order; observed ~1e-14);
#  2. the same plate without fracture: energies, histories and the final field as in 1;
#  3. LPS with the critical bond-energy criterion (plate_slabs_lps.yaml): the same damage.csv
#     on 1, 2 and 3 ranks. The test reads the dilatations of both ends, which the slab's outer
#     halo has wrong: without the exchange of the owners' decisions (src/problem/fracture.c)
#     2 ranks break other bonds from step ~950 on;
#  4. the stable step: the guaranteed bound of K's rows (cupid_pd_operator_row_bound, the
#     maximum over the slabs' owned rows) makes dt stable without Lanczos on 1 and 2 ranks,
#     the same bound to 1e-12 (a maximum of the same rows' values).
# Skipped (77) without PETSc. ~40 s on 2 cores.
. "$(dirname "$0")/../tools/mpi_checks.sh"
models=$SRC/tests/models/mpi
grep -v "fracture:\|criterion:\|critical_stretch:" "$models/plate_slabs.yaml" > elastic.yaml

run() { # model out ranks
  if [ "$3" = 1 ]; then "$CUPID" run "$1" -o "$2" --quiet
  else "$MPIEXEC" -n "$3" "$CUPID" run "$1" -o "$2" --quiet; fi
}
for r in 1 2; do
  run "$models/plate_slabs.yaml" pmb$r $r && ok || bad "PMB plate on $r rank(s)"
  run elastic.yaml el$r $r && ok || bad "elastic plate on $r rank(s)"
done
for r in 1 2 3; do
  run "$models/plate_slabs_lps.yaml" lps$r $r && ok || bad "LPS plate on $r rank(s)"
done
[ "$fail" -eq 0 ] || finish mpi_fracture_dynamics

cmp pmb1/damage.csv pmb2/damage.csv && ok || bad "PMB: damage.csv differs between 1 and 2 ranks"
cmp lps1/damage.csv lps2/damage.csv && ok || bad "LPS energy: damage.csv differs, 1 and 2 ranks"
cmp lps1/damage.csv lps3/damage.csv && ok || bad "LPS energy: damage.csv differs, 1 and 3 ranks"
[ "$(ls pmb1 | grep -c '^pd_.*vtu$')" = 51 ] && [ "$(ls pmb1)" = "$(ls pmb2)" ] && ok \
  || bad "the output files differ, or not 51 VTU frames"
if python3 - <<'PY'; then ok; else bad "fields, histories and summaries (above)"; fi
import csv, json
good = True
def table(path):
    rows = list(csv.reader(open(path)))
    return rows[0], [[float(x) for x in r] for r in rows[1:]]
def close(a, b, what, rel=1e-9):
    global good
    ha, ra = table(a)
    hb, rb = table(b)
    if ha != hb or len(ra) != len(rb):
        print(f"FAIL: {what}: columns or rows differ"); good = False; return
    scale = max((abs(x) for r in ra for x in r), default=0.0)
    diff = max((abs(x - y) for r, s in zip(ra, rb) for x, y in zip(r, s)), default=0.0)
    print(f"{what}: max difference {diff:.2e} of {scale:.3g}")
    if not diff <= rel * scale:
        print(f"FAIL: {what}: above {rel:g} of the largest value"); good = False
for case in ("pmb", "el"):
    for f in ("history.csv", "energies.csv", "pd_nodes.csv"):
        close(f"{case}1/{f}", f"{case}2/{f}", f"{case} {f}")
s1, s2 = (json.load(open(f"pmb{r}/summary.json")) for r in (1, 2))
for k in ("broken_bonds", "first_break_step", "damaged_nodes"):
    if s1["fracture"][k] != s2["fracture"][k]:
        print(f"FAIL: fracture.{k}: {s1['fracture'][k]} vs {s2['fracture'][k]}"); good = False
print(f"PMB: {s1['fracture']['broken_bonds']} bonds broken, first at step "
      f"{s1['fracture']['first_break_step']}, in both")
for case in ("pmb", "el"): # the stable step from the row bound, over the slabs' owned rows
    d1, d2 = (json.load(open(f"{case}{r}/summary.json"))["dynamic"] for r in (1, 2))
    b1, b2 = d1["dt_guaranteed_stable"], d2["dt_guaranteed_stable"]
    print(f"{case}: stable step by {d1['stable_step_check']} / {d2['stable_step_check']}, "
          f"guaranteed up to {b1:.10g} / {b2:.10g}")
    if d1["stable_step_check"] != "bound" or d2["stable_step_check"] != "bound" or \
            not abs(b1 - b2) <= 1e-12 * b1:
        print(f"FAIL: {case}: the bound differs between 1 and 2 ranks, or Lanczos ran"); good = False
if s2["dynamic"].get("pd_slabs", {}).get("ranks") != 2 or "pd_slabs" in s1["dynamic"]:
    print("FAIL: the 2-rank run was not split into 2 slabs"); good = False
if s1["fracture"]["broken_bonds"] < 1000:
    print("FAIL: the crack did not run (fewer than 1000 broken bonds)"); good = False
raise SystemExit(0 if good else 1)
PY
finish mpi_fracture_dynamics
