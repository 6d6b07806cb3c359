#!/usr/bin/env bash
# Installs the dependencies, builds GiPSi (release) and runs the default demo: a mass-spring sheet
# sagging under gravity, written to out/hanging_sheet/ (open sheet.pvd in ParaView).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release
cmake --build --preset release
./build/release/bin/gipsi run scenes/hanging_sheet.json
echo "Open out/hanging_sheet/sheet.pvd in ParaView; probe traces are in out/hanging_sheet/probes/."
