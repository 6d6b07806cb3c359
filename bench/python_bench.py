#!/usr/bin/env python3
"""What the Python module costs (issue 19's benchmark; docs/performance.md, "Python").

1. The heart demo's macro step driven from Python (sim.step() in a Python loop, reading the
   muscle's positions each step) against the same steps run by the C++ kernel's own loop
   (sim.run(until=...)). Two simulations start identically and advance through the same
   simulated interval in alternating blocks, so both see the same phases of the beat; the
   figure is the median over blocks of the per-step ratio.
2. Reading every node position of a FemSolid through `positions` (a view, no copy) against
   `field("position")` (a copy), for boxes of 6k, 25k and 83k tets: the view's time does not
   grow with the mesh.

    OMP_NUM_THREADS=1 PYTHONPATH=build/release/python /usr/bin/python3 bench/python_bench.py
"""
import argparse
import os
import statistics
import time

import numpy as np

import gipsi

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "scenes")


def heart_overhead(blocks, steps):
    cpp = gipsi.Simulation.from_file(os.path.join(SCENES, "heart.json"))
    py = gipsi.Simulation.from_file(os.path.join(SCENES, "heart.json"))
    muscle = py.object("heart.muscle")
    dt = cpp.macro_dt
    warm = 0.2
    cpp.run(until=warm)
    py.run(until=warm)
    ratios, cpp_ms, py_ms = [], [], []
    for b in range(blocks):
        until = warm + (b + 1) * steps * dt
        start = time.perf_counter()
        cpp.run(until=until)
        t_cpp = time.perf_counter() - start
        start = time.perf_counter()
        total = 0.0
        for _ in range(steps):
            py.step()
            total += muscle.positions[0, 2]  # a read of the state each step
        t_py = time.perf_counter() - start
        ratios.append(t_py / t_cpp)
        cpp_ms.append(1e3 * t_cpp / steps)
        py_ms.append(1e3 * t_py / steps)
    assert cpp.time == py.time
    same = np.array_equal(cpp.object("heart.muscle").positions, muscle.positions)
    return statistics.median(cpp_ms), statistics.median(py_ms), statistics.median(ratios), same


def box_scene(n):
    return {"gipsi": 1, "units": "SI",
            "meshes": {"box": {"generate": "box", "min": [0, 0, 0], "max": [0.1, 0.1, 0.1],
                               "cells": [n, n, n]}},
            "objects": {"box": {"type": "FemSolid", "domain": "box", "dt": 0.01,
                                "density": 1000, "integrator": "BackwardEuler",
                                "material": {"law": "Corotational", "youngs_modulus": 1e4,
                                             "poisson_ratio": 0.45}}},
            "schedule": {"end": 0.01}}


def read_positions(sizes, repeats):
    rows = []
    for n in sizes:
        sim = gipsi.Simulation.from_dict(box_scene(n))
        box = sim.object("box")
        tets = box.tets.shape[0]

        def time_it(read, count):
            samples = []
            for _ in range(5):
                start = time.perf_counter()
                for _ in range(count):
                    x = read()
                samples.append((time.perf_counter() - start) / count)
            assert x.shape == (box.positions.shape[0], 3)
            return statistics.median(samples)

        view = time_it(lambda: box.positions, repeats)
        copy = time_it(lambda: box.field("position"), max(1, repeats // 100))
        rows.append((tets, view, copy))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", type=int, default=9)
    parser.add_argument("--steps", type=int, default=20, help="macro steps per block")
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 16, 24])
    parser.add_argument("--repeats", type=int, default=20000)
    args = parser.parse_args()
    print(f"gipsi {gipsi.__version__}; OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', '(unset)')}")
    cpp, py, ratio, same = heart_overhead(args.blocks, args.steps)
    print(f"heart macro step: C++ loop {cpp:.3f} ms, Python loop {py:.3f} ms; "
          f"median ratio {ratio:.4f} ({100 * (ratio - 1):+.2f} %); same positions: {same}")
    for tets, view, copy in read_positions(args.sizes, args.repeats):
        print(f"{tets:6d} tets: positions (view) {1e6 * view:7.2f} us, "
              f"field('position') (copy) {1e6 * copy:8.1f} us")


if __name__ == "__main__":
    main()
