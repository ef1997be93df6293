#!/usr/bin/env bash
# The coupled stiffened panel at PD spacing h = 0.5 (tests/models/mpi/panel_pd_h05.yaml: the
# example's L9 mesh, PD regions of 8 x 40 x 40 nodes in both stringers, m = 3) against the
# converged full-L9 panel (panel_fe_fine.yaml, the mesh refined until A, B, C move by less
# than 0.2%): u_z at A and B and sigma_yy at C within the issue's 2% (observed -0.24%,
# -0.91%, -0.09%). Against the example's own full-L9 mesh the coupled panel differs by +0.62%,
# +4.77%, -2.52%: that mesh is 5.4% off the converged B (one L9 element across a 4 mm
# stringer), the PD stringer is not; both figures are printed (docs/coupling.md, "A converged
# full-L9 reference"). Also: the matrix-free GMRES converged (cupid fails the run otherwise),
# the true relative residual recomputed after it is <= 1e-7 (observed 1.5e-8; GMRES stops at
# 1e-10 of its own residual estimate, which drifts from the true one), and the z imbalance of
# Eq. 38 stays below 1% of the 20 N load (observed 0.11 N).
# Paper 000's operator as printed (`balance: none`, pinned). The default (issue 34: balanced)
# equals its own FE model instead: within 1% of the example's full-L9 mesh (observed +0.02%,
# +0.15%, -0.08%), and so shares that mesh's 5% at B against the converged L9 (docs/coupling.md,
# "The balanced fictitious-node coupling", the panel table).
# The coupled model needs the matrix-free path (the direct one takes ~17 GB): skipped (77)
# without PETSc. ~30 s on 2 cores.
if [ "${CUPID_HAVE_PETSC:-0}" != 1 ]; then
  echo "SKIP: cupid was built without PETSc (scripts/build.sh --with-petsc builds build-petsc/)"
  exit 77
fi
. "$(dirname "$0")/../tools/checks.sh"
models=$SRC/tests/models/mpi
"$CUPID" run "$models/panel_pd_h05.yaml" -o pd --quiet --set coupling.balance=none && ok || bad "coupled h = 0.5 run"
"$CUPID" run "$models/panel_pd_h05.yaml" -o bal --quiet && ok || bad "coupled h = 0.5 run, balanced"
"$CUPID" run "$models/panel_fe_fine.yaml" -o fine --quiet && ok || bad "converged full-FE run"
"$CUPID" run "$SRC/examples/panel/panel_fe_l9.yaml" -o fe --quiet && ok || bad "example full-FE run"
[ "$fail" -eq 0 ] || finish mpi_panel_fine
python3 "$SRC/tests/tools/panel_points.py" pd fine fe "coupled h=0.5,converged L9,example L9" 2 \
  && ok || bad "panel figures against the converged full L9 (above)"
python3 "$SRC/tests/tools/panel_points.py" bal fe fine "balanced h=0.5,example L9,converged L9" 1 \
  && ok || bad "the balanced panel against its own full-L9 mesh (above)"
if python3 - <<'PY'; then ok; else bad "panel residual and equilibrium (above)"; fi
import json
pd = json.load(open("pd/summary.json"))
good = True
res = pd["solver"]["residual"]
imb = abs(pd["equilibrium_imbalance"][2])
print(f"GMRES residual {res:.1e}, z imbalance {imb:.3f} N of 20 N, "
      f"{pd['solver']['iterations']} iterations ({pd['solver']['operator']})")
if not res <= 1e-7:
    print("FAIL: residual above 1e-7"); good = False
if not imb <= 0.2:
    print("FAIL: z imbalance above 1% of the load"); good = False
raise SystemExit(0 if good else 1)
PY
finish mpi_panel_fine
