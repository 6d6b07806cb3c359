#!/usr/bin/env bash
# The core without the optional parts (docs/install.md, "Optional parts"): configures
# build/minimal with GIPSI_WITH_GMSH, GIPSI_WITH_OPENIGTLINK and GIPSI_WITH_PETSC OFF and otherwise the release
# flags (so ccache serves every file but the few that differ), builds the gipsi tool, and checks:
#  - no library of it links Gmsh, OpenIGTLink, MPI or PETSc;
#  - `gipsi --version` and `gipsi types` say what was left out;
#  - a scene that needs neither runs;
#  - a scene that generates a mesh with Gmsh is refused at the mesh's JSON path (exit 1);
#  - a scene with an OpenIGTLink device is refused at the device's JSON path (exit 1);
#  - `gipsi run` under an MPI launcher with several ranks is refused (exit 2).
# Run by scripts/test.sh after the package stage (about 2 minutes with a warm ccache).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build/minimal
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DGIPSI_WERROR="${GIPSI_WERROR:-OFF}" \
  -DGIPSI_WITH_GMSH=OFF -DGIPSI_WITH_OPENIGTLINK=OFF -DGIPSI_WITH_PETSC=OFF \
  -DGIPSI_BUILD_TESTS=OFF -DGIPSI_BUILD_BENCH=OFF -DGIPSI_BUILD_PYTHON=OFF > /dev/null
cmake --build "$build" --target gipsi_cli
gipsi="$build/bin/gipsi"
work=$(mktemp -d "${TMPDIR:-/tmp}/gipsi-minimal.XXXXXX")
trap 'rm -rf "$work"' EXIT
fail() { echo "minimal-test: $*" >&2; exit 1; }

if ldd "$gipsi" "$build"/src/libgipsi_*.so | grep -Ei "libgmsh|libOpenIGTLink|libmpi|libpetsc"; then
  fail "a library of the minimal build links Gmsh, OpenIGTLink, MPI or PETSc"
fi
"$gipsi" --version | tee "$work/version"
grep -q "without Gmsh, OpenIGTLink" "$work/version" || fail "--version does not say what was left out"
"$gipsi" types | head -1 | grep -q "without Gmsh, OpenIGTLink" || fail "types does not say what was left out"

"$gipsi" run scenes/hanging_sheet.json --until 0.05 --out "$work/sheet" -q ||
  fail "a scene without Gmsh meshes or OpenIGTLink devices did not run"

expect_refusal() {  # SCENE EXPECTED-TEXT
  local code=0
  "$gipsi" validate "$1" > "$work/out" 2>&1 || code=$?
  [ "$code" -eq 1 ] && grep -qF "$2" "$work/out" ||
    { cat "$work/out" >&2; fail "$1: expected exit 1 with '$2', got exit $code"; }
  echo "refused as expected: $(grep -F "$2" "$work/out")"
}
expect_refusal scenes/lv_inflation.json \
  "meshes.lv: generating an ellipsoid shell needs Gmsh, which this GiPSi was built without (configure with -DGIPSI_WITH_GMSH=ON)"
python3 - "$work/igtl.json" <<'PY'
import json, os, sys
scene = json.load(open("scenes/liver_palpation.json"))
probe = scene["objects"]["probe"]
del probe["path"]
probe["device"] = {"type": "OpenIGTLink", "host": "127.0.0.1", "port": 18944}
for mesh in scene["meshes"].values():  # the copy lives elsewhere: absolute mesh paths
    if "file" in mesh:
        mesh["file"] = os.path.abspath(os.path.join("scenes", mesh["file"]))
json.dump(scene, open(sys.argv[1], "w"))
PY
expect_refusal "$work/igtl.json" \
  "objects.probe.device: an OpenIGTLink device needs OpenIGTLink, which this GiPSi was built without (configure with -DGIPSI_WITH_OPENIGTLINK=ON)"
# Under an MPI launcher with several ranks (its environment is enough): refused, exit 2.
code=0
OMPI_COMM_WORLD_SIZE=2 "$gipsi" run scenes/hanging_sheet.json --until 0.05 --out "$work/mpi" -q \
  > "$work/out" 2>&1 || code=$?
[ "$code" -eq 2 ] && grep -qF "this gipsi was built without PETSc" "$work/out" ||
  { cat "$work/out" >&2; fail "a run on several MPI ranks: expected exit 2, got exit $code"; }
[ ! -e "$work/mpi" ] || fail "the refused run on several MPI ranks wrote $work/mpi"
echo "refused as expected: $(head -c 120 "$work/out")"
echo "minimal-test: passed"
