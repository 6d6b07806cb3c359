#!/usr/bin/env python3
"""`mpiexec -np N gipsi run SCENE` against the serial run of the same scene file.

Runs the N-version benchmark slab (scenes/slab_ep_0.5mm.json, its first 30 ms) serially and on
2 and 4 ranks (4 oversubscribed: more ranks than cores), and checks that
  - the distributed runs write the same files as the serial one, from rank 0 only;
  - every probe (a point probe of V and activation time, the activated fraction, the line probe
    of activation times along the diagonal) has the serial run's rows and times, and values
    within what the diffusion solver's tolerance allows: both solve with CG + Jacobi to a
    relative residual of 1e-8, which leaves at most 1e-3 ms in activation times against an
    exact solve on this slab (tests/parallel/distributed_monodomain_test.cc), so 2e-3 ms, and
    0.5 mV for V (an upstroke of at most ~250 mV/ms shifted by 2e-3 ms); measured: 1e-13;
  - the summary names the ranks;
  - the heart (scenes/heart.json, its first beat: 0.8 s) on 2 ranks, its bioelectricity split
    and its muscle and circulation whole on every rank, gives the serial PV loop and beat
    summary within 1e-4 relative (activation times within 2e-3 ms shift the active tension by
    that; at the steepest pressure rise, ~200 kPa/s, that is 0.4 Pa of ~10 kPa); measured 3e-14;
  - what a distributed run refuses (checkpoints) and a bad scene exit with the serial codes.

Usage: distributed_scene_test.py GIPSI MPIEXEC SOURCE_DIR
"""
import csv
import os
import subprocess
import sys
import tempfile

GIPSI, MPIEXEC, SOURCE = sys.argv[1], sys.argv[2], sys.argv[3]
SCENE = os.path.join(SOURCE, "scenes", "slab_ep_0.5mm.json")
BOUNDS = {"V": 0.5, "activation_time": 2e-3, "activated_fraction": 1e-9}
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(ranks, out, *extra):
    command = [GIPSI, "run", SCENE, "--until", "0.03", "-o", out, "--overwrite", *extra]
    if ranks > 1:
        command = [MPIEXEC, "-np", str(ranks)] + (["--oversubscribe"] if ranks > 2 else []) + command
    result = subprocess.run(command, capture_output=True, text=True, timeout=240)
    return result.returncode, result.stdout + result.stderr


def files(folder):
    return sorted(os.path.relpath(os.path.join(d, f), folder)
                  for d, _, names in os.walk(folder) for f in names)


def rows(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


with tempfile.TemporaryDirectory() as work:
    serial = os.path.join(work, "serial")
    code, text = run(1, serial)
    check(code == 0, f"serial run exited {code}: {text}")
    for ranks in (2, 4):
        out = os.path.join(work, f"ranks{ranks}")
        code, text = run(ranks, out)
        check(code == 0, f"{ranks} ranks: exit {code}: {text}")
        check(f"MPI ranks:        {ranks} (distributed: Monodomain)" in text,
              f"{ranks} ranks: the summary does not name the ranks:\n{text}")
        check(text.count("simulated time:") == 1, f"{ranks} ranks: more than one rank printed")
        check(files(out) == files(serial),
              f"{ranks} ranks: files differ: {set(files(out)) ^ set(files(serial))}")
        for name in ("far_corner", "activated", "diagonal"):
            a = rows(os.path.join(serial, "probes", name + ".csv"))
            b = rows(os.path.join(out, "probes", name + ".csv"))
            check(a[0] == b[0], f"{ranks} ranks, {name}: header {b[0]} != {a[0]}")
            check(len(a) == len(b) and len(a) > 2, f"{ranks} ranks, {name}: {len(b)} rows, serial {len(a)}")
            worst = {}
            for ra, rb in zip(a[1:], b[1:]):
                for column, x, y in zip(a[0], ra, rb):
                    bound = BOUNDS.get(column, 0.0)  # time, distance, x, y, z: the same numbers
                    diff = abs(float(x) - float(y))
                    worst[column] = max(worst.get(column, 0.0), diff)
                    if diff > bound:
                        check(False, f"{ranks} ranks, {name}.{column}: {y} vs serial {x}")
                        break
            print(f"{ranks} ranks, {name}: largest differences {worst}")
    heart = os.path.join(SOURCE, "scenes", "heart.json")
    heart_runs = {}
    for ranks in (1, 2):
        out = os.path.join(work, f"heart{ranks}")
        command = [GIPSI, "run", heart, "--until", "0.8", "-o", out, "--overwrite", "-q"]
        if ranks > 1:
            command = [MPIEXEC, "-np", str(ranks)] + command
        result = subprocess.run(command, capture_output=True, text=True, timeout=240)
        check(result.returncode == 0, f"heart on {ranks} ranks: exit {result.returncode}: "
              f"{result.stdout}{result.stderr}")
        heart_runs[ranks] = out
    for name in ("pv", "summary"):
        a = rows(os.path.join(heart_runs[1], "probes", name + ".csv"))
        b = rows(os.path.join(heart_runs[2], "probes", name + ".csv"))
        check(a[0] == b[0] and len(a) == len(b) and len(a) > 1,
              f"heart, {name}: {len(b)} rows with {b[0]}, serial {len(a)} with {a[0]}")
        worst = 0.0
        for ra, rb in zip(a[1:], b[1:]):
            for column, x, y in zip(a[0], ra, rb):
                diff = abs(float(x) - float(y))
                scale = max(abs(float(x)), 1e-300)
                worst = max(worst, diff / scale if float(x) != 0 else diff)
                check(diff <= 1e-4 * abs(float(x)) or diff == 0,
                      f"heart, {name}.{column}: {y} vs serial {x}")
        print(f"heart on 2 ranks, {name}: largest relative difference {worst:.3g}")
    # Refusals keep the serial exit codes, on every rank.
    code, text = run(2, os.path.join(work, "refused"), "--checkpoint-every", "0.01")
    check(code == 1 and "checkpoints of a distributed run (2 ranks) are not available yet" in text,
          f"checkpoints under MPI: exit {code}: {text}")
    missing = os.path.join(work, "no-such-scene.json")
    result = subprocess.run([MPIEXEC, "-np", "2", GIPSI, "run", missing], capture_output=True,
                            text=True, timeout=120)
    check(result.returncode == 1 and "no-such-scene.json" in result.stderr,
          f"a missing scene under MPI: exit {result.returncode}: {result.stderr}")

print("FAILED" if failures else "PASSED", f"({len(failures)} failures)")
sys.exit(1 if failures else 0)
