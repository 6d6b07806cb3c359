#!/usr/bin/env bash
# The installed package as an outside user gets it. Installs a build (default build/release)
# into a fresh temporary prefix, or with --deb builds the Debian package (CPack), checks that
# apt can resolve its dependencies (a simulation: nothing is installed) and unpacks it into a
# temporary folder. Then copies tests/consumer/ away from the source tree, configures it with
# find_package(gipsi) against that prefix alone, builds it and runs its checks; builds the
# docs/install.md snippet; runs the installed `gipsi` with the installed example plugin and
# imports the installed Python module. Fails if the consumer's build refers to the source or
# build tree. Run by scripts/test.sh after the release tests (about 40 s each way).
#   bash scripts/consumer-test.sh [--deb] [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
source_dir=$PWD
deb=false
if [ "${1:-}" = "--deb" ]; then deb=true; shift; fi
build_dir=$(realpath "${1:-build/release}")
work=$(mktemp -d "${TMPDIR:-/tmp}/gipsi-consumer.XXXXXX")
trap 'rm -rf "$work"' EXIT

if $deb; then
  (cd "$build_dir" && cpack -G DEB -B "$work/deb" > "$work/cpack.log") ||
    { cat "$work/cpack.log" >&2; exit 1; }
  package=$(ls "$work"/deb/gipsi_*.deb)
  # The distributed runs' package, from a build with PETSc.
  mpi_package=$(ls "$work"/deb/gipsi-mpi_*.deb 2>/dev/null || true)
  for p in $package $mpi_package; do
    echo "built $(basename "$p") ($(du -k "$p" | cut -f1) kB)"
    dpkg-deb --field "$p" Depends
  done
  # Every dependency must resolve from the machine's apt sources (simulated; installs nothing).
  apt-get install --simulate --no-install-recommends $package $mpi_package > "$work/apt.log" 2>&1 ||
    { echo "consumer-test: apt cannot install $(basename "$package") $mpi_package:" >&2; cat "$work/apt.log" >&2; exit 1; }
  for p in $package $mpi_package; do dpkg-deb --extract "$p" "$work/root"; done
  prefix="$work/root/usr"
else
  cmake --install "$build_dir" --prefix "$work/prefix" > "$work/install.log"
  echo "installed into a temporary prefix: $(grep -c 'Installing:' "$work/install.log") files"
  prefix="$work/prefix"
fi
cp -r tests/consumer "$work/src"
cmake -S "$work/src" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF > "$work/configure.log"
grep -q "^gipsi_DIR:PATH=$prefix/" "$work/build/CMakeCache.txt" ||
  { echo "consumer-test: gipsi was not found in the fresh prefix" >&2; grep gipsi_DIR "$work/build/CMakeCache.txt" >&2; exit 1; }
cmake --build "$work/build"

# The consumer must have seen only the installed package.
for tree in "$source_dir" "$build_dir"; do
  if grep -q "$tree" "$work/build/compile_commands.json" "$work/build/build.ninja"; then
    echo "consumer-test: the consumer's build refers to $tree:" >&2
    grep -o "[^ ]*$tree[^ ]*" "$work/build/compile_commands.json" "$work/build/build.ninja" | head >&2
    exit 1
  fi
done
if ldd "$work/build/thermal_consumer" | grep -q "$build_dir"; then
  echo "consumer-test: thermal_consumer loads libraries from the build tree" >&2; exit 1
fi

"$work/build/thermal_consumer" "$work"
"$prefix/bin/gipsi" --version
# The installed tool runs a scene and draws its plot (PLplot's driver is loaded at run time).
"$prefix/bin/gipsi" run scenes/slab_ep_0.5mm.json --until 0.005 --out "$work/slab" -q
[ -s "$work/slab/activation_diagonal.png" ] ||
  { echo "consumer-test: the installed gipsi wrote no plot" >&2; exit 1; }

# The CMake snippet of docs/install.md as a user copies it, with a main of their own; then the
# same with COMPONENTS viz, and with a component that does not exist (must fail, naming it).
project_dir="$work/my_project"
mkdir -p "$project_dir"
awk '/^## Use it from CMake/{s=1} s && /^```cmake$/{f=1; next} f && /^```$/{exit} f' docs/install.md \
  > "$project_dir/CMakeLists.txt"
cat > "$project_dir/main.cc" <<'CC'
#include <cstdio>

#include "gipsi/base/version.h"
#include "gipsi/core/registry.h"
#include "gipsi/io/builtins.h"

int main() {
  gipsi::TypeRegistry registry;
  gipsi::RegisterBuiltins(registry);
  std::printf("docs/install.md snippet: gipsi %s, %zu object types\n", GIPSI_VERSION_STRING,
              registry.objects.Names().size());
}
CC
configure() { cmake -S "$project_dir" -B "$project_dir/build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix"; }
configure > /dev/null
cmake --build "$project_dir/build" > /dev/null
"$project_dir/build/my_simulation"
sed -i 's/find_package(gipsi 0.1 REQUIRED)/find_package(gipsi 0.1 REQUIRED COMPONENTS viz)/;
        s/PRIVATE gipsi::gipsi)/PRIVATE gipsi::gipsi gipsi::viz)/' "$project_dir/CMakeLists.txt"
configure > /dev/null
cmake --build "$project_dir/build" > /dev/null
"$project_dir/build/my_simulation" > /dev/null
sed -i 's/COMPONENTS viz)/COMPONENTS viz python)/' "$project_dir/CMakeLists.txt"
if configure > "$work/bad_component.log" 2>&1 || ! grep -q "no component 'python'" "$work/bad_component.log"; then
  echo "consumer-test: an unknown component was not refused by name:" >&2
  cat "$work/bad_component.log" >&2; exit 1
