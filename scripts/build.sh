#!/usr/bin/env bash
# Install what is missing (Debian packages), configure and build cupid in ./build.
# Extra arguments go to CMake's configure step, e.g. scripts/build.sh -DCUPID_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
BUILD_DIR=${CUPID_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc)"
