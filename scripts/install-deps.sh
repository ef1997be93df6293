#!/usr/bin/env bash
# Install cupid's build and test dependencies from Debian 12 packages (idempotent).
# Usage: scripts/install-deps.sh [--with-petsc]
# Only packages that are missing are installed, so a prepared machine pays nothing.
set -euo pipefail

pkgs=(cmake make gcc pkg-config libsuitesparse-dev libopenblas-dev libyaml-dev libcmocka-dev gnuplot-nox python3)
if [ "${1:-}" = "--with-petsc" ]; then pkgs+=(petsc-dev); fi

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
