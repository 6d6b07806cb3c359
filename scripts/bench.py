#!/usr/bin/env python3
"""GiPSi's headline benchmarks in one table, to compare machines (issue 23).

Runs the release build's benchmarks (Google Benchmark, medians of --repetitions runs) and the
CLI's own timing of two shipped scenes, and prints one Markdown table with the machine's STREAM
triad, CPU, vector kernels, core count and load average, so figures from different machines can be compared
(per core: run it with --threads 1; the default runs at 1 and at 2 threads, OMP_NUM_THREADS).

  python3 scripts/bench.py            # builds what it needs (release preset), about 6 minutes
  python3 scripts/bench.py --quick    # one repetition, no 10-s haptic loop, no long scenes
  python3 scripts/bench.py --json out.json   # also the raw figures
  python3 scripts/bench.py --busy     # also each figure beside a busy neighbour

Rows:
  STREAM triad [GB/s]                      the machine's memory bandwidth (sparse_bench)
  FEM step 5k / 20k / 78k tets [ms]        corotational, backward Euler, Jacobi-CG (fem_bench)
  FEM step ..., sgs [ms]                   the same with block Gauss-Seidel CG ("sgs")
  SpMV 26^3 lattice [GB/s, % of triad]     symmetric sparse matrix-vector product (sparse_bench)
  TTP06 cell model [M node-steps/s]        ten Tusscher-Panfilov 2006, 10^5 cells (cell_models_bench)
  Collision query [ms]                     two 224x224 sheets, 50 % overlap (collision_bench)
  Haptic loop p99 period error [us]        1 kHz beside a physics thread (haptics_bench; not --quick)
  Heart real-time factor                   scenes/heart.json, 4 s (gipsi run; not --quick)
  Heart 10.9k tets real-time factor        scenes/heart_fine.json, 1.6 s (gipsi run; not --quick)
  Niederer slab 0.2 mm [s]                 scenes/slab_ep_0.2mm.json to its end (gipsi run; not --quick)
Loads on a shared machine distort every row: the load average is printed, and the medians of
several repetitions are reported, never the best. With --busy every thread count is measured
twice: alone, and beside a busy neighbour (one process spinning on one core for the whole
measurement, as a user's other work would), where two threads should not lose to one.
"""
import argparse
import json
import os
import platform
import re
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
BUILD = os.path.join(ROOT, "build", "release")  # --build-dir changes it
TARGETS = ["gipsi_cli", "fem_bench", "sparse_bench", "cell_models_bench", "collision_bench",
           "haptics_bench"]


def build():
    subprocess.run(["cmake", "--preset", "release"], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", "--preset", "release", "--target", *TARGETS], cwd=ROOT,
                   check=True, stdout=subprocess.DEVNULL)


def env_with(threads):
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = str(threads)
    env.setdefault("OMP_WAIT_POLICY", "passive")
    return env


def run_benchmark(binary, pattern, threads, repetitions):
    """Median rows of `binary` for the benchmarks matching `pattern`, by name."""
    cmd = [os.path.join(BUILD, "bench", binary), f"--benchmark_filter={pattern}",
           "--benchmark_format=json"]
    if repetitions > 1:
        cmd += [f"--benchmark_repetitions={repetitions}", "--benchmark_report_aggregates_only=true"]
    out = subprocess.run(cmd, env=env_with(threads), check=True, capture_output=True, text=True)
    rows = {}
    for b in json.loads(out.stdout)["benchmarks"]:
        if repetitions > 1 and b.get("aggregate_name") != "median":
            continue
        rows[b["run_name"]] = b
    if not rows:
        sys.exit(f"bench.py: {binary} ran no benchmark matching '{pattern}'")
    return rows


def ms(row):
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[row["time_unit"]]
    return row["real_time"] * scale


def run_scene(scene, threads, until=None):
    """The CLI's own figures for a scene: wall seconds and real-time factor."""
    cmd = [os.path.join(BUILD, "bin", "gipsi"), "run", os.path.join(ROOT, "scenes", scene),
           "--no-vtu", "-o", os.path.join(BUILD, "bench_runs", scene.replace(".json", "")),
           "--overwrite"]
    if until is not None:
        cmd += ["--until", str(until)]
    out = subprocess.run(cmd, env=env_with(threads), check=True, capture_output=True, text=True)
    text = out.stdout + out.stderr
    wall = re.search(r"wall time:\s+([0-9.]+) s", text)
    rtf = re.search(r"real-time factor:\s+([0-9.]+)", text)
    if not wall or not rtf:
        sys.exit(f"bench.py: no timing in the output of {' '.join(cmd)}:\n{text}")
    return float(wall.group(1)), float(rtf.group(1))


class BusyNeighbour:
    """One process spinning on one core while the `with` block lasts. It also stops by itself
    if this script dies (it watches its parent), so it never outlives the measurement."""

    CODE = ("import os\nparent = os.getppid()\n"
            "while os.getppid() == parent:\n    for _ in range(200000): pass\n")

    def __enter__(self):
        self.proc = subprocess.Popen([sys.executable, "-c", self.CODE])
        return self

    def __exit__(self, *exc):
        self.proc.kill()
        self.proc.wait()
        return False


