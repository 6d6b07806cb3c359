#!/usr/bin/env bash
# Builds the libFuzzer targets (in the asan preset's tree: clang, ASan + UBSan) and runs each for
# a bounded time, seeded with the project's own meshes and scenes plus every earlier finding in
# fuzz/regressions/.
# A finding (crash, sanitizer report, escaped non-InputError exception, hang over 10 s, or
# memory over the limits) fails the script and leaves the input in build/asan/fuzz/findings/.
# Usage: bash scripts/fuzz.sh [SECONDS_PER_TARGET]   (default 30)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-30}"

cmake --preset asan >/dev/null
targets=(scene gmsh obj stl vtu vtk tetgen)
cmake --build --preset asan --target "${targets[@]/#/fuzz_}"

work="build/asan/fuzz/corpus"
findings="build/asan/fuzz/findings"
rm -rf "$work" && mkdir -p "$work" "$findings"
seed() {  # seed TARGET FILES...
  local target="$1"; shift
  mkdir -p "$work/$target"
  for f in "$@"; do [ -f "$f" ] && cp "$f" "$work/$target/"; done
  if [ -d "fuzz/regressions/$target" ]; then cp fuzz/regressions/"$target"/* "$work/$target/"; fi
  return 0
}
seed scene scenes/hanging_sheet.json scenes/coupled_blocks.json scenes/cantilever.json \
  scenes/indentation.json scenes/slab_ep_grid_0.5mm.json
seed gmsh tests/data/meshes/*.msh
seed obj tests/data/meshes/*.obj
seed stl tests/data/meshes/*.stl
seed vtu tests/data/meshes/*.vtu
seed vtk tests/data/meshes/*.vtk
mkdir -p "$work/tetgen"
{ cat tests/data/meshes/two_tets.node; printf '@@'; cat tests/data/meshes/two_tets.ele; } \
  >"$work/tetgen/two_tets"
seed tetgen

export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1"
status=0
for target in "${targets[@]}"; do
  echo "== fuzz_$target for ${seconds} s"
  if ! ./build/asan/fuzz/fuzz_"$target" "$work/$target" -max_total_time="$seconds" -timeout=10 \
      -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
      -artifact_prefix="$findings/${target}_" 2>"build/asan/fuzz/$target.log"; then
    echo "fuzz_$target: FINDING (log build/asan/fuzz/$target.log, input in $findings/)"
    tail -40 "build/asan/fuzz/$target.log"
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::new_units_added" "build/asan/fuzz/$target.log" |
      tr '\n' ' '
    echo
  fi
done
exit "$status"
