#!/usr/bin/env bash
# The coupling error of the coupled bar as the horizon shrinks at fixed m = 3 (the issue's
# acceptance: delta = 3, 2, 1.5 mm, i.e. h = 1, 2/3, 1/2 and 4,000, 13,500, 32,000 PD nodes),
# fictitious nodes, the README's configuration (3 B2 elements on the clamped span, PD surface
# correction), against its full-FE twin (bar_fe_te2 with the same clamped span), through
# examples/bar/convergence.py, which prints the table. Checks:
#  - the largest relative error of u_y along the axis falls at every step (observed 0.05%,
#    0.03%, 0.02%; 0.16%, 0.11%, 0.09% with the h/2 fictitious element before issue 18) and
#    stays within the issue's 0.7% bar target;
#  - the equilibrium imbalance stays below 0.1% of the load (observed 0.00%, 0.06% before
#    issue 18: Eq. 38 is not momentum-conserving, the bound is the one observed at h = 1 then,
#    docs/coupling.md).
# The two finer cases need the matrix-free path (a direct LU of the 32,000-node case would
# take ~50 GB): skipped (77) without PETSc. ~15 s on 2 cores.
if [ "${CUPID_HAVE_PETSC:-0}" != 1 ]; then
  echo "SKIP: cupid was built without PETSc (scripts/build.sh --with-petsc builds build-petsc/)"
  exit 77
fi
. "$(dirname "$0")/../tools/checks.sh"
# convergence.py runs the models through the Python package (python/cupid: Debian's python3-numpy,
# hence /usr/bin/python3) on this build's library.
if /usr/bin/python3 "$SRC/examples/bar/convergence.py" --library "$(dirname "$CUPID")/libcupid.so" \
     --solver petsc --clamp-elements 3 --surface-correction energy > table.md; then ok
else bad "convergence.py failed"; fi
cat table.md
if python3 - table.md <<'PY'; then ok; else bad "horizon study (above)"; fi
import sys
rows = [l.split("|")[1:-1] for l in open(sys.argv[1]) if l.startswith("| ") and "%" in l]
rel = [float(r[5].strip().rstrip("%")) for r in rows]
imb = [float(r[6].strip().rstrip("%")) for r in rows]
good = len(rows) == 3
if not good:
    print(f"FAIL: {len(rows)} rows, expected 3")
for k in range(1, len(rel)):
    if not rel[k] < rel[k - 1]:
        print(f"FAIL: the error does not fall from delta row {k} to {k + 1}: {rel[k - 1]}% -> {rel[k]}%")
        good = False
if any(r > 0.7 for r in rel):
    print(f"FAIL: an error above the 0.7% target: {rel}")
    good = False
if any(i > 0.1 for i in imb):
    print(f"FAIL: an imbalance above 0.1%: {imb}")
    good = False
raise SystemExit(0 if good else 1)
PY
finish mpi_bar_convergence
