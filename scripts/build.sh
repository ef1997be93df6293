#!/usr/bin/env bash
# Install what is missing (Debian packages), configure and build cupid in ./build.
# Extra arguments go to CMake's configure step, e.g. scripts/build.sh -DCUPID_SANITIZE=ON.
#   --with-petsc   also install PETSc + OpenMPI (petsc-dev) and build the PETSc/MPI engine
#                  (CUPID_WITH_PETSC=ON) in ./build-petsc: `--solver petsc`, `mpirun -n N cupid run`
set -euo pipefail
cd "$(dirname "$0")/.."
deps=() cmake_args=() default_dir=build
for arg in "$@"; do
  case $arg in
    --with-petsc) deps+=(--with-petsc) cmake_args+=(-DCUPID_WITH_PETSC=ON) default_dir=build-petsc ;;
    *) cmake_args+=("$arg") ;;
  esac
done
scripts/install-deps.sh ${deps[@]+"${deps[@]}"}
BUILD_DIR=${CUPID_BUILD_DIR:-$default_dir}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release ${cmake_args[@]+"${cmake_args[@]}"} >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc)"
