"""The gipsi Python module (python/gipsi_module.cc; docs/python.md), run by ctest as
Python.Module with PYTHONPATH pointing at the build tree's module.

Physics checks have exact answers: a free sheet under gravity falls as -g t^2 / 2 (RK4 is exact
for a constant acceleration, and unstretched springs exert no force), and a force written into
every node changes the total momentum by N f t (spring forces cancel in the sum).
"""
import contextlib
import io
import os
import re
import tempfile
import threading
import unittest

import numpy as np

import gipsi

SOURCE_DIR = os.environ.get("GIPSI_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
G = 9.81


def sheet_scene(gravity=(0.0, 0.0, -G), end=0.2, integrator="RK4"):
    """A free 10 x 10 cm mass-spring sheet (no pins, no damping, no drag), as a dict."""
    return {
        "gipsi": 1,
        "units": "SI",
        "meshes": {"sheet": {"generate": "sheet", "origin": [0, 0, 0], "u": [0.1, 0, 0],
                             "v": [0, 0.1, 0], "cells": [4, 4]}},
        "objects": {"sheet": {"type": "MassSpring", "domain": "sheet", "density": 1000,
                              "thickness": 0.001, "stiffness": 20, "damping": 0, "drag": 0,
                              "gravity": list(gravity), "integrator": integrator, "dt": 0.001}},
        "schedule": {"end": end, "dt": 0.01},
        "probes": {"energy": {"object": "sheet", "fields": ["kinetic_energy"], "every": 0.02}},
    }


class Module(unittest.TestCase):
    def test_names_its_version_and_plugin_interface(self):
        self.assertRegex(gipsi.__version__, r"^\d+\.\d+\.\d+$")
        self.assertGreaterEqual(gipsi.plugin_interface, 11)


class Running(unittest.TestCase):
    def test_a_free_sheet_falls_as_minus_g_t_squared_over_two(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        sheet = sim.object("sheet")
        x = sheet.positions  # a view: it follows the state as the simulation runs
        z0 = x[:, 2].copy()
        result = sim.run(until=0.1)
        self.assertEqual(result["outcome"], "completed")
        self.assertEqual(sim.macro_steps, 10)
        t = sim.time
        self.assertAlmostEqual(t, 0.1, delta=1e-12)
        # Rounding only: 100 RK4 steps of a 5 m/s^2-scale motion.
        np.testing.assert_allclose(x[:, 2], z0 - G * t * t / 2, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(x[:, :2], sheet.rest_positions[:, :2])

    def test_positions_are_a_read_only_view_without_a_copy(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        sheet = sim.object("sheet")
        x = sheet.positions
        self.assertFalse(x.flags.writeable)
        self.assertEqual(x.shape, (25, 3))
        before = x.copy()
        sim.step()
        self.assertFalse(np.array_equal(before, x))  # the same array now shows the new state
        self.assertTrue(np.shares_memory(x, sheet.positions))
        with self.assertRaises(ValueError):
            x[0, 0] = 1.0
        del sim  # the view keeps the simulation alive
        self.assertTrue(np.all(np.isfinite(x)))

    def test_stored_fields_are_views_that_follow_the_state_without_a_copy(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        sheet = sim.object("sheet")
        stored = [name for name, f in sheet.fields.items() if f["view"]]
        self.assertEqual(stored, ["position", "velocity", "external_force"])
        views = {name: sheet.view(name) for name in stored}
        address = {name: v.__array_interface__["data"][0] for name, v in views.items()}
        state = sim.save()

        def check():
            for name, v in views.items():
                self.assertFalse(v.flags.writeable)
                # The same memory, and what the object itself reads for the field.
                self.assertEqual(sheet.view(name).__array_interface__["data"][0], address[name])
                np.testing.assert_array_equal(v, sheet.field(name))

        sim.run(until=0.05)
        check()
        self.assertTrue(np.any(views["velocity"] != 0))  # it falls
        # Views and copies carry the field's name, units and location.
        velocity = views["velocity"]
        self.assertEqual((velocity.field, velocity.units, velocity.location),
                         ("velocity", "m/s", "node"))
        energy = sheet.field("kinetic_energy")
        self.assertIsInstance(energy, gipsi.FieldArray)
        self.assertEqual((energy.units, energy.location, energy.shape), ("J", "global", (1, 1)))
        force = np.tile([0.0, 0.0, 0.5], (25, 1))
        sheet.set_field("external_force", force)  # a write, seen through the view
        np.testing.assert_array_equal(views["external_force"], force)
        sim.restore(state)  # restores copy into the same memory
        check()
        np.testing.assert_array_equal(views["velocity"], 0)
        with self.assertRaisesRegex(ValueError, "field 'kinetic_energy' of 'sheet' is computed "
                                    "on request.*fields with views: position, velocity"):
            sheet.view("kinetic_energy")
        v = views["position"]
        del sim, sheet, views  # the view keeps the simulation alive
        self.assertTrue(np.all(np.isfinite(v)))

    def test_the_cell_states_of_a_monodomain_are_views(self):
        scene = {
            "gipsi": 1, "units": "SI",
            "meshes": {"bar": {"generate": "box", "min": [0, 0, 0], "max": [0.004, 0.001, 0.001],
                               "cells": [8, 2, 2]}},
            "objects": {"tissue": {
                "type": "Monodomain", "domain": "bar", "dt": "0.05 ms",
                "cell": {"model": "MitchellSchaeffer"}, "conductivity": "0.2 S/m",
                "stimuli": {"end": {"region": {"box": {"min": [0, 0, 0],
                                                       "max": [0.0005, 0.001, 0.001]}},
                                    "amplitude": "50 uA/uF", "duration": "2 ms"}}}},
            "schedule": {"end": 0.005, "dt": 0.0005}}
        sim = gipsi.Simulation.from_dict(scene)
        tissue = sim.object("tissue")
        v = tissue.view("V")
        self.assertEqual(v.shape, (tissue.fields["V"]["count"], 1))
        sim.run()
        np.testing.assert_array_equal(v, tissue.field("V"))
        self.assertGreater(v.max(), 0.0)  # the stimulated end is excited (mV)
        np.testing.assert_array_equal(tissue.view("activation_time"),
                                      tissue.field("activation_time"))
        self.check_views_hold(sim, scene_until=0.005)

    def check_views_hold(self, sim, scene_until):
        """Every stored field of every object keeps its address through steps, a restore of
        bytes and of a checkpoint file, and always equals field()."""
        views = {(o, n): sim.object(o).view(n) for o in sim.objects
                 for n, f in sim.object(o).fields.items() if f["view"]}
        self.assertTrue(views)
        address = {k: v.__array_interface__["data"][0] for k, v in views.items()}
        state = sim.save()

        def check():
            for (o, n), v in views.items():
                with self.subTest(object=o, field=n):
                    self.assertEqual(sim.object(o).view(n).__array_interface__["data"][0],
                                     address[(o, n)])
                    np.testing.assert_array_equal(v, sim.object(o).field(n))

        sim.step()
        check()
        sim.restore(state)
        check()
        with tempfile.TemporaryDirectory() as tmp:
            sim.save_file(os.path.join(tmp, "c.ckpt"))
            sim.step()
            sim.restore_file(os.path.join(tmp, "c.ckpt"))
        check()

    def test_the_views_of_fem_solids_and_a_grid_monodomain_hold_their_address(self):
        for scene in ("cantilever.json", "cantilever_explicit.json", "slab_ep_grid_0.5mm.json"):
            with self.subTest(scene=scene):
                sim = gipsi.Simulation.from_file(os.path.join(SOURCE_DIR, "scenes", scene))
                sim.run(until=2 * sim.macro_dt)
                self.check_views_hold(sim, scene_until=None)

    def test_the_gil_is_released_while_it_runs(self):
        # A second Python thread counts while run() steps C++ code; with the GIL held it
        # could not run at all until run() returned.
        sim = gipsi.Simulation.from_file(os.path.join(SOURCE_DIR, "scenes", "heart.json"))
        counts, done = [0], threading.Event()

        def count():
            while not done.is_set():
                counts[0] += 1

        counter = threading.Thread(target=count)
        counter.start()
        try:
            while counts[0] == 0:
                pass
            before = counts[0]
            result = sim.run(until=0.1)
            during = counts[0] - before
        finally:
            done.set()
            counter.join()
        self.assertEqual(result["outcome"], "completed")
        self.assertGreater(during, 10000)

    def test_fields_read_in_their_declared_shape(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        sheet = sim.object("sheet")
        sim.run(until=0.05)
        info = sheet.fields["displacement"]
        self.assertEqual((info["location"], info["components"], info["count"], info["units"]),
                         ("node", 3, 25, "m"))
        np.testing.assert_array_equal(sheet.field("displacement"),
                                      sheet.positions - sheet.rest_positions)
        self.assertEqual(sheet.field("kinetic_energy").shape, (1, 1))

    def test_a_written_force_changes_the_momentum_by_n_f_t(self):
        sim = gipsi.Simulation.from_dict(sheet_scene(gravity=(0, 0, 0)))
        sheet = sim.object("sheet")
        f = np.array([0.0, 0.002, 0.001])
        force = np.tile(f, (25, 1))
        for _ in range(10):  # a coupling load lasts one macro step: set it before each
            sheet.set_field("external_force", force)
            sim.step()
        momentum = sheet.field("momentum")[0]
        np.testing.assert_allclose(momentum, 25 * f * sim.time, rtol=1e-12, atol=1e-17)

    def test_writes_are_checked_like_a_connectors_port(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        sheet = sim.object("sheet")
        with self.assertRaisesRegex(ValueError, r"read-only"):
            sheet.set_field("displacement", np.zeros((25, 3)))
        before = sheet.field("external_force")
        with self.assertRaisesRegex(ValueError, r"field 'external_force' of 'sheet' takes an array "
                                    r"of shape \(25, 3\) in \[N\], got \(24, 3\); nothing was "
                                    r"written"):
            sheet.set_field("external_force", np.ones((24, 3)))
        np.testing.assert_array_equal(sheet.field("external_force"), before)
        with self.assertRaisesRegex(TypeError, r"set_field"):  # not numbers at all
            sheet.set_field("external_force", "forces")
        bad = np.zeros((25, 3))
        bad[7, 1] = np.nan
        with self.assertRaisesRegex(ValueError, r"value 22 is not finite"):
            sheet.set_field("external_force", bad)
        with self.assertRaisesRegex(KeyError, r"no field 'pressure'.*external_force"):
            sheet.field("pressure")

    def test_a_callback_can_stop_the_run_and_its_exceptions_propagate(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        seen = []
        result = sim.run(callback=lambda t: seen.append(t) or t < 0.05 - 1e-9)
        self.assertEqual(result["outcome"], "stopped")
        self.assertAlmostEqual(sim.time, 0.05, delta=1e-12)
        self.assertEqual(len(seen), 5)

        def fail(t):
            raise RuntimeError("from the callback")

        with tempfile.TemporaryDirectory() as tmp:
            sim.write_outputs(tmp)
            with self.assertRaisesRegex(RuntimeError, "from the callback"):
                sim.run(callback=fail)
            self.assertAlmostEqual(sim.time, 0.06, delta=1e-12)  # stopped after that step
            # The outputs are kept and complete up to the stop: the probe's row at 0.06 in
            # memory and in its CSV, and a closed PVD index listing the frame written then.
            self.assertAlmostEqual(sim.probes["energy"]["time"][-1], 0.06, delta=1e-12)
            csv = np.loadtxt(os.path.join(tmp, "probes", "energy.csv"), delimiter=",",
                             skiprows=1, ndmin=2)
            self.assertAlmostEqual(csv[-1, 0], 0.06, delta=1e-12)
            with open(os.path.join(tmp, "sheet.pvd"), encoding="utf-8") as f:
                pvd = f.read()
            self.assertTrue(pvd.rstrip().endswith("</VTKFile>"))
            self.assertIn('timestep="0.06"', pvd)
            self.assertEqual(sim.run(until=0.08)["outcome"], "completed")  # it may go on


    def test_a_scheduled_python_event_fires_once_at_its_time(self):
        sim = gipsi.Simulation.from_dict(sheet_scene(gravity=(0, 0, 0)))
        times = []
        sim.schedule(0.05, lambda s: times.append(s.time), "note the time")
        sim.run(until=0.1)
        self.assertEqual(len(times), 1)
        self.assertAlmostEqual(times[0], 0.05, delta=1e-12)
        self.assertEqual(len(sim.fired_events), 1)
        self.assertAlmostEqual(sim.fired_events[0][0], 0.05, delta=1e-12)
        self.assertEqual(sim.fired_events[0][1], "note the time")

    def test_an_event_that_raises_stops_the_run_and_the_exception_propagates(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())

        def fail(s):
            raise KeyError("from the event")

        sim.schedule(0.03, fail)
        with self.assertRaisesRegex(KeyError, "from the event"):
            sim.run()
        self.assertAlmostEqual(sim.time, 0.03, delta=1e-12)  # the step it was due in not taken
        self.assertEqual(sim.run(until=0.05)["outcome"], "completed")  # it fired once


    def test_a_callback_may_read_and_write_fields_but_not_run_or_restore(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        state = sim.save()
        sheet = sim.object("sheet")
        energies = []

        def callback(t):
            energies.append(sheet.field("kinetic_energy")[0, 0])
            sheet.set_field("external_force", np.zeros((25, 3)))
            sim.save()
            if t > 0.025:
                sim.step()

        with self.assertRaisesRegex(RuntimeError, "run: the simulation is running"):
            sim.run(callback=callback)
        self.assertEqual(len(energies), 3)
        for forbidden in (lambda: sim.restore(state), lambda: sim.schedule(1, print)):
            with self.assertRaisesRegex(RuntimeError, "the simulation is running"):
                sim.run(callback=lambda t: forbidden())

    def test_another_thread_may_not_touch_fields_while_it_runs(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        sheet = sim.object("sheet")
        started, checked = threading.Event(), threading.Event()
        outcome = []

        def callback(t):
            started.set()
            checked.wait(timeout=60)
            return False

        worker = threading.Thread(target=lambda: outcome.append(sim.run(callback=callback)))
        worker.start()
        self.assertTrue(started.wait(timeout=60))
        with self.assertRaisesRegex(RuntimeError, "running on another thread"):
            sheet.field("displacement")
        with self.assertRaisesRegex(RuntimeError, "running on another thread"):
            sheet.set_field("external_force", np.zeros((25, 3)))
        checked.set()
        worker.join()
        self.assertEqual(outcome[0]["outcome"], "stopped")
        self.assertEqual(sheet.field("displacement").shape, (25, 3))  # fine once it returned


class Checkpoints(unittest.TestCase):
    def test_restoring_bytes_repeats_the_run_bitwise_with_its_probes(self):
        sim = gipsi.Simulation.from_dict(sheet_scene(integrator="SymplecticEuler"))
        sim.run(until=0.1)
        state = sim.save()
        self.assertIsInstance(state, bytes)
        sim.run(until=0.2)
        first = sim.object("sheet").positions.copy()
        first_probe = sim.probes["energy"]
        sim.restore(state)
        self.assertAlmostEqual(sim.time, 0.1, delta=1e-12)
        self.assertEqual(len(sim.probes["energy"]["time"]), 6)  # 0, 0.02, ..., 0.1
        sim.run(until=0.2)
        np.testing.assert_array_equal(sim.object("sheet").positions, first)
        for column, values in first_probe.items():
            np.testing.assert_array_equal(sim.probes["energy"][column], values)

    def test_a_checkpoint_file_resumes_in_a_fresh_simulation(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "sheet.ckpt")
            sim = gipsi.Simulation.from_dict(sheet_scene())
            sim.run(until=0.1)
            sim.save_file(path)
            sim.run(until=0.2)
            fresh = gipsi.Simulation.from_dict(sheet_scene())
            fresh.restore_file(path)
            fresh.run(until=0.2)
            np.testing.assert_array_equal(fresh.object("sheet").positions,
                                          sim.object("sheet").positions)

    def test_bytes_of_another_scene_are_refused(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        other = sheet_scene()
        other["meshes"]["sheet"]["cells"] = [5, 5]
        with self.assertRaisesRegex(gipsi.InputError, "checkpoint bytes"):
            gipsi.Simulation.from_dict(other).restore(sim.save())


class Errors(unittest.TestCase):
    def test_a_bad_value_raises_input_error_with_its_json_path(self):
        scene = sheet_scene()
        scene["objects"]["sheet"]["density"] = -1
        with self.assertRaises(gipsi.InputError) as raised:
            gipsi.Simulation.from_dict(scene, name="my_scene.json")
        e = raised.exception
        self.assertIsInstance(e, ValueError)
        self.assertEqual(e.file, "my_scene.json")
        self.assertEqual(e.path, "objects.sheet.density")
        self.assertIn("positive", e.what)

    def test_a_missing_top_level_key_names_the_document_root(self):
        with self.assertRaises(gipsi.InputError) as raised:
            gipsi.Simulation.from_dict({"gipsi": 1, "objects": {}})
        self.assertEqual(raised.exception.path, "")
        self.assertIn("missing required key 'schedule'", raised.exception.what)

    def test_an_unknown_object_raises_input_error_listing_the_objects(self):
        sim = gipsi.Simulation.from_dict(sheet_scene())
        with self.assertRaisesRegex(gipsi.InputError, "sheet"):
            sim.object("sheeet")


class Meshes(unittest.TestCase):
    def test_read_mesh_gives_the_arrays_a_scene_builds_from_the_file(self):
        path = os.path.join(SOURCE_DIR, "scenes", "meshes", "liver.msh")
        mesh = gipsi.read_mesh(path)
        self.assertEqual(mesh["nodes"].shape[1], 3)
        self.assertEqual(mesh["tets"].shape[1], 4)
        self.assertGreater(len(mesh["tets"]), 100)
        scene = {"gipsi": 1, "units": "SI", "meshes": {"liver": {"file": path}},
                 "objects": {"liver": {"type": "MassSpring", "domain": "liver", "density": 1000,
                                       "stiffness": 100, "dt": 0.001}},
                 "schedule": {"end": 0.01, "dt": 0.001}}
        liver = gipsi.Simulation.from_dict(scene).object("liver")
        np.testing.assert_array_equal(liver.rest_positions, mesh["nodes"])
        np.testing.assert_array_equal(liver.tets, mesh["tets"])

    def test_read_mesh_gives_a_second_order_files_edge_nodes_apart(self):
        path = os.path.join(SOURCE_DIR, "tests", "data", "meshes", "two_tets_order2_v22.msh")
        mesh = gipsi.read_mesh(path)
        self.assertEqual(mesh["nodes"].shape, (5, 3))
        self.assertEqual(mesh["edge_nodes"].shape, (9, 3))
        np.testing.assert_array_equal(mesh["edge_node_ends"][0], [0, 1])
        np.testing.assert_array_equal(mesh["edge_nodes"][0], [0.5, -0.1, 0])
        linear = gipsi.read_mesh(os.path.join(SOURCE_DIR, "scenes", "meshes", "liver.msh"))
        self.assertNotIn("edge_nodes", linear)

    def test_write_mesh_then_read_mesh_gives_the_arrays_back(self):
        nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.5]], dtype=float)
        tets = np.array([[0, 1, 2, 3]])
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "tet.vtu")
            gipsi.write_mesh(path, {"nodes": nodes, "tets": tets})
            mesh = gipsi.read_mesh(path)
        np.testing.assert_array_equal(mesh["nodes"], nodes)
        np.testing.assert_array_equal(mesh["tets"], tets)

    def test_write_mesh_checks_the_arrays_as_a_scene_does(self):
        nodes = np.zeros((4, 3))
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "bad.vtu")
            with self.assertRaises(gipsi.InputError) as raised:
                gipsi.write_mesh(path, {"nodes": nodes, "tets": np.array([[0, 1, 2, 4]])})
            self.assertEqual(raised.exception.file, path)
            self.assertEqual(raised.exception.path, "tets[0][3]")
            with self.assertRaisesRegex(KeyError, "unknown key 'tet'"):
                gipsi.write_mesh(path, {"nodes": nodes, "tet": np.array([[0, 1, 2, 3]])})
            self.assertFalse(os.path.exists(path))

    def test_a_mesh_given_as_numpy_arrays_falls_as_the_generated_one(self):
        generated = gipsi.Simulation.from_dict(sheet_scene())
        mesh = generated.mesh("sheet")
        self.assertEqual(mesh["nodes"].shape, (25, 3))
        self.assertEqual(mesh["triangles"].shape, (32, 3))
        scene = sheet_scene()
        scene["meshes"]["sheet"] = {"nodes": mesh["nodes"], "triangles": mesh["triangles"]}
        built = gipsi.Simulation.from_dict(scene)
        generated.run(until=0.05)
        built.run(until=0.05)
        np.testing.assert_array_equal(built.object("sheet").positions,
                                      generated.object("sheet").positions)

    def test_nan_in_a_numpy_mesh_is_refused(self):
        scene = sheet_scene()
        nodes = np.zeros((3, 3))
        nodes[1, 2] = np.nan
        scene["meshes"]["sheet"] = {"nodes": nodes, "triangles": np.array([[0, 1, 2]])}
        with self.assertRaisesRegex(ValueError, "JSON"):
            gipsi.Simulation.from_dict(scene)

    def test_a_missing_mesh_file_raises_input_error_naming_it(self):
        with self.assertRaisesRegex(gipsi.InputError, "no_such.msh"):
            gipsi.read_mesh("no_such.msh")


class Outputs(unittest.TestCase):
    def test_write_outputs_writes_the_series_gipsi_run_writes(self):
        with tempfile.TemporaryDirectory() as tmp:
            sim = gipsi.Simulation.from_dict(sheet_scene(end=0.05))
            sim.write_outputs(tmp)
            self.assertEqual(sim.run()["outcome"], "completed")
            self.assertTrue(os.path.exists(os.path.join(tmp, "sheet.pvd")))
            self.assertTrue(os.path.exists(os.path.join(tmp, "probes", "energy.csv")))

    def test_probes_in_memory_hold_the_rows_of_the_csvs(self):
        # Point, region and line probes, the sampling interval off the macro-step grid: memory
        # and files take their samples at the same times, with the same values.
        scene = sheet_scene(end=0.1)
        scene["probes"] = {
            "energy": {"object": "sheet", "fields": ["kinetic_energy"], "every": 0.025},
            "corner": {"object": "sheet", "point": [0, 0, 0], "fields": ["displacement"],
                       "every": 0.03},
            "edge": {"object": "sheet", "field": "displacement", "at": [0.02, 0.05, 0.051],
                     "line": {"from": [0, 0, 0], "to": [0.1, 0, 0], "points": 5}},
            "final": {"object": "sheet", "field": "displacement",
                      "line": {"from": [0, 0.05, 0], "to": [0.1, 0.05, 0], "points": 3}}}
        with tempfile.TemporaryDirectory() as tmp:
            sim = gipsi.Simulation.from_dict(scene)
            sim.write_outputs(tmp)
            self.assertEqual(sim.run()["outcome"], "completed")
            probes = sim.probes
            for name in ("energy", "corner"):
                csv = np.loadtxt(os.path.join(tmp, "probes", name + ".csv"), delimiter=",",
                                 skiprows=1, ndmin=2)
                columns = list(probes[name])
                np.testing.assert_allclose(
                    np.column_stack([probes[name][c] for c in columns]), csv, rtol=1e-9,
                    atol=1e-15)
            self.assertEqual(len(probes["energy"]["time"]), 5)  # 0, 0.025 .. 0.1 (on 0.03, ...)
            # 0.051 is first reached by the macro step at 0.06.
            for name, times in (("edge", [0.02, 0.05, 0.06]), ("final", [0.1])):
                memory = probes[name]
                np.testing.assert_allclose(memory["time"], times, atol=1e-12)
                points = len(memory["distance"])
                self.assertEqual(memory["displacement_z"].shape, (len(times), points))
                csv = np.loadtxt(os.path.join(tmp, "probes", name + ".csv"), delimiter=",",
                                 skiprows=1, ndmin=2)
                # The CSV: one row per point and time (time, distance, x, y, z, fields).
                np.testing.assert_allclose(csv[:, 0], np.repeat(memory["time"], points))
                np.testing.assert_allclose(csv[:, 1], np.tile(memory["distance"], len(times)))
                np.testing.assert_allclose(csv[:, 4], np.tile(memory["z"], len(times)))
                np.testing.assert_allclose(csv[:, 7], memory["displacement_z"].ravel(),
                                           rtol=1e-9, atol=1e-15)
            self.assertLess(probes["edge"]["displacement_z"][1, 0], 0)  # falling
        # A restore to t = 0.03 drops the later rows, and running again records them anew.
        state_at = gipsi.Simulation.from_dict(scene)
        state_at.run(until=0.03)
        saved = state_at.save()
        state_at.run()
        rows = {k: v["time"].copy() for k, v in state_at.probes.items()}
        state_at.restore(saved)
        self.assertEqual(len(state_at.probes["edge"]["time"]), 1)
        state_at.run()
        for k, v in state_at.probes.items():
            np.testing.assert_array_equal(v["time"], rows[k])



class Decay:
    """dx/dt = -k x, stepped in closed form; reads its input u (added to x once per step)."""

    fields = {"x": {"units": "1", "access": "read", "description": "the decaying value"},
              "u": {"units": "1", "access": "write", "description": "a kick added per step"}}

    def __init__(self, name, params):
        if params.get("rate", 1.0) <= 0:
            raise ValueError("rate must be positive")
        self.k = params.get("rate", 1.0)
        self.x = params.get("start", 1.0)
        self.u = 0.0

    def step(self, t, dt):
        self.x = self.x * np.exp(-self.k * dt) + self.u
        self.u = 0.0

    def read(self, name):
        return [self.x]

    def write(self, name, values):
        self.u = float(values[0])

    def get_state(self):
        return np.array([self.x, self.u]).tobytes()

    def set_state(self, state):
        self.x, self.u = np.frombuffer(state)


def decay_scene(**extra):
    scene = {"gipsi": 1, "units": "SI",
             "objects": {"a": {"type": "Decay", "rate": 2.0, "dt": 0.01},
                         "b": {"type": "Decay", "rate": 1.0, "start": 0.0, "dt": 0.01}},
             "schedule": {"end": 1.0, "dt": 0.01},
             "probes": {"a": {"object": "a", "fields": ["x"], "every": 0.1}}}
    scene.update(extra)
    return scene


class PythonObjects(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        gipsi.register_object("Decay", Decay, "dx/dt = -k x")

    def test_a_python_object_steps_in_the_kernel_and_is_probed(self):
        sim = gipsi.Simulation.from_dict(decay_scene())
        self.assertEqual(sim.object("a").type, "Decay")
        self.assertEqual(sim.object("a").fields["u"]["access"], "write")
        sim.run()
        probe = sim.probes["a"]
        np.testing.assert_allclose(probe["x"], np.exp(-2.0 * probe["time"]), rtol=1e-12)

    def test_a_builtin_connector_couples_two_python_objects(self):
        scene = decay_scene(connectors={"kick": {"type": "FieldCopy", "from": "a.x", "to": "b.u"}})
        sim = gipsi.Simulation.from_dict(scene)
        sim.run(until=0.05)
        # b gets a's value at the start of each step: b_n+1 = b_n e^(-dt) + a_n, a_n = e^(-2 n dt).
        dt, b = 0.01, 0.0
        for n in range(5):
            b = b * np.exp(-dt) + np.exp(-2.0 * n * dt)
        self.assertAlmostEqual(sim.object("b").field("x")[0, 0], b, delta=1e-14)

    def test_a_python_object_resumes_bitwise_from_its_state(self):
        sim = gipsi.Simulation.from_dict(decay_scene())
        sim.run(until=0.3)
        state = sim.save()
        sim.run(until=0.7)
        x = sim.object("a").field("x")
        sim.restore(state)
        sim.run(until=0.7)
        np.testing.assert_array_equal(sim.object("a").field("x"), x)

    def test_a_failing_python_step_stops_the_run_with_its_reason(self):
        class Broken(Decay):
            def step(self, t, dt):
                raise ZeroDivisionError("a bug in step")

        gipsi.register_object("Broken", Broken)
        scene = decay_scene()
        scene["objects"]["a"]["type"] = "Broken"
        result = gipsi.Simulation.from_dict(scene).run()
        self.assertEqual(result["outcome"], "diverged")
        self.assertIn("ZeroDivisionError: a bug in step", result["diagnostic"])

        class Refusing(Decay):
            def step(self, t, dt):
                return t < 0.05 - 1e-9  # False from t = 0.05 on: the step failed

        gipsi.register_object("Refusing", Refusing)
        scene["objects"]["a"]["type"] = "Refusing"
        sim = gipsi.Simulation.from_dict(scene)
        start = sim.save()
        result = sim.run()
        self.assertEqual(result["outcome"], "diverged")
        self.assertIn("step() returned False", result["diagnostic"])
        self.assertAlmostEqual(sim.time, 0.05, delta=1e-12)
        # a failed inside the macro step: going on would step the others twice. Refused,
        # until a saved state is restored.
        for call in (sim.step, sim.run):
            with self.assertRaisesRegex(RuntimeError, "the simulation cannot go on from t = 0.05 "
                                        "s: object 'a' failed inside the macro step"):
                call()
        self.assertEqual(len(sim.object("a").field("x")), 1)  # fields can still be read
        sim.restore(start)
        self.assertEqual(sim.run(until=0.03)["outcome"], "completed")

    def test_a_step_that_fails_at_full_size_is_retried_in_halves(self):
        class Picky(Decay):
            def step(self, t, dt):
                if dt > 0.006:  # only halved steps succeed
                    return False
                super().step(t, dt)

        gipsi.register_object("Picky", Picky)
        scene = decay_scene()
        scene["objects"]["a"]["type"] = "Picky"
        scene["schedule"]["on_failure"] = {"retry": {"max_halvings": 1}}
        sim = gipsi.Simulation.from_dict(scene)
        self.assertEqual(sim.run(until=0.1)["outcome"], "completed")
        # Halved steps of the closed form compose exactly: x = e^(-2 t), to rounding.
        self.assertAlmostEqual(sim.object("a").field("x")[0, 0], np.exp(-0.2), delta=1e-14)

    def test_a_read_of_the_wrong_size_through_a_connector_stops_the_run_saying_so(self):
        class Chatty(Decay):
            def read(self, name):
                return [self.x, self.x]

        gipsi.register_object("Chatty", Chatty)
        scene = decay_scene(connectors={"kick": {"type": "FieldCopy", "from": "a.x", "to": "b.u"}})
        scene["objects"]["a"]["type"] = "Chatty"
        del scene["probes"]  # a probe's read would fail first, as an output ("output_failed")
        result = gipsi.Simulation.from_dict(scene).run()
        self.assertEqual(result["outcome"], "stopped")
        self.assertIn("the macro step at t = 0 s could not be done: Chatty 'a': read('x') "
                      "returned 2 values, expected 1", result["diagnostic"])

    def test_bad_parameters_and_declarations_are_refused_at_the_objects_path(self):
        scene = decay_scene()
        scene["objects"]["a"]["rate"] = -1
        with self.assertRaises(gipsi.InputError) as raised:
            gipsi.Simulation.from_dict(scene)
        self.assertEqual(raised.exception.path, "objects.a")
        self.assertIn("rate must be positive", raised.exception.what)

        class NoFields:
            def __init__(self, name, params):
                pass

        gipsi.register_object("NoFields", NoFields)
        scene = decay_scene()
        scene["objects"]["a"]["type"] = "NoFields"
        with self.assertRaisesRegex(gipsi.InputError, "objects.a: NoFields: its 'fields'"):
            gipsi.Simulation.from_dict(scene)
        class BadComponents(Decay):
            fields = {"x": {"components": "three"}}

        gipsi.register_object("BadComponents", BadComponents)
        scene["objects"]["a"]["type"] = "BadComponents"
        with self.assertRaisesRegex(gipsi.InputError, "objects.a: BadComponents: "):
            gipsi.Simulation.from_dict(scene)
        with self.assertRaisesRegex(ValueError, "'MassSpring' is a built-in object type"):
            gipsi.register_object("MassSpring", Decay)


MMHG = 133.322387415  # Pa
ML = 1e-6  # m^3


def windkessel_scene(**extra):
    """A Windkessel: 100 mL/s into arteries (C 1.5 mL/mmHg, from 80 mmHg) draining through R_p
    (1 mmHg s/mL) into a 5 mmHg venous reservoir. P(t) = P_v + R Q + (P_0 - P_v - R Q) e^(-t/RC)
    while R is held."""
    scene = {
        "gipsi": 1, "units": "SI",
        "objects": {"wk": {
            "type": "Circulation", "dt": "1 ms", "log_events": False,
            "tolerance": {"relative": 1e-10, "absolute": "1e-9 mL"},
            "compartments": {
                "arteries": {"type": "compliance", "compliance": "1.5 mL/mmHg",
                             "pressure": "80 mmHg"},
                "veins": {"type": "reservoir", "pressure": "5 mmHg"}},
            "connections": {
                "inflow": {"type": "source", "to": "arteries", "flow": "100 mL/s"},
                "peripheral": {"type": "resistor", "from": "arteries", "to": "veins",
                               "resistance": "1 mmHg*s/mL"}}}},
        "schedule": {"end": 3.0, "dt": 0.01},
        "probes": {"p": {"object": "wk", "fields": ["arteries_pressure"], "every": 0.01}},
    }
    scene.update(extra)
    return scene


class Constrictor(gipsi.ConnectorBase):
    """Holds the resistance it writes at `factor` times the one it reads."""
    ports = {"resistance": {"access": "read_write", "units": "Pa*s/m3"}}
    parameters = ("factor",)

    def __init__(self, name, params):
        super().__init__(name, params)
        self.r0 = None

    def fire(self, t, values):
        if self.r0 is None:
            self.r0 = values["resistance"][0, 0]
        return {"resistance": [self.r0 * self.params["factor"]]}

    def get_state(self):
        return np.array([np.nan if self.r0 is None else self.r0]).tobytes()

    def set_state(self, state):
        r0 = np.frombuffer(state)[0]
        self.r0 = None if np.isnan(r0) else r0


class PressureControl(gipsi.ConnectorBase):
    """Integral control of a pressure through a resistance: every fire,
    R <- R (target / p)^gain. At a steady state p = target."""
    ports = {"pressure": {"access": "read", "units": "Pa", "components": 1},
             "resistance": {"access": "read_write", "units": "Pa*s/m3"}}
    parameters = ("target", "gain")

    def fire(self, t, values):
        p, r = values["pressure"][0, 0], values["resistance"][0, 0]
        return {"resistance": np.array([r * (self.params["target"] / p) ** self.params["gain"]])}


def controlled_windkessel(connector):
    return windkessel_scene(connectors={"ctl": connector})


class PythonConnectors(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        gipsi.register_connector("Constrictor", Constrictor, "R <- factor R0")
        gipsi.register_connector("PressureControl", PressureControl, "integral control")

    def test_a_python_connector_changes_the_result_as_the_closed_form_predicts(self):
        sim = gipsi.Simulation.from_dict(controlled_windkessel(
            {"type": "Constrictor", "resistance": "wk.peripheral_resistance", "factor": 2.0}))
        r0 = sim.object("wk").field("peripheral_resistance")[0, 0]
        self.assertAlmostEqual(r0, MMHG / ML, delta=1e-9 * r0)
        self.assertEqual(sim.run()["outcome"], "completed")
        self.assertEqual(sim.object("wk").field("peripheral_resistance")[0, 0], 2 * r0)
        # The connector fires before the circulation steps, so R = 2 R0 from t = 0. The
        # integrator's tolerance (1e-10) bounds the error far below 1e-6 of the pressure.
        t, p = sim.probes["p"]["time"], sim.probes["p"]["arteries_pressure"]
        q, c, pv, p0, r = 100 * ML, 1.5 * ML / MMHG, 5 * MMHG, 80 * MMHG, 2 * r0
        exact = pv + r * q + (p0 - pv - r * q) * np.exp(-t / (r * c))
        np.testing.assert_allclose(p, exact, rtol=1e-6)

    def test_a_python_feedback_holds_the_pressure_at_its_target(self):
        target = 110 * MMHG
        scene = controlled_windkessel({"type": "PressureControl", "target": target, "gain": 0.05,
                                       "pressure": "wk.arteries_pressure",
                                       "resistance": "wk.peripheral_resistance"})
        scene["schedule"]["end"] = 40.0
        sim = gipsi.Simulation.from_dict(scene)
        self.assertEqual(sim.run()["outcome"], "completed")
        # The only steady state: p = target with R Q = target - P_v.
        wk = sim.object("wk")
        self.assertAlmostEqual(wk.field("arteries_pressure")[0, 0], target, delta=1e-3 * target)
        r_star = (target - 5 * MMHG) / (100 * ML)
        self.assertAlmostEqual(wk.field("peripheral_resistance")[0, 0], r_star,
                               delta=1e-3 * r_star)

    def test_a_python_connector_resumes_bitwise_from_its_state(self):
        sim = gipsi.Simulation.from_dict(controlled_windkessel(
            {"type": "Constrictor", "resistance": "wk.peripheral_resistance", "factor": 1.5}))
        sim.run(until=0.5)
        state = sim.save()
        sim.run(until=1.0)
        p = sim.object("wk").field("arteries_pressure")
        fresh = gipsi.Simulation.from_dict(controlled_windkessel(
            {"type": "Constrictor", "resistance": "wk.peripheral_resistance", "factor": 1.5}))
        fresh.restore(state)
        fresh.run(until=1.0)
        np.testing.assert_array_equal(fresh.object("wk").field("arteries_pressure"), p)

    def test_ports_are_checked_when_the_scene_loads(self):
        def refused(connector):
            with self.assertRaises(gipsi.InputError) as raised:
                gipsi.Simulation.from_dict(controlled_windkessel(connector))
            return raised.exception

        good = {"type": "PressureControl", "target": 1e4, "gain": 0.1,
                "pressure": "wk.arteries_pressure", "resistance": "wk.peripheral_resistance"}
        e = refused(dict(good, pressure="wk.arteries_volume"))  # m3, not Pa
        self.assertEqual(e.path, "connectors.ctl")
        self.assertIn("reads field 'arteries_volume' of 'wk' (Circulation) at its 'pressure' key",
                      e.what)
        e = refused(dict(good, resistance="wk.arteries_pressure"))  # read-only, and Pa
        self.assertIn("arteries_pressure", e.what)
        e = refused(dict(good, resistance="wk.peripheral_resistanse"))
        self.assertEqual(e.path, "connectors.ctl.resistance")
        self.assertIn("peripheral_resistance", e.what)  # the closest name is suggested
        e = refused({k: v for k, v in good.items() if k != "pressure"})
        self.assertIn("PressureControl needs \"pressure\": \"object.field\"", e.what)
        e = refused(dict(good, gian=0.1))
        self.assertEqual(e.path, "connectors.ctl.gian")
        self.assertIn("PressureControl has no parameter 'gian'", e.what)
        with self.assertRaisesRegex(ValueError, "'FieldCopy' is a built-in connector type"):
            gipsi.register_connector("FieldCopy", Constrictor)

    def test_a_failing_fire_stops_the_run_with_its_reason_and_writes_nothing(self):
        class Wrong(gipsi.ConnectorBase):
            ports = {"resistance": {"access": "read_write"},
                     "pressure": {"access": "read"}}

            def fire(self, t, values):
                if t >= 0.1 - 1e-9:
                    return {"resistance": [1e8], "pressure": [1.0]}
                return None

        gipsi.register_connector("Wrong", Wrong)
        sim = gipsi.Simulation.from_dict(controlled_windkessel(
            {"type": "Wrong", "pressure": "wk.arteries_pressure",
             "resistance": "wk.peripheral_resistance"}))
        r0 = sim.object("wk").field("peripheral_resistance")[0, 0]
        result = sim.run()
        self.assertEqual(result["outcome"], "diverged")
        self.assertIn("connector 'ctl' (fire() returned 'pressure', which is not a port it "
                      "writes) failed at t = 0.1 s", result["diagnostic"])
        self.assertEqual(sim.object("wk").field("peripheral_resistance")[0, 0], r0)
        self.assertAlmostEqual(sim.time, 0.1, delta=1e-12)
        self.assertEqual(len(sim.probes["p"]["time"]), 11)  # t = 0 .. 0.1 kept

        class Raising(Wrong):
            def fire(self, t, values):
                return {"resistance": [float(values["pressure"][0, 0]) / 0.0]}

        gipsi.register_connector("Raising", Raising)
        scene = controlled_windkessel({"type": "Raising", "pressure": "wk.arteries_pressure",
                                       "resistance": "wk.peripheral_resistance"})
        result = gipsi.Simulation.from_dict(scene).run()
        self.assertIn("fire() raised ZeroDivisionError", result["diagnostic"])

        class NotFinite(Wrong):
            def fire(self, t, values):
                return {"resistance": np.array([np.nan])}

        gipsi.register_connector("NotFinite", NotFinite)
        scene["connectors"]["ctl"]["type"] = "NotFinite"
        result = gipsi.Simulation.from_dict(scene).run()
        self.assertIn("fire() returned a non-finite value for 'resistance' at 0: nan",
                      result["diagnostic"])


class Drifter(gipsi.ObjectBase):
    """Warms at 1 K/s at every node and drifts at 0.1 m/s along x, on its "domain" mesh."""
    fields = {"temperature": {"location": "node", "units": "K", "access": "read_write"},
              "volume": {"location": "element", "units": "m3"}}

    def set_domain(self, mesh):
        self.rest, self.tets = mesh["nodes"], mesh["tets"]
        self.temperature = np.full((len(self.rest), 1), 300.0)
        self.t = 0.0

    def step(self, t, dt):
        self.t = t + dt
        self.temperature += dt

    def positions(self):
        return self.rest + [0.1 * self.t, 0.0, 0.0]

    def read(self, name):
        if name == "temperature":
            return self.temperature
        x = self.rest[self.tets]
        return np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / 6

    def write(self, name, values):
        assert values.shape == self.temperature.shape, values.shape
        self.temperature = values.copy()

    def get_state(self):
        return np.append(self.temperature.ravel(), self.t).tobytes()

    def set_state(self, state):
        values = np.frombuffer(state)
        self.temperature, self.t = values[:-1].reshape(-1, 1).copy(), values[-1]


class PythonObjectsOnAMesh(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        gipsi.register_object("Drifter", Drifter, "warms and drifts")

    def scene(self, with_domain=True):
        obj = {"type": "Drifter", "dt": 0.01}
        if with_domain:
            obj["domain"] = "box"
        return {"gipsi": 1, "units": "SI",
                "meshes": {"box": {"generate": "box", "min": [0, 0, 0], "max": [0.1, 0.1, 0.1],
                                   "cells": [2, 2, 2]}},
                "objects": {"d": obj},
                "schedule": {"end": 0.5, "dt": 0.01},
                "probes": {"centre": {"object": "d", "point": [0.05, 0.05, 0.05],
                                      "fields": ["temperature"], "every": 0.1}}}

    def test_node_and_element_fields_are_probed_and_its_nodes_move(self):
        sim = gipsi.Simulation.from_dict(self.scene())
        d = sim.object("d")
        self.assertEqual(d.fields["temperature"]["location"], "node")
        self.assertEqual(d.fields["temperature"]["count"], 27)
        self.assertEqual(d.fields["volume"]["count"], 48)
        self.assertEqual(sim.run()["outcome"], "completed")
        probe = sim.probes["centre"]
        # A uniform field interpolates exactly: 300 K + 1 K/s t.
        np.testing.assert_allclose(probe["temperature"], 300 + probe["time"], rtol=1e-12)
        self.assertAlmostEqual(d.field("volume").sum(), 0.001, delta=1e-15)
        np.testing.assert_allclose(d.positions, d.rest_positions + [0.05, 0, 0], atol=1e-15)
        d.set_field("temperature", np.full((27, 1), 250.0))  # written as (count, components)
        sim.step()
        self.assertAlmostEqual(d.field("temperature")[13, 0], 250.01, delta=1e-12)
        self.assertIs(type(d.impl), Drifter)
        # A restore brings its nodes back with its state.
        fresh = gipsi.Simulation.from_dict(self.scene())
        fresh.run(until=0.2)
        state = fresh.save()
        fresh.run(until=0.4)
        fresh.restore(state)
        np.testing.assert_allclose(fresh.object("d").positions,
                                   fresh.object("d").rest_positions + [0.02, 0, 0], atol=1e-15)

    def test_a_node_field_without_a_domain_is_refused_at_the_objects_path(self):
        with self.assertRaises(gipsi.InputError) as raised:
            gipsi.Simulation.from_dict(self.scene(with_domain=False))
        self.assertEqual(raised.exception.path, "objects.d")
        self.assertIn("field 'temperature' is a node field, but the object has no \"domain\" "
                      "mesh", raised.exception.what)

class DocsSnippets(unittest.TestCase):
    def test_every_python_snippet_of_docs_python_md_runs(self):
        with open(os.path.join(SOURCE_DIR, "docs", "python.md"), encoding="utf-8") as f:
            text = f.read()
        snippets = re.findall(r"```python\n(.*?)```", text, re.S)
        self.assertGreaterEqual(len(snippets), 5)
        cwd = os.getcwd()
        with tempfile.TemporaryDirectory() as tmp:
            # The snippets name files relative to the checkout; they write beside them.
            os.symlink(os.path.join(SOURCE_DIR, "scenes"), os.path.join(tmp, "scenes"))
            os.chdir(tmp)
            try:
                for snippet in snippets:
                    with self.subTest(snippet=snippet.splitlines()[0]):
                        with contextlib.redirect_stdout(io.StringIO()):
                            exec(compile(snippet, "docs/python.md", "exec"), {})
            finally:
                os.chdir(cwd)


if __name__ == "__main__":
    unittest.main()
