#!/usr/bin/env bash
# The PETSc/MPI engine (issue 6) against the direct solver, on 2 MPI ranks:
#  1. a small coupled bar (fictitious nodes, non-symmetric Eq. 38: GMRES), assembled MPIAIJ
#     (--assembled), matrix-free with the PD grid in z slabs (the default) and
#     matrix-free with the model replicated (--replicate) on 2 ranks; the C-beam's web
#     region over part of the section (fictitious nodes beyond its z faces) in slabs,
#  1b. the same bar on one process: matrix-free Eq. 38 (src/coupling/operator.c, krylov.c),
#  1c. the coupled bar with Arlequin (symmetric: CG), 2 ranks: matrix-free (the default: the
#      PD grid split into z slabs, one per rank, the node-weighted PD operator, CG + MUMPS
#      Cholesky of the cheap twin) and assembled (--assembled: CG + GAMG on K's
#      rows); the Arlequin panel (two regions over part of the section) in slabs on 2 ranks,
#  2. a small PD-only LPS block (matrix-free MATSHELL + halo exchange, CG + GAMG), with a
#     prescribed non-zero displacement (lifted right-hand side),
#  2b. a PD-only column long in z, split into slabs: each rank builds only its z layers and the
#     halo (the grid is partitioned in memory); stresses and reactions gathered on rank 0,
#  3. the model key `analysis.solver: petsc` on one process, PETSc options passed through,
#  4. solver auto: direct for the small block, PETSc when --max-memory makes it large,
#  5. a forced divergence: exit 2 with PETSc's reason, printed once.
# Every displacement (PD nodes, line and point samples) must match the direct solve to 1e-8
# relative to the largest displacement: the Krylov solves stop at a relative residual of 1e-12
# and the preconditioned systems are well conditioned, so ~1e-10 is expected; 1e-8 is the
# issue's contract. Skipped (exit 77) when cupid is built without PETSc.
set -euo pipefail
: "${CUPID:?path to the cupid binary}" "${CUPID_SOURCE_DIR:?source directory}"
if [ "${CUPID_HAVE_PETSC:-0}" != 1 ]; then
  echo "SKIP: cupid was built without PETSc (configure with -DCUPID_WITH_PETSC=ON, or"
  echo "      scripts/build.sh --with-petsc, which builds build-petsc/)"
  exit 77
fi
MPIEXEC=${CUPID_MPIEXEC:-mpiexec}
# OpenMPI refuses root unless told (CI containers run as root); one OpenMP thread per rank on
# the 2-core machines.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
export OMPI_MCA_rmaps_base_oversubscribe=1
models=$CUPID_SOURCE_DIR/tests/models/mpi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

