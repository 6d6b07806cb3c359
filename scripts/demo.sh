#!/usr/bin/env bash
# Installs the dependencies, builds GiPSi (release) and runs the default demo: the GiPSi heart
# (scenes/heart.json), written to out/heart/ (pv_loop.png, probes/*.csv, muscle.pvd, bioelectricity.pvd).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release
cmake --build --preset release --target gipsi_cli
export OMP_WAIT_POLICY=passive
./build/release/bin/gipsi run scenes/heart.json --overwrite
echo "The PV loop is out/heart/pv_loop.png; open out/heart/muscle.pvd and bioelectricity.pvd in ParaView; traces and the beat summary are in out/heart/probes/."