fi
"$prefix/bin/gipsi" types --plugin gipsi_example_plugin | grep -q "Oscillator" ||
  { echo "consumer-test: the installed gipsi did not load the installed example plugin" >&2; exit 1; }
# docs/plugins.md, "From an empty folder": the example plugin built as an outside project
# against the prefix, listed by the installed tool and run in the oscillator scene.
plugin_dir="$work/my_plugin"
mkdir -p "$plugin_dir"
awk '/^## From an empty folder/{s=1} s && /^```cmake$/{f=1; next} f && /^```$/{exit} f' \
  docs/plugins.md > "$plugin_dir/CMakeLists.txt"
cp plugins/example/example_plugin.cc "$plugin_dir/my_plugin.cc"
cmake -S "$plugin_dir" -B "$plugin_dir/build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" > /dev/null
cmake --build "$plugin_dir/build" > /dev/null
"$prefix/bin/gipsi" types --plugin "$plugin_dir/build/my_plugin.so" | grep -q "Oscillator" ||
  { echo "consumer-test: the outside plugin's types are not listed" >&2; exit 1; }
sed "s|\"gipsi_example_plugin\"|\"$plugin_dir/build/my_plugin.so\"|" scenes/plugin_oscillator.json \
  > "$work/oscillator.json"
"$prefix/bin/gipsi" run "$work/oscillator.json" --until 0.05 --out "$work/oscillator" -q ||
  { echo "consumer-test: the oscillator scene did not run with the outside plugin" >&2; exit 1; }
echo "outside plugin: built from docs/plugins.md and run"

# The distributed runs from the installed packages (when the build has them): the installed tool
# under mpiexec loads the installed libgipsi_parallel, and the docs/install.md program built
# against COMPONENTS parallel cuts a box over two ranks.
if [ -n "$(find "$prefix" -name 'libgipsi_parallel.so*' | head -1)" ]; then
  export OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_mpi_yield_when_idle=1
  mpiexec -np 2 "$prefix/bin/gipsi" run scenes/slab_ep_0.5mm.json --until 0.002 --out "$work/slab_mpi" \
    > "$work/mpi_run.log" 2>&1 || { echo "consumer-test: the installed gipsi failed on 2 ranks:" >&2; cat "$work/mpi_run.log" >&2; exit 1; }
  grep -q "split over them: tissue (Monodomain, in blocks)" "$work/mpi_run.log" ||
    { echo "consumer-test: the installed gipsi did not split the slab:" >&2; cat "$work/mpi_run.log" >&2; exit 1; }
  mpi_dir="$work/my_partition"
  mkdir -p "$mpi_dir"
  awk '/^## The distributed runs/{s=1} s && /^```cmake$/{f=1; next} f && /^```$/{exit} f' docs/install.md > "$mpi_dir/CMakeLists.txt"
  awk '/^## The distributed runs/{s=1} s && /^```cpp$/{f=1; next} f && /^```$/{exit} f' docs/install.md > "$mpi_dir/main.cc"
  { cmake -S "$mpi_dir" -B "$mpi_dir/build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" &&
    cmake --build "$mpi_dir/build"; } > "$work/my_partition_build.log" 2>&1 ||
    { echo "consumer-test: the docs/install.md COMPONENTS parallel program did not build:" >&2; cat "$work/my_partition_build.log" >&2; exit 1; }
  mpiexec -np 2 "$mpi_dir/build/my_partition" > "$work/my_partition.log" 2>&1 ||
    { echo "consumer-test: the COMPONENTS parallel program failed on 2 ranks:" >&2; cat "$work/my_partition.log" >&2; exit 1; }
  # Every node owned by one rank: the owned counts add up to the box's 41 x 15 x 7 nodes.
  awk '/nodes owned of/ {sum += $(NF-4); total = $NF} END {exit !(NR == 2 && sum == total && total == 4305)}' \
    "$work/my_partition.log" ||
    { echo "consumer-test: the COMPONENTS parallel program's ranks do not own every node once:" >&2; cat "$work/my_partition.log" >&2; exit 1; }
  echo "distributed runs: the installed gipsi split the slab over 2 ranks; COMPONENTS parallel built and ran"
fi

# The installed Python module, from the prefix alone (when the build has it).
module=$(find "$prefix" -name 'gipsi.cpython-*.so' | head -1)
if [ -n "$module" ]; then
  python=$(sed -n 's/^_Python3_EXECUTABLE:INTERNAL=//p' "$build_dir/CMakeCache.txt")
  PYTHONPATH=$(dirname "$module") "${python:-/usr/bin/python3}" - "$prefix" <<'PY'
import sys
import gipsi
assert gipsi.__file__.startswith(sys.argv[1]), f"gipsi imported from {gipsi.__file__}"
scene = {"gipsi": 1, "units": "SI",
         "meshes": {"m": {"generate": "sheet", "origin": [0, 0, 0], "u": [0.1, 0, 0],
                          "v": [0, 0.1, 0], "cells": [2, 2]}},
         "objects": {"sheet": {"type": "MassSpring", "domain": "m", "density": 1000,
                               "thickness": 0.001, "stiffness": 20, "dt": 0.001}},
         "schedule": {"end": 0.01, "dt": 0.001}}
sim = gipsi.Simulation.from_dict(scene)
assert sim.run()["outcome"] == "completed"
assert sim.object("sheet").positions.shape == (9, 3)
print(f"installed Python module: gipsi {gipsi.__version__} from the prefix")
PY
fi
echo "consumer-test: passed"
