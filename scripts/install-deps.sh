#!/usr/bin/env bash
# Installs every Debian 12 package GiPSi needs to build, test and run. Idempotent; run as root
# (or through sudo). Nothing else is required on a fresh machine.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev          # dense/sparse linear algebra
  nlohmann-json3-dev     # scene files
  libcli11-dev           # the gipsi command line
  libspdlog-dev libfmt-dev   # logging and formatting
  libpugixml-dev         # reading VTU (XML) meshes
  zlib1g-dev             # compressed VTU payloads
  libgmsh-dev gmsh       # Gmsh C++ API: shell (left-ventricle) mesh generation
  libsuitesparse-dev libopenblas-dev  # CHOLMOD sparse Cholesky (with an optimised BLAS)
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format clang-tidy
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
