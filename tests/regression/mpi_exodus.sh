#!/usr/bin/env bash
# model.exo of runs on PD slabs under mpirun (output.exodus, issue 35): a PD-only explicit run
# and crack growth on 2 ranks, rank 0 writing the gathered frames, read back by meshio and
# netCDF4 against the run's VTU files and damage.csv (tests/regression/exodus_readers.py).
if [ "${CUPID_HAVE_PETSC:-0}" != 1 ]; then
  echo "SKIP: cupid was built without PETSc (scripts/build.sh --with-petsc builds build-petsc/)"
  exit 77
fi
CUPID=$(realpath "${CUPID:-build-petsc/cupid}")
if ! "$CUPID" check "${CUPID_SOURCE_DIR:-.}/examples/bar/bar.yaml" --set output.exodus=true >/dev/null 2>&1; then
  echo "SKIP: cupid was built without Exodus II (libexodusii-dev)"
  exit 77
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
export OMPI_MCA_rmaps_base_oversubscribe=1 CUPID_EXODUS_RANKS=2 CUPID
exec /usr/bin/python3 "${CUPID_SOURCE_DIR:-.}/tests/regression/exodus_readers.py"
