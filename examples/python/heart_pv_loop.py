#!/usr/bin/env python3
"""The heart demo (scenes/heart.json) driven from Python.

Runs the beating left ventricle, prints each beat's summary as the run reaches it (a callback
per macro step), and plots the last beat's pressure-volume loop and the pressures with
matplotlib. From the checkout, after building:

    PYTHONPATH=build/release/python python3 examples/python/heart_pv_loop.py

Options: --until SECONDS (default: the scene's 4 s), --out FOLDER (default out/python).
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gipsi  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "..", "scenes", "heart.json")
MMHG = 133.322387415  # Pa
ML = 1e-6  # m^3


def run(until=None, out="out/python", quiet=False):
    """Runs the heart to `until` [s]; returns the per-beat summary and the PNG's path."""
    sim = gipsi.Simulation.from_file(SCENE)
    heart = sim.object("heart")
    summaries = []

    def each_macro_step(t):
        beats = int(heart.field("beats")[0, 0])
        if beats > len(summaries):  # a beat has just been completed
            row = {name: heart.field(name)[0, 0]
                   for name in ("end_diastolic_volume", "end_systolic_volume",
                                "ejection_fraction", "peak_chamber_pressure")}
            summaries.append(row)
            if not quiet:
                print(f"t = {t:5.2f} s  beat {beats}: EDV {row['end_diastolic_volume'] / ML:5.1f} mL"
                      f"  ESV {row['end_systolic_volume'] / ML:5.1f} mL"
                      f"  EF {100 * row['ejection_fraction']:4.1f} %"
                      f"  peak {row['peak_chamber_pressure'] / MMHG:5.1f} mmHg", flush=True)

    result = sim.run(until=until, callback=each_macro_step)
    if result["outcome"] != "completed":
        sys.exit(f"the heart did not complete: {result['diagnostic']}")

    pv = sim.probes["pv"]
    t = pv["time"]
    volume = pv["blood.lv_volume"] / ML
    pressure = pv["blood.lv_pressure"] / MMHG
    period = 0.8  # the pacing cycle of the scene
    last = t >= t[-1] - period  # the last beat

    os.makedirs(out, exist_ok=True)
    figure, (loop, traces) = plt.subplots(1, 2, figsize=(11, 4.5))
    loop.plot(volume[last], pressure[last], color="tab:red")
    loop.set_xlabel("LV volume [mL]")
    loop.set_ylabel("LV pressure [mmHg]")
    loop.set_title("Pressure-volume loop (last beat)")
    for column, label in (("blood.lv_pressure", "LV"), ("blood.aorta_pressure", "aorta"),
                          ("blood.la_pressure", "LA")):
        traces.plot(t, pv[column] / MMHG, label=label)
    traces.set_xlabel("time [s]")
    traces.set_ylabel("pressure [mmHg]")
    traces.legend()
    figure.tight_layout()
    png = os.path.join(out, "heart_pv_loop.png")
    figure.savefig(png, dpi=100)
    plt.close(figure)
    if not quiet:
        print(f"{result['macro_steps']} macro steps in {result['wall_seconds']:.1f} s; "
              f"loop plotted to {png}")
    return summaries, png


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--until", type=float, help="simulated seconds (default: 4)")
    parser.add_argument("--out", default="out/python", help="folder for the plot")
    args = parser.parse_args()
    run(args.until, args.out)


if __name__ == "__main__":
    main()
