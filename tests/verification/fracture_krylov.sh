#!/usr/bin/env bash
# Quasi-static crack growth on the built-in iterative engine (`--solver krylov`, no PETSc): what
# `solver: auto` picks where the direct factor does not fit (issue 38: the coupled SENB at
# 80,000 PD nodes). Every run below must break the same bonds in the same steps as the direct
# path (CHOLMOD, the factor downdated by the broken bonds): damage.csv's counts equal row by
# row, every node's final damage equal to the bit, the reactions and the load point's
# displacement within 1e-8 of the largest (each solve stops at a relative residual of 1e-12 on
# the direct path and 1e-10 here; a crack that took another path would differ by O(1)):
#  - the coupled SENB of examples/fracture (Arlequin) at h = 5/3, bond-based and LPS: the
#    method's operator matrix-free, CG preconditioned by the kept factor of its bond-based
#    twin (CHOLMOD), re-run from the last solution after each round of breaks
#    (src/problem/growth_matrix_free.c), as the PETSc engine's kept solve with MUMPS;
#  - the same SENB with fictitious nodes (non-symmetric): GMRES on the twin's kept UMFPACK LU;
#  - tests/models/growth/senb_interface.yaml: the crack reaches the overlap, and the run stops
#    at the same step with the same message (exit 2);
#  - the PD-only plate of tests/models/growth (assembled: the krylov engine's assembled solve is
#    the factorisation, so growth keeps its own factor and downdates it, as on the direct
#    engine; before, every re-solve factorised K afresh);
#  - `cupid check` names the way each engine re-solves.
. "$(dirname "$0")/../tools/checks.sh"
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
E=$SRC/examples/fracture/senb_coupled.yaml
I=$SRC/tests/models/growth/senb_interface.yaml
P=$SRC/tests/models/growth/plate.yaml
coarse=(--quiet --set output.pd_nodes=true --set analysis.steps=20 --set "constraints[0].displacement.value=[-0.03, null, null]"
        --set peridynamics.spacing=1.6666666666666667 --set peridynamics.horizon=5.025
        --set output.vtu=false --set output.plots=false)
fic=(--set 'coupling={method: fictitious}' --set output.pd_nodes=true)

# Under the sanitizers (CUPID_TEST_SANITIZED=1: 5-15 times slower) the CG and GMRES paths and
# the assembled one only: LPS and the stop take the same code (docs/hardening.md).
full=1
[ "${CUPID_TEST_SANITIZED:-0}" = 1 ] && full=0
for s in direct krylov; do
  "$CUPID" run "$E" -o senb_$s "${coarse[@]}" --solver $s && ok || bad "SENB, $s"
  "$CUPID" run "$E" -o fic_$s "${coarse[@]}" "${fic[@]}" --solver $s && ok || bad "SENB, fictitious nodes, $s"
  "$CUPID" run "$P" -o plate_$s --quiet --set output.pd_nodes=true --solver $s && ok || bad "PD plate, $s"
  [ $full = 1 ] || continue
  "$CUPID" run "$E" -o lps_$s "${coarse[@]}" --set peridynamics.model=lps --solver $s && ok || bad "SENB, LPS, $s"
  "$CUPID" run "$I" -o stop_$s --quiet --solver $s 2> stop_$s.err
  [ $? -eq 2 ] && ok || bad "SENB into an overlap, $s: exit status 2 ($(tail -1 stop_$s.err))"
done
# cupid check says how each would re-solve
expect 0 "crack growth on krylov: each re-solve iterates from the last solution" -- "$CUPID" check "$E" --solver krylov
expect 0 "crack growth on direct: one factorisation, downdated" -- "$CUPID" check "$E" --solver direct
expect 0 "crack growth on krylov: one factorisation, downdated" -- "$CUPID" check "$P" --solver krylov
msg() { grep -o "cupid: crack growth stopped.*" "$1"; }
[ $full = 0 ] || { [ -n "$(msg stop_direct.err)" ] && [ "$(msg stop_direct.err)" = "$(msg stop_krylov.err)" ]; } &&
  ok || bad "the same stop message: $(msg stop_krylov.err)"

"$PY" - $full "$SRC/tests/tools" <<'PY' && ok || bad "the same bonds on the direct and krylov engines"
import json, sys
full = sys.argv[1] == "1"
sys.path.insert(0, sys.argv[2])
from same_growth import rows, same
kinds = ("senb", "fic", "plate") + (("lps",) if full else ())
for k in kinds:
    same(k + "_direct", k + "_krylov")
    assert int(rows(k + "_direct")[-1]["broken_bonds"]) > 100, (k, rows(k + "_direct")[-1])
if full:
    same("stop_direct", "stop_krylov", nodes=False)
coupled = ("senb_krylov", "fic_krylov") + (("lps_krylov", "stop_krylov") if full else ())
s = {d: json.load(open(d + "/summary.json")) for d in coupled + ("plate_krylov",)}
for d in coupled:
    sv = s[d]["fracture"]["solves"]
    assert sv["resolve"] == "matrix-free" and s[d]["solver"]["operator"] == "matrix-free", (d, sv)
    assert s[d]["solver"]["engine"] == "krylov", (d, s[d]["solver"])
    print("%s: %d solves, %d iterations (%.1f a solve)" % (d, sv["solves"], sv["cg_iterations"],
                                                          sv["cg_iterations"] / sv["solves"]))
assert s["senb_krylov"]["solver"]["pc_type"] == "cholmod", s["senb_krylov"]["solver"]
assert s["fic_krylov"]["solver"]["pc_type"] == "umfpack", s["fic_krylov"]["solver"]
# the plate's assembled K: its own factor, downdated, as the direct engine's
sv = s["plate_krylov"]["fracture"]["solves"]
assert sv["resolve"] == "downdate" and sv["downdates"] > 0 and sv["factorisations"] < 5, sv
PY
finish fracture_krylov
