"""The scripts of examples/python/, run shortened (ctest Python.Examples; pytest).

Each is checked against what it should show: the heart's beats and a PNG of its loop; the
Mitchell-Schaeffer APD90 growing with tau_close and above the paper's asymptotic lower estimate,
the threaded sweep equal bit for bit to serial calls; the baroreflex moving the resistance in
the direction of the pressure error every beat and the pressure toward its target.
"""
import importlib.util
import math
import os
import tempfile
import unittest

import gipsi

SOURCE_DIR = os.environ.get("GIPSI_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
MMHG = 133.322387415


def load(name):
    path = os.path.join(SOURCE_DIR, "examples", "python", name + ".py")
    spec = importlib.util.spec_from_file_location("example_" + name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def is_png(path):
    with open(path, "rb") as f:
        return f.read(8) == b"\x89PNG\r\n\x1a\n" and os.path.getsize(path) > 10000


class Examples(unittest.TestCase):
    def test_the_heart_from_python_beats_and_plots_its_loop(self):
        heart = load("heart_pv_loop")
        with tempfile.TemporaryDirectory() as out:
            summaries, png = heart.run(until=1.6, out=out, quiet=True)
            self.assertTrue(is_png(png), png)
        self.assertEqual(len(summaries), 2)  # beats end at 0.8 and 1.6 s
        for beat in summaries:
            # A working ventricle: it ejects (EDV > ESV) and pressurises above the aorta's
            # diastolic range; the demo's own figures are in docs/heart.md.
            self.assertGreater(beat["end_diastolic_volume"], beat["end_systolic_volume"])
            self.assertGreater(beat["ejection_fraction"], 0.2)
            self.assertGreater(beat["peak_chamber_pressure"], 60 * MMHG)

    def test_the_cell_sweep_grows_with_tau_close_above_the_lower_estimate(self):
        sweep = load("cell_sweep")
        values = [100.0, 150.0, 200.0]
        apds = sweep.sweep(values, beats=2, workers=2)
        self.assertEqual(apds, sorted(apds))
        for tau, apd in zip(values, apds):
            self.assertGreater(apd, sweep.lower_estimate(tau))
        # The threads changed nothing: a serial call gives the same bits.
        self.assertEqual(sweep.apd90(150.0, beats=2), apds[1])

    def test_pace_cell_refuses_bad_input_naming_the_key(self):
        with self.assertRaisesRegex(gipsi.InputError, "cell.tau_in"):
            gipsi.pace_cell({"model": "MitchellSchaeffer", "tau_in": -1})
        with self.assertRaisesRegex(gipsi.InputError, "MitchellSchaeffer"):
            gipsi.pace_cell({"model": "MitchelSchaeffer"})  # lists the known ones
        with self.assertRaises(gipsi.InputError):
            gipsi.pace_cell({"model": "MitchellSchaeffer"}, bcl=-1)
        result = gipsi.pace_cell({"model": "MitchellSchaeffer"}, beats=1, dt=0.05)
        self.assertTrue(math.isfinite(result["beats"]["apd"][0]))
        self.assertEqual(result["model"], "MitchellSchaeffer")

    def test_the_baroreflex_moves_the_pressure_toward_its_target(self):
        baroreflex = load("baroreflex")
        for target in (70.0, 110.0):  # below and above the demo's mean pressure
            with self.subTest(target=target):
                r0, history = baroreflex.run(target, gain=1.0, until=3.2, quiet=True)
                self.assertEqual(len(history), 3)  # beats ending at 0.8, 1.6, 2.4 s
                r = r0
                for _, mean, new in history:
                    # The rule's sign: R rises when MAP is below the target, falls above it,
                    # unless it is held at a limit (R0 / 2, 2 R0).
                    if new not in (r0 / 2, 2 * r0):
                        self.assertEqual(math.copysign(1, new - r),
                                         math.copysign(1, target * MMHG - mean))
                    r = new
                first, last = history[0][1], history[-1][1]
                self.assertLess(abs(last - target * MMHG), abs(first - target * MMHG))


if __name__ == "__main__":
    unittest.main()
