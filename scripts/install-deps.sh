#!/usr/bin/env bash
# Installs every Debian 12 package GiPSi needs to build, test and run. Idempotent; run as root
# (or through sudo). Nothing else is required on a fresh machine.
#   bash scripts/install-deps.sh --mpi   adds PETSc and Open MPI (about 110 packages, 1 GB):
#                                        distributed runs (docs/scale-out.md). The test command
#                                        installs them; the demo does not need them.
set -euo pipefail
case "${1:-}" in
  "" | --mpi) ;;
  *) echo "install-deps: unknown option '$1' (expected --mpi or nothing)" >&2; exit 2 ;;
esac

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev          # dense/sparse linear algebra
  nlohmann-json3-dev     # scene files
  libcli11-dev           # the gipsi command line
  libspdlog-dev libfmt-dev   # logging and formatting
  libpugixml-dev         # reading VTU (XML) meshes
  zlib1g-dev             # compressed VTU payloads
  libgmsh-dev gmsh       # Gmsh C++ API: shell (left-ventricle) mesh generation
  libsuitesparse-dev     # CHOLMOD sparse Cholesky
  libopenblas-serial-dev # its BLAS: OpenBLAS (run single-threaded; GiPSi threads above it)
  libudunits2-dev        # UDUNITS-2: quantities with units in scene files
  libosmesa6-dev         # off-screen OpenGL (software) for gipsi snapshot
  libstb-dev             # PNG files and font rasterisation (stb_image_write, stb_truetype)
  fonts-dejavu-core      # the font of image labels
  libplplot-dev plplot-driver-cairo  # plots (PNG and SVG through cairo)
  libglfw3-dev libimgui-dev  # the gipsi view window and its panels
  xvfb xauth             # a virtual display for testing the viewer
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-14 libclang-rt-14-dev libomp-14-dev  # libFuzzer targets (scripts/fuzz.sh)
  libopenigtlink-dev     # OpenIGTLink 1.11: the networked haptic device (tracker, 3D Slicer)
  libfcl-dev             # FCL 0.7: the collision benchmark's baseline (bench/collision_bench.cc)
  pybind11-dev python3-dev python3-numpy  # the gipsi Python module (python/)
  python3-pytest python3-matplotlib  # its tests, and the plots of examples/python/
  clang-format clang-tidy
)
if [ "${1:-}" = "--mpi" ]; then
  # PETSc 3.18 (with PT-Scotch, hypre and MUMPS) over Open MPI: src/gipsi/parallel/.
  packages+=(petsc-dev libopenmpi-dev openmpi-bin)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The system's BLAS choice (the libblas.so.3 alternative) is left as the user has it: GiPSi asks
# the loaded BLAS for one thread at run time (numerics/sparse/blas_threads.h), and this script
# never changes system-wide settings.
