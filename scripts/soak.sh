#!/usr/bin/env bash
# Soak test: long bounded runs of small scenes through `gipsi run`, sampling the process's
# resident memory (VmRSS) once a second and checking a conserved quantity afterwards.
#  - circulation_closed_loop.json for STEPS macro steps of 1 ms: the closed loop conserves the
#    total blood volume exactly (compartment flows cancel), so its drift must stay at round-off.
#  - coupled_blocks.json (an Aggregate of two mass-spring blocks glued by BoundaryCoupling) for
#    STEPS macro steps of 0.1 ms: resident memory only.
# Memory growth is the RSS at the end minus the RSS after warm-up (the first quarter of the run,
# at least 3 s of wall time: both scenes reach their plateau within 2 s).
# Usage: bash scripts/soak.sh [STEPS]   (default 100000; needs a release build)
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${1:-100000}
gipsi=build/release/bin/gipsi
out=$(mktemp -d /tmp/gipsi_soak.XXXXXX)
export OMP_WAIT_POLICY=passive

soak() {  # name scene end_time
  local name=$1 scene=$2 end=$3
  local log="$out/$name.rss"
  : >"$log"
  local start=$SECONDS
  "$gipsi" run "scenes/$scene" -q --no-vtu --until "$end" -o "$out/$name" >"$out/$name.log" 2>&1 &
  local pid=$!
  while kill -0 "$pid" 2>/dev/null; do
    awk '/VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null >>"$log" || true
    sleep 0.2
  done
  wait "$pid"
  local wall=$((SECONDS - start))
  python3 - "$log" "$name" "$wall" <<'PY'
import sys
samples = [int(x) for x in open(sys.argv[1]).read().split()]
name, wall = sys.argv[2], sys.argv[3]
if len(samples) < 3:
    print(f"{name}: {wall} s wall, too short to sample RSS ({len(samples)} samples)")
    sys.exit(0)
# Warm-up: the first quarter of the run, at least 3 s of wall time (loading the libraries,
# scene set-up, solver and output buffers, OpenMP's threads).
warm = samples[min(len(samples) - 1, max(len(samples) // 4, 15)):]
print(f"{name}: {wall} s wall, {len(samples)} RSS samples: start {samples[0] / 1024:.1f} MiB, "
      f"after warm-up {warm[0] / 1024:.1f} MiB, max after warm-up {max(warm) / 1024:.1f} MiB, "
      f"end {samples[-1] / 1024:.1f} MiB, growth after warm-up "
      f"{(samples[-1] - warm[0]) / 1024:+.2f} MiB")
PY
}

soak circulation circulation_closed_loop.json "$(python3 -c "print($steps * 1e-3)")"
python3 - "$out/circulation/probes/conservation.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
i = rows[0].index("total_volume")
v = [float(r[i]) for r in rows[1:]]
drift = max(abs(x - v[0]) for x in v)
print(f"circulation: total volume {v[0] * 1e6:.6f} mL, max drift over {len(v)} samples "
      f"{drift * 1e6:.3e} mL (relative {drift / v[0]:.2e})")
PY
soak coupled_blocks coupled_blocks.json "$(python3 -c "print($steps * 1e-4)")"
[ "${SOAK_KEEP:-}" = 1 ] && echo "kept $out" || rm -rf "$out"