def measure(threads, repetitions, quick):
    r = {}
    triad = run_benchmark("sparse_bench", "BM_StreamTriad|BM_SymmetricSpMV/26/", threads,
                          repetitions)
    r["STREAM triad [GB/s]"] = triad["BM_StreamTriad/real_time"]["bytes_per_second"] / 1e9
    spmv = triad["BM_SymmetricSpMV/26/real_time"]["bytes_per_second"] / 1e9
    r["SpMV 26^3 lattice [GB/s]"] = spmv
    r["SpMV / triad [%]"] = 100 * spmv / r["STREAM triad [GB/s]"]
    fem = run_benchmark("fem_bench", "BM_ImplicitStep/corotational/(10|16|25)/(0|4)/", threads,
                        repetitions)
    for pre, name in ((0, ""), (4, ", sgs")):
        for n, tets in ((10, "5k"), (16, "20k"), (25, "78k")):
            r[f"FEM step {tets} tets{name} [ms]"] = ms(
                fem[f"BM_ImplicitStep/corotational/{n}/{pre}/real_time"])
    cells = run_benchmark("cell_models_bench", "BM_CellModelStep/TenTusscherPanfilov2006/100000$",
                          threads, repetitions)
    r["TTP06 [M node-steps/s]"] = 1e5 / ms(
        cells["BM_CellModelStep/TenTusscherPanfilov2006/100000"]) / 1e3
    coll = run_benchmark("collision_bench", "BM_GipsiSheets/224/50$", threads, repetitions)
    r["Collision query 2x224^2 sheets [ms]"] = ms(coll["BM_GipsiSheets/224/50"])
    if not quick:
        hap = run_benchmark("haptics_bench", "BM_HapticLoopUnderPhysics/10/0/", threads, 1)
        row = next(iter(hap.values()))
        r["Haptic loop p99 period error [us]"] = row["error_p99_us"]
        wall, rtf = run_scene("heart.json", threads, until=4)
        r["Heart real-time factor"] = rtf
        wall, rtf = run_scene("heart_fine.json", threads, until=1.6)
        r["Heart 10.9k tets real-time factor"] = rtf
        wall, _ = run_scene("slab_ep_0.2mm.json", threads)
        r["Niederer slab 0.2 mm [s]"] = wall
    return r


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def simd_kernels():
    """The vector kernels the build runs here ("avx" or "generic"), from `gipsi --version`."""
    try:
        out = subprocess.run([os.path.join(BUILD, "bin", "gipsi"), "--version"],
                             capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    m = re.search(r"(\w+) kernels\)", out)
    return m.group(1) if m else "unknown"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="one repetition, without the haptic loop and the long scenes")
    parser.add_argument("--threads", type=int, action="append",
                        help="thread count(s) to run at (default: 1 and 2)")
    parser.add_argument("--repetitions", type=int, default=None,
                        help="repetitions per benchmark, medians reported (default 3; 1 --quick)")
    parser.add_argument("--no-build", action="store_true", help="use build/release as it is")
    parser.add_argument("--build-dir", help="a release build folder (implies --no-build)")
    parser.add_argument("--json", help="also write the figures to this file")
    parser.add_argument("--busy", action="store_true",
                        help="also measure each thread count beside a busy neighbour")
    args = parser.parse_args()
    global BUILD
    if args.build_dir:
        BUILD = os.path.abspath(args.build_dir)
        args.no_build = True
    threads = args.threads or [1, 2]
    if any(t < 1 for t in threads):
        parser.error("--threads must be at least 1")
    repetitions = args.repetitions or (1 if args.quick else 3)
    if repetitions < 1:
        parser.error("--repetitions must be at least 1")
    if not args.no_build:
        build()
    load_before = os.getloadavg()
    columns = [(t, False) for t in threads] + ([(t, True) for t in threads] if args.busy else [])
    results = {}
    for t, busy in columns:
        if busy:
            with BusyNeighbour():
                results[(t, busy)] = measure(t, repetitions, args.quick)
        else:
            results[(t, busy)] = measure(t, repetitions, args.quick)
    load_after = os.getloadavg()

    def title(t, busy):
        return f"{t} thread{'s' if t > 1 else ''}" + (", busy neighbour" if busy else "")

    print(f"GiPSi benchmarks: {cpu_model()}, {simd_kernels()} kernels, "
          f"{os.cpu_count()} logical CPUs, "
          f"load average {load_before[0]:.2f} before and {load_after[0]:.2f} after, "
          f"medians of {repetitions}")
    print()
    print("| figure | " + " | ".join(title(*c) for c in columns) + " |")
    print("|---|" + "---|" * len(columns))
    for name in results[columns[0]]:
        print(f"| {name} | " + " | ".join(f"{results[c][name]:.3g}" for c in columns) + " |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"cpu": cpu_model(), "kernels": simd_kernels(), "cpus": os.cpu_count(),
                       "load_before": load_before,
                       "load_after": load_after, "repetitions": repetitions,
                       "results": {f"{t} busy" if busy else str(t): results[(t, busy)]
                                   for t, busy in columns}}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
