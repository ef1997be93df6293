# Shared preamble of the bash tests of the PETSc/MPI engine (sourced, not a test itself): skipped
# (exit 77) in a build without PETSc, then checks.sh's preamble (the binary, a scratch folder,
# ok / bad / finish), the Python Debian's packages serve ($PY), the MPI launcher ($MPIEXEC) and
# OpenMPI's settings for a root container on 2 cores (oversubscribed for 3 ranks), one OpenMP
# thread a rank.
#   . "$(dirname "$0")/../tools/mpi_checks.sh"
if [ "${CUPID_HAVE_PETSC:-0}" != 1 ]; then
  echo "SKIP: cupid was built without PETSc (scripts/build.sh --with-petsc builds build-petsc/)"
  exit 77
fi
. "$(dirname "${BASH_SOURCE[0]}")/checks.sh"
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
MPIEXEC=${CUPID_MPIEXEC:-mpiexec}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
export OMPI_MCA_rmaps_base_oversubscribe=1
