#!/usr/bin/env python3
"""A connector written in Python: a baroreflex-like feedback on the heart demo.

Each beat, the Baroreflex connector averages the aortic pressure and then changes the systemic
(peripheral) resistance of the heart's circulation by a proportional rule,

    R <- R (1 + gain (target - MAP) / target),   clamped to [R0 / 2, 2 R0],

so a mean arterial pressure below the target constricts the vessels (R up) and one above it
dilates them. The kernel fires it every macro step at its place in the order, with its ports
(the aortic pressure it reads, the resistance it writes) checked like a built-in connector's;
its running average is its state, saved in checkpoints. From the checkout, after building:

    PYTHONPATH=build/release/python python3 examples/python/baroreflex.py

Options: --target MMHG (default 100), --gain G (default 1), --until SECONDS (default 4).
"""
import argparse
import json
import os

import gipsi

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "..", "scenes")
MMHG = 133.322387415  # Pa


class Baroreflex(gipsi.ConnectorBase):
    ports = {"pressure": {"access": "read", "units": "Pa", "components": 1},
             "resistance": {"access": "read_write", "units": "Pa*s/m3", "components": 1}}
    parameters = ("target", "gain", "period")

    def __init__(self, name, params):
        super().__init__(name, params)
        self.total, self.samples = 0.0, 0
        self.beat_end = params["period"]
        self.r0 = None
        self.history = []  # (time, MAP, new R) per beat

    def fire(self, t, values):
        pressure, resistance = values["pressure"][0, 0], values["resistance"][0, 0]
        if self.r0 is None:
            self.r0 = resistance
        if t < self.beat_end - 1e-9:
            self.total += pressure
            self.samples += 1
            return None
        mean = self.total / self.samples
        error = (self.params["target"] - mean) / self.params["target"]
        new = min(2 * self.r0, max(0.5 * self.r0, resistance * (1 + self.params["gain"] * error)))
        self.history.append((t, mean, new))
        self.total, self.samples = pressure, 1
        self.beat_end += self.params["period"]
        return {"resistance": [new]}

    def get_state(self):
        return json.dumps([self.total, self.samples, self.beat_end, self.r0,
                           self.history]).encode()

    def set_state(self, state):
        self.total, self.samples, self.beat_end, self.r0, history = json.loads(state)
        self.history = [tuple(h) for h in history]


gipsi.register_connector("Baroreflex", Baroreflex,
                         "changes a resistance each beat from the mean of a pressure")


def run(target_mmhg=100.0, gain=1.0, until=None, quiet=False):
    """Runs the heart with the baroreflex; returns its per-beat (time, MAP, R) history."""
    with open(os.path.join(SCENES, "heart.json"), encoding="utf-8") as f:
        scene = json.load(f)
    scene["connectors"] = {"baroreflex": {
        "type": "Baroreflex", "pressure": "heart.blood.aorta_pressure",
        "resistance": "heart.blood.peripheral_resistance",
        "target": target_mmhg * MMHG, "gain": gain, "period": 0.8}}
    del scene["outputs"]  # in memory only
    sim = gipsi.Simulation.from_dict(scene, name="heart_baroreflex.json", base_dir=SCENES)
    r0 = sim.object("heart.blood").field("peripheral_resistance")[0, 0]
    result = sim.run(until=until)
    if result["outcome"] != "completed":
        raise RuntimeError(result["diagnostic"])
    history = sim.connector("baroreflex").impl.history  # the instance the kernel fired
    if not quiet:
        print(f"target MAP {target_mmhg:.0f} mmHg; R0 {r0 * 1e-6 / MMHG:.3f} mmHg*s/mL")
        for t, mean, r in history:
            print(f"beat ending t = {t:4.2f} s: MAP {mean / MMHG:6.1f} mmHg -> R "
                  f"{r * 1e-6 / MMHG:.3f} mmHg*s/mL")
    return r0, history


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--target", type=float, default=100.0, help="target MAP [mmHg]")
    parser.add_argument("--gain", type=float, default=1.0)
    parser.add_argument("--until", type=float, help="simulated seconds (default: 4)")
    args = parser.parse_args()
    run(args.target, args.gain, args.until)


if __name__ == "__main__":
    main()
