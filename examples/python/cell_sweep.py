#!/usr/bin/env python3
"""A parameter sweep of a cell model: the Mitchell-Schaeffer cell's APD90 against tau_close.

Paces one cell per value of tau_close (gipsi.pace_cell, which releases the GIL, so the sweep
runs on every core through a thread pool), measures the last beat's APD90, and plots it beside
the paper's asymptotic maximal APD, tau_close ln(tau_out / (4 tau_in)) (Mitchell & Schaeffer,
Bull. Math. Biol. 65:767, 2003), which is a lower estimate (docs/electrophysiology.md). From the
checkout, after building:

    PYTHONPATH=build/release/python python3 examples/python/cell_sweep.py

Options: --values MS MS ... (tau_close values), --beats N, --out FOLDER (default out/python).
"""
import argparse
import math
import os
from concurrent.futures import ThreadPoolExecutor

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import gipsi  # noqa: E402

TAU_IN, TAU_OUT = 0.3, 6.0  # ms, the model's defaults


def apd90(tau_close, beats=3, bcl=1000.0):
    """APD90 [ms] of the last of `beats` beats at basic cycle length `bcl` [ms]."""
    result = gipsi.pace_cell({"model": "MitchellSchaeffer", "tau_close": tau_close},
                             bcl=bcl, beats=beats, dt=0.05, record_every=0)
    return float(result["beats"]["apd"][-1])


def sweep(values, beats=3, workers=None):
    """APD90 for every tau_close in `values`, computed in parallel threads."""
    with ThreadPoolExecutor(max_workers=workers or os.cpu_count()) as pool:
        return list(pool.map(lambda v: apd90(v, beats), values))


def lower_estimate(tau_close):
    return tau_close * math.log(TAU_OUT / (4 * TAU_IN))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--values", type=float, nargs="+",
                        default=[90, 105, 120, 135, 150, 165, 180, 195, 210])
    parser.add_argument("--beats", type=int, default=3)
    parser.add_argument("--out", default="out/python")
    args = parser.parse_args()

    apds = sweep(args.values, args.beats)
    print(f"{'tau_close':>10} {'APD90':>8} {'lower est.':>10}")
    for tau, apd in zip(args.values, apds):
        print(f"{tau:10.1f} {apd:8.1f} {lower_estimate(tau):10.1f}")

    os.makedirs(args.out, exist_ok=True)
    figure, axes = plt.subplots(figsize=(6, 4))
    axes.plot(args.values, apds, "o-", label="APD90, paced at 1 Hz")
    axes.plot(args.values, [lower_estimate(v) for v in args.values], "--",
              label=r"$\tau_{close}\,\ln(\tau_{out}/4\tau_{in})$")
    axes.set_xlabel(r"$\tau_{close}$ [ms]")
    axes.set_ylabel("APD [ms]")
    axes.set_title("Mitchell-Schaeffer: APD against tau_close")
    axes.legend()
    figure.tight_layout()
    png = os.path.join(args.out, "cell_sweep.png")
    figure.savefig(png, dpi=100)
    print(f"plotted to {png}")


if __name__ == "__main__":
    main()
