#!/usr/bin/env bash
# Install cupid's build and test dependencies from Debian 12 packages (idempotent).
# Usage: scripts/install-deps.sh [--with-petsc] [--with-fuzz] [--with-valgrind] [--with-lammps]
#   --with-petsc     PETSc 3.18 + OpenMPI (petsc-dev; CUPID_WITH_PETSC, scripts/build.sh --with-petsc)
#   --with-fuzz      clang-14 with libFuzzer and its OpenMP runtime (CUPID_FUZZ, docs/hardening.md)
#   --with-valgrind  valgrind (CUPID_VALGRIND_TESTS)
#   --with-lammps    LAMMPS (`lmp`), the reference of bench/run_lammps.sh (not needed to build or test)
# Only packages that are missing are installed, so a prepared machine pays nothing.
set -euo pipefail

# python3-numpy, python3-meshio and python3-vtk9: regression.vtu_readers opens every VTU cupid
# writes with meshio and VTK's own reader (run by /usr/bin/python3, which these serve).
# python3-pip, python3-setuptools, python3-venv: `pip install ./python` into a virtual
# environment (unit.python_install). libexodusii-dev: Exodus II output (output.exodus; the
# header at build time, its library loaded at run time);
# python3-netcdf4: meshio and the tests read model.exo back (regression.exodus_readers).
# libgmsh4.8: section meshes from Gmsh files (beam.section.mesh; loaded at run time, not linked).
# calculix-ccx: CalculiX, the reference of verification.pd_plate_calculix (a C3D20R plate).
pkgs=(cmake make gcc pkg-config libsuitesparse-dev libopenblas-dev libyaml-dev zlib1g-dev libcmocka-dev gnuplot-nox python3
      python3-numpy python3-meshio python3-vtk9 python3-pytest python3-pip python3-setuptools python3-venv
      libexodusii-dev python3-netcdf4 libgmsh4.8 calculix-ccx)
for arg in "$@"; do
  case $arg in
    --with-petsc) pkgs+=(petsc-dev procps) ;; # procps: pkill, SIGKILL to the ranks (mpi_resume)
    --with-fuzz) pkgs+=(clang-14 libclang-rt-14-dev libomp-14-dev) ;;
    --with-valgrind) pkgs+=(valgrind) ;;
    --with-lammps) pkgs+=(lammps) ;;
    *) echo "install-deps.sh: unknown option '$arg'" >&2; exit 1 ;;
  esac
done

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "cupid: installing missing Debian packages: ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
