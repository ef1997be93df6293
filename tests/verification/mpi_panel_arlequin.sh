#!/usr/bin/env bash
# The Arlequin panel (examples/panel/panel_pd_l9_arlequin.yaml: both stringers PD over
# y [280, 320], overlaps y [280, 290], [310, 320] and z [2, 7]) at PD spacing h = 0.5 (m = 3,
# 8 x 80 x 40 nodes a stringer, 51,200 in all; kappa 5e4 = 10 E h) on the matrix-free
# Arlequin path (`--solver petsc`: the node-weighted LPS operator, CG preconditioned by the
# Cholesky factor of the cheap weighted twin), against the example's full L9 (panel_fe_l9.yaml; the
# Arlequin beam mesh moves it by <= 0.02%): u_z at A and B and sigma_yy at C within the
# issue's 2% (observed -0.11%, -0.78%, +0.42%; at h = 1 B was +2.44%: the 4-node-thick PD
# stringer). The converged full-L9 panel (tests/models/mpi/panel_fe_fine.yaml) is printed
# beside it, not bounded (-0.96%, -6.2%, +2.9%: with both models in the overlaps the coupled
# panel keeps the coarse L9 stringer's twist at B). Also: CG converged in <= 100 iterations
# (observed 32: the cheap twin is a good preconditioner), the true residual <= 1e-6 (observed
# 7e-8: the penalty makes K ill-conditioned, so CG's 1e-10 is not reached in the true
# residual), equilibrium to 1e-6 of the load (symmetric, momentum-conserving).
# The assembled matrix would hold 278 M blocks (20 GB): skipped (77) without PETSc. ~20 s and
# 2.6 GB on 2 cores.
if [ "${CUPID_HAVE_PETSC:-0}" != 1 ]; then
  echo "SKIP: cupid was built without PETSc (scripts/build.sh --with-petsc builds build-petsc/)"
  exit 77
fi
. "$(dirname "$0")/../tools/checks.sh"
sed -e 's/  spacing: 1.0/  spacing: 0.5/; s/  horizon: 3.0/  horizon: 1.5/; s/penalty: 1.0e5/penalty: 5.0e4/' \
  "$SRC/examples/panel/panel_pd_l9_arlequin.yaml" > h05.yaml
grep -q "spacing: 0.5" h05.yaml && grep -q "penalty: 5.0e4" h05.yaml && ok || bad "model edits"
"$CUPID" run h05.yaml -o arl --solver petsc --quiet && ok || bad "Arlequin h = 0.5 run"
"$CUPID" run "$SRC/examples/panel/panel_fe_l9.yaml" -o fe --quiet && ok || bad "full-FE run"
"$CUPID" run "$SRC/tests/models/mpi/panel_fe_fine.yaml" -o fine --quiet && ok || bad "converged full-FE run"
[ "$fail" -eq 0 ] || finish mpi_panel_arlequin
python3 "$SRC/tests/tools/panel_points.py" arl fe fine "Arlequin h=0.5,full L9,converged L9" 2 \
  && ok || bad "Arlequin panel figures against full L9 (above)"
if python3 - <<'PY'; then ok; else bad "Arlequin solve (above)"; fi
import json
arl = json.load(open("arl/summary.json"))
good = True
s = arl["solver"]
imb = max(abs(v) for v in arl["equilibrium_imbalance"])
load = max(abs(v) for v in arl["applied_load_sum"])
print(f"{s['ksp_type']} + {s['pc_type']}, {s['operator']}: {s['iterations']} iterations, true "
      f"residual {s['residual']:.1e}; imbalance {imb / load:.1e} of the load; "
      f"{arl['counts']['pd_nodes']} PD nodes, {arl['total_time_s']:.1f} s, "
      f"{arl['peak_memory_bytes'] / 1e9:.2f} GB")
if not (s["operator"] == "matrix-free" and s["ksp_type"] == "cg" and s["iterations"] <= 100):
    print("FAIL: not the matrix-free CG path, or more than 100 iterations"); good = False
if not s["residual"] <= 1e-6:
    print("FAIL: true residual above 1e-6"); good = False
if not imb <= 1e-6 * load:
    print("FAIL: equilibrium"); good = False
if arl["counts"]["pd_nodes"] != 51200:
    print("FAIL: PD nodes", arl["counts"]["pd_nodes"]); good = False
raise SystemExit(0 if good else 1)
PY
finish mpi_panel_arlequin