compare() { # direct-dir petsc-dir label
  python3 - "$1" "$2" "$3" <<'PY'
import csv, glob, json, os, sys
d, p, label = sys.argv[1:4]
def columns(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [float(r[k]) for r in rows for k in ("ux", "uy", "uz") if k in r]
ref, got = [], []
files = sorted(os.path.basename(f) for f in glob.glob(os.path.join(d, "*.csv")))
assert files, "no CSV outputs in " + d
for name in files:
    a, b = columns(os.path.join(d, name)), columns(os.path.join(p, name))
    assert len(a) == len(b), (name, len(a), len(b))
    ref += a; got += b
sd, sp = (json.load(open(os.path.join(x, "summary.json"))) for x in (d, p))
for a, b in zip(sd["points"], sp["points"]):
    for k in ("ux", "uy", "uz"):
        ref.append(a[k]); got.append(b[k])
scale = max(abs(v) for v in ref)
err = max(abs(a - b) for a, b in zip(ref, got)) / scale
s = sp["solver"]
print(f"{label}: {len(ref)} displacements, max |u_petsc - u_direct| / max |u| = {err:.2e} "
      f"({s['ksp_type']} + {s['pc_type']}, {s['iterations']} iterations, {s['ranks']} ranks, "
      f"{s['operator']}, residual {s['residual']:.1e})")
assert s["method"] == "petsc" and s["converged_reason"].startswith("CONVERGED"), s
assert err <= 1e-8, f"{label}: PETSc and direct solutions differ by {err:.3e} > 1e-8"
PY
}

slabs_agree() { # direct-dir slab-dir label ksp: the PD grid was split into 2 z slabs (each
  # rank built only its layers + halo) and the counts and equilibrium match the direct solve's
  python3 - "$1/summary.json" "$2/summary.json" "$3" "$4" <<'PY'
import json, sys
d, p = (json.load(open(f)) for f in sys.argv[1:3])
s = p["solver"]
assert s["ranks"] == 2 and s["ksp_type"] == sys.argv[4] and s["operator"] == "matrix-free", s
assert s["pd_slabs"]["ranks"] == 2, s
for k in ("pd_nodes", "fe_dofs", "bonds", "constrained_dofs", "fictitious_nodes"):
    assert d["counts"][k] == p["counts"][k], (k, d["counts"][k], p["counts"][k])
assert s["equations"] == d["solver"]["equations"], (s["equations"], d["solver"]["equations"])
# reactions from the slabs' K u (owned rows + FE rows summed over the ranks): the direct
# solve's equilibrium imbalance (Arlequin: ~0; fictitious nodes: Eq. 38 does not conserve
# momentum) to 1e-6 of the load (the penalty kappa = 10 E h makes the Arlequin K stiff)
load = max(abs(v) for v in p["applied_load_sum"])
imb = max(abs(a - b) for a, b in zip(p["equilibrium_imbalance"], d["equilibrium_imbalance"])) / load
print(f"{sys.argv[3]}: largest slab {s['pd_slabs']['largest_slab_nodes']} of "
      f"{p['counts']['pd_nodes']} PD nodes, imbalance differs from the direct one by {imb:.1e} "
      f"of the load")
assert imb <= 1e-6, imb
PY
}

echo "== coupled bar (fictitious nodes), 2 ranks, assembled Eq. 38 (--assembled)"
"$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_direct" --solver direct --quiet --set coupling.balance=none
"$MPIEXEC" -n 2 "$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_petsc" --solver petsc --quiet \
  --assembled --set coupling.balance=none # the assembled path solves Eq. 38 as printed only
compare "$tmp/bar_direct" "$tmp/bar_petsc" "coupled bar"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['solver']; assert s['ranks']==2 and s['operator']=='assembled' and s['ksp_type']=='gmres', s" "$tmp/bar_petsc/summary.json"

echo "== coupled bar, 2 ranks, matrix-free Eq. 38, balanced (the defaults: GMRES + MUMPS LU of the twin)"
"$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_dbal" --solver direct --quiet
"$MPIEXEC" -n 2 "$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_mf2" --solver petsc --quiet
compare "$tmp/bar_dbal" "$tmp/bar_mf2" "coupled bar, matrix-free, 2 ranks"
slabs_agree "$tmp/bar_dbal" "$tmp/bar_mf2" "coupled bar, slabs" gmres
"$MPIEXEC" -n 2 "$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_rep2" --solver petsc --quiet \
  --replicate
compare "$tmp/bar_dbal" "$tmp/bar_rep2" "coupled bar, matrix-free, 2 ranks, replicated model"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['solver']; assert 'pd_slabs' not in s and s['ranks']==2, s" "$tmp/bar_rep2/summary.json"

echo "== C-beam with a web region over part of the section (parallel interfaces), 2 ranks, slabs"
sed -e 's/horizon: 3.0/horizon: 1.5/' "$CUPID_SOURCE_DIR/examples/cbeam/cbeam_pd_l9.yaml" > "$tmp/cb.yaml"
"$CUPID" run "$tmp/cb.yaml" -o "$tmp/cb_direct" --solver direct --quiet
"$MPIEXEC" -n 2 "$CUPID" run "$tmp/cb.yaml" -o "$tmp/cb_petsc" --solver petsc --quiet
compare "$tmp/cb_direct" "$tmp/cb_petsc" "C-beam, fictitious nodes, slabs"
slabs_agree "$tmp/cb_direct" "$tmp/cb_petsc" "C-beam, fictitious nodes, slabs" gmres

echo "== coupled bar, one process: matrix-free Eq. 38 (GMRES + LU of the bond-based twin)"
"$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_mf" --solver petsc --quiet
compare "$tmp/bar_dbal" "$tmp/bar_mf" "coupled bar, matrix-free"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['solver']; assert s['ranks']==1 and s['operator']=='matrix-free' and s['ksp_type']=='gmres', s" "$tmp/bar_mf/summary.json"

echo "== coupled bar, Arlequin (two overlaps, LPS weighted node by node: symmetric, CG), 2 ranks"
sed 's/horizon: 3.0/horizon: 1.5/' "$CUPID_SOURCE_DIR/examples/bar/bar_coupled_arlequin_l9.yaml" > "$tmp/arl.yaml"
"$CUPID" run "$tmp/arl.yaml" -o "$tmp/arl_direct" --solver direct --quiet
"$MPIEXEC" -n 2 "$CUPID" run "$tmp/arl.yaml" -o "$tmp/arl_petsc" --solver petsc --quiet
compare "$tmp/arl_direct" "$tmp/arl_petsc" "coupled bar, Arlequin, matrix-free"
slabs_agree "$tmp/arl_direct" "$tmp/arl_petsc" "coupled bar, Arlequin, slabs" cg
"$MPIEXEC" -n 2 "$CUPID" run "$tmp/arl.yaml" -o "$tmp/arl_asm" --solver petsc --quiet --assembled
compare "$tmp/arl_direct" "$tmp/arl_asm" "coupled bar, Arlequin, assembled"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['solver']; assert s['ranks']==2 and s['ksp_type']=='cg' and s['operator']=='assembled', s" "$tmp/arl_asm/summary.json"

echo "== panel, Arlequin (two stringer regions over part of the section), matrix-free, 2 ranks"
"$CUPID" run "$CUPID_SOURCE_DIR/examples/panel/panel_pd_l9_arlequin.yaml" -o "$tmp/parl_direct" --solver direct --quiet
"$MPIEXEC" -n 2 "$CUPID" run "$CUPID_SOURCE_DIR/examples/panel/panel_pd_l9_arlequin.yaml" -o "$tmp/parl_petsc" --solver petsc --quiet
compare "$tmp/parl_direct" "$tmp/parl_petsc" "panel, Arlequin, matrix-free"
slabs_agree "$tmp/parl_direct" "$tmp/parl_petsc" "panel, Arlequin, slabs" cg

echo "== PD-only LPS block, matrix-free, 2 ranks"
"$CUPID" run "$models/pd_block.yaml" -o "$tmp/pd_direct" --solver direct --quiet
"$MPIEXEC" -n 2 "$CUPID" run "$models/pd_block.yaml" -o "$tmp/pd_petsc" --solver petsc --quiet
compare "$tmp/pd_direct" "$tmp/pd_petsc" "PD block"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['solver']; assert s['ranks']==2 and s['operator']=='matrix-free' and s['ksp_type']=='cg', s" "$tmp/pd_petsc/summary.json"

echo "== PD-only column split into z slabs (each rank builds only its layers + halo), 2 ranks"
"$CUPID" run "$models/pd_tower.yaml" -o "$tmp/tower_direct" --solver direct --quiet
"$MPIEXEC" -n 2 "$CUPID" run "$models/pd_tower.yaml" -o "$tmp/tower_petsc" --quiet
compare "$tmp/tower_direct" "$tmp/tower_petsc" "PD column in slabs"
python3 - "$tmp/tower_direct/summary.json" "$tmp/tower_petsc/summary.json" <<'PY'
import json, sys
d, p = (json.load(open(f)) for f in sys.argv[1:3])
s = p["solver"]
# 6 x 12 x 30 nodes, 72 a layer; 15 owned layers + 6 halo layers = 21 layers = 1512 nodes a rank
assert s["ranks"] == 2 and s["operator"] == "matrix-free", s
assert s["pd_slabs"] == {"ranks": 2, "largest_slab_nodes": 1512}, s
for k in ("pd_nodes", "bonds", "constrained_dofs"):
    assert d["counts"][k] == p["counts"][k], (k, d["counts"][k], p["counts"][k])
# Stresses gathered from the slabs (1e-8 of the largest component, as the displacements).
keys = ("sxx", "syy", "szz", "syz", "sxz", "sxy")
scale = max(abs(a[k]) for a in d["points"] for k in keys)
err = max(abs(a[k] - b[k]) for a, b in zip(d["points"], p["points"]) for k in keys) / scale
# Reactions from K u of the owned rows: equilibrium as tight as the direct solve's.
imb = max(abs(v) for v in p["equilibrium_imbalance"]) / max(abs(v) for v in p["applied_load_sum"])
print(f"PD column in slabs: largest slab {s['pd_slabs']['largest_slab_nodes']} of "
      f"{p['counts']['pd_nodes']} nodes; stresses differ by {err:.1e}; imbalance {imb:.1e}")
assert err <= 1e-8, err
assert imb <= 1e-9, imb
PY

echo "== analysis.solver: petsc on one process, PETSc options passed through"
sed 's/solver: direct/solver: petsc/' "$models/pd_block.yaml" > "$tmp/pd_key.yaml"
"$CUPID" run "$tmp/pd_key.yaml" -o "$tmp/pd_key" --quiet -ksp_type gmres -ksp_rtol 1e-13
compare "$tmp/pd_direct" "$tmp/pd_key" "PD block, model key, -ksp_type gmres"
python3 -c "import json,sys; s=json.load(open(sys.argv[1]))['solver']; assert s['ranks']==1 and s['ksp_type']=='gmres', s" "$tmp/pd_key/summary.json"

echo "== solver auto: direct for a small model, PETSc once the direct estimate passes the limit"
sed 's/solver: direct/solver: auto/' "$models/pd_block.yaml" > "$tmp/pd_auto.yaml"
"$CUPID" run "$tmp/pd_auto.yaml" -o "$tmp/pd_auto_small" --quiet
# The direct path needs ~0.15 GB (cupid check): a 0.2 GB limit leaves it above a quarter.
"$CUPID" run "$tmp/pd_auto.yaml" -o "$tmp/pd_auto_large" --quiet --max-memory 0.2
python3 - "$tmp/pd_auto_small/summary.json" "$tmp/pd_auto_large/summary.json" <<'PY'
import json, sys
small, large = (json.load(open(p))["solver"] for p in sys.argv[1:3])
print("auto, small:", small["method"], "-", small["choice"])
print("auto, 0.2 GB limit:", large["method"], "-", large["choice"])
assert small["method"] == "cholmod" and small["choice"].startswith("auto"), small
assert large["method"] == "petsc" and large["choice"].startswith("auto"), large
PY
compare "$tmp/pd_direct" "$tmp/pd_auto_large" "PD block, auto -> petsc"

echo "== a forced divergence fails cleanly (exit 2, one message)"
set +e
"$MPIEXEC" -n 2 "$CUPID" run "$models/coupled_bar.yaml" -o "$tmp/bar_fail" --solver petsc \
  -ksp_max_it 3 > "$tmp/fail.out" 2>&1
rc=$?
set -e
cat "$tmp/fail.out"
[ "$rc" -eq 2 ] || { echo "FAIL: exit status $rc, expected 2"; exit 1; }
[ "$(grep -c 'DIVERGED_ITS' "$tmp/fail.out")" -eq 1 ] || { echo "FAIL: expected one DIVERGED_ITS message"; exit 1; }
[ ! -e "$tmp/bar_fail/summary.json" ] || { echo "FAIL: a failed run wrote outputs"; exit 1; }
echo "PASS"
