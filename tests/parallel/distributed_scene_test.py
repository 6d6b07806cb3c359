#!/usr/bin/env python3
"""`mpiexec -np N gipsi run SCENE` against the serial run of the same scene file.

Runs the N-version benchmark slab (scenes/slab_ep_0.5mm.json, its first 30 ms) serially and on
2 and 4 ranks (4 oversubscribed: more ranks than cores), and checks that
  - the distributed runs write the serial run's files, except that each VTU frame of the split
    object is a `.pvtu` joining one `.vtu` piece per rank; the pieces of a frame hold every tet
    once and every node (shared ones in several pieces) with the serial frame's values;
  - every probe (a point probe of V and activation time, the activated fraction, the line probe
    of activation times along the diagonal) has the serial run's rows and times, and values
    within what the diffusion solver's tolerance allows: both solve with CG + Jacobi to a
    relative residual of 1e-8, which leaves at most 1e-3 ms in activation times against an
    exact solve on this slab (tests/parallel/distributed_monodomain_test.cc), so 2e-3 ms, and
    0.5 mV for V (an upstroke of at most ~250 mV/ms shifted by 2e-3 ms); measured: 1e-13;
  - the summary names the ranks, and that the slab is made in blocks (no rank holds it whole);
  - region probes (a box's mean, a face group's largest activation time, a sum over node ids)
    and a point probe where the parts meet give the serial values within those bounds;
  - the slab given as a Gmsh 4.1 file and as a legacy VTK file, which each rank reads in blocks,
    gives the serial run's probes within those bounds on 2 and 4 ranks;
  - the ventricle's activation (scenes/lv_activation.json, its first 50 ms), its transmural
    fibre rule solved over the ranks and so made in blocks, gives the serial probes within those
    bounds on 2 and 4 ranks; so does the benchmark ventricle (scenes/lv_inflation.json) with a
    cavity on its endocardium, made in blocks (its enclosed volume and apex within 1e-6 of
    their scale);
  - the slab's tissue coupled by a barycentric FieldCopy to a muscle on another, coarser mesh
    that sticks out of it, both made in blocks (cut differently), gives the serial muscle's
    probes within the bound on V carried over (6e-3 of their scale) on 2 and 4 ranks;
  - the soft cantilever (scenes/cantilever.json), its FemSolid split over 2 and 4 ranks and
    made in blocks (no rank holds its mesh), gives the serial tip motion, clamp reaction and
    kinetic energy within 1e-6 of their scale (Newton to 1e-8, CG to 1e-6); measured 1e-8; so
    does the cantilever under a total force, a pressure and a traction on face groups and boxes
    and a displacement on a node id, with a reaction probe over a box (a condition that selects
    nothing is refused once, exit 1), and so with events that apply and remove conditions, also
    checkpointed after them on 2 ranks and resumed on 4; and the cantilever integrated explicitly
    (scenes/cantilever_explicit.json, RK4) split over 2 ranks gives the serial probes within
    1e-9 of their scale (the same arithmetic, summed in another order); and a slab glued on
    the cantilever's top by a BoundaryCoupling, both made in blocks, gives the serial probes
    within 1e-6 of their scale on 2 and 4 ranks; the liver read from its Gmsh 1.0 file in
    blocks gives them on 2 ranks, and so do its reaction probes over a region when a display
    mesh keeps its whole mesh on every rank;
  - the heart (scenes/heart.json, its first beat: 0.8 s) on 2 ranks, its bioelectricity and its
    muscle made in blocks and coupled part to part (the cavity's volume over the whole
    endocardium, the blood pressure Newton's bordered unknown on every rank) and its
    circulation whole on every rank, gives the serial PV loop and beat
    summary within 1e-4 relative (activation times within 2e-3 ms shift the active tension by
    that; at the steepest pressure rise, ~200 kPa/s, that is 0.4 Pa of ~10 kPa); measured 6e-11;
    so does the heart with a mass-spring muscle (its first 0.15 s), whose bioelectricity is made
    in blocks while the muscle runs whole, coupled through the bioelectricity's parts;
  - an earlier run's pieces are refused, or deleted with --overwrite; the output limit
    (--max-output) estimates the split slab's frames as the serial run does;
  - a divergence on one rank's part (a 5 V clamp at the far corner from 5 ms) stops every rank
    at the serial run's step, exit 3, with the probe rows recorded until then;
  - checkpoints: written per rank, and a run resumed from them on 2 ranks writes the
    uninterrupted run's files byte for byte (the slab, the cantilever and the heart, their solids
    split); resumed on another rank count they give the uninterrupted run's probes within the
    bounds above (the slab 2 → 4, 2 → 3, 4 → 2, the last frame's extra pieces deleted; the
    cantilever 2 → 4; the heart 2 → 3), and a serial run's checkpoint resumed on 2 ranks gives
    them too (the slab, its series listing the serial frames before the checkpoint; the heart),
    as does a 2-rank checkpoint resumed on one process (the slab, the cantilever);
    a set of files from two checkpoints is refused with the way out;
  - the object's "parallel" block chooses the distributed diffusion solver (BoomerAMG: one CG
    iteration per step, fewer in all than Jacobi's one or two);
  - a bad scene exits with the serial code, its error printed once (not once per rank).

Usage: distributed_scene_test.py GIPSI MPIEXEC SOURCE_DIR
"""
import base64
import csv
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

GIPSI, MPIEXEC, SOURCE = sys.argv[1], sys.argv[2], sys.argv[3]
SCENE = os.path.join(SOURCE, "scenes", "slab_ep_0.5mm.json")
BOUNDS = {"V": 0.5, "activation_time": 2e-3, "activated_fraction": 1e-9}
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(ranks, out, *extra, scene=SCENE, until="0.03"):
    command = [GIPSI, "run", scene, "--until", until, "-o", out, "--overwrite", *extra]
    if ranks > 1:
        command = [MPIEXEC, "-np", str(ranks)] + (["--oversubscribe"] if ranks > 2 else []) + command
    result = subprocess.run(command, capture_output=True, text=True, timeout=240)
    return result.returncode, result.stdout + result.stderr


def files(folder):
    return sorted(os.path.relpath(os.path.join(d, f), folder)
                  for d, _, names in os.walk(folder) for f in names)


def expected_files(serial_files, ranks, split="tissue"):
    """The serial file list with each frame of the split object as a .pvtu and its pieces."""
    out = []
    for f in serial_files:
        m = re.fullmatch(split + r"/" + split + r"_\d{6}\.vtu", f) and re.fullmatch(r"(.*)\.vtu", f)
        if m:
            out.append(m.group(1) + ".pvtu")
            out += [f"{m.group(1)}_p{k}.vtu" for k in range(ranks)]
        else:
            out.append(f)
    return sorted(out)


def vtu_arrays(path):
    """Point count, cell count and the Float64 arrays of a .vtu GiPSi wrote (inline base64: a
    12-character UInt64 byte count, then the data)."""
    piece = ET.parse(path).getroot().find("UnstructuredGrid/Piece")
    arrays = {}
    for array in piece.iter("DataArray"):
        if array.get("type") != "Float64":
            continue
        data = base64.b64decode(array.text.strip()[12:])
        values = struct.unpack(f"<{len(data) // 8}d", data)
        arrays[array.get("Name")] = values
    return int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells")), arrays


def compare_frame(serial_vtu, pvtu, ranks, label):
    n, cells, reference = vtu_arrays(serial_vtu)
    points = reference["Points"]
    index = {tuple(round(c, 12) for c in points[3 * i:3 * i + 3]): i for i in range(n)}
    root = ET.parse(pvtu).getroot()
    sources = [p.get("Source") for p in root.iter("Piece")]
    check(len(sources) == ranks, f"{label}: {len(sources)} pieces in {pvtu}")
    names = {a.get("Name") for a in root.find("PUnstructuredGrid/PPointData")}
    check({"V", "activation_time"} <= names, f"{label}: point arrays {names}")
    seen, piece_cells, worst = set(), 0, 0.0
    for source in sources:
        m, c, arrays = vtu_arrays(os.path.join(os.path.dirname(pvtu), source))
        piece_cells += c
        for i in range(m):
            key = tuple(round(x, 12) for x in arrays["Points"][3 * i:3 * i + 3])
            j = index.get(key)
            if j is None:
                check(False, f"{label}: {source} point {i} at {key} is not a node of the mesh")
                break
            seen.add(j)
            for name in ("V", "activation_time"):
                diff = abs(arrays[name][i] - reference[name][j])
                worst = max(worst, diff)
                if diff > BOUNDS[name]:
                    check(False, f"{label}: {source} {name} at node {j}: {arrays[name][i]} vs "
                          f"serial {reference[name][j]}")
    check(piece_cells == cells, f"{label}: the pieces hold {piece_cells} cells, serial {cells}")
    check(len(seen) == n, f"{label}: the pieces hold {len(seen)} of the {n} nodes")
    print(f"{label}: {len(sources)} pieces, {piece_cells} cells, largest difference {worst:.3g}")


def rows(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


def compare_probes(label, serial_dir, split_dir, names, scale=None):
    """Each probe's rows in `split_dir` have the serial run's header and times, and values
    within BOUNDS of its column (times `scale[name]`, default 1)."""
    for name in names:
        a = rows(os.path.join(serial_dir, "probes", name + ".csv"))
        b = rows(os.path.join(split_dir, "probes", name + ".csv"))
        check(a[0] == b[0] and len(a) == len(b) and len(a) > 2,
              f"{label}, {name}: {len(b)} rows with {b[0]}, serial {len(a)} with {a[0]}")
        worst = 0.0
        for ra, rb in zip(a[1:], b[1:]):
            for column, x, y in zip(a[0], ra, rb):
                bound = BOUNDS.get(column, 0.0) * (scale or {}).get(name, 1)
                worst = max(worst, abs(float(x) - float(y)))
                check(abs(float(x) - float(y)) <= bound, f"{label}, {name}.{column}: {y} vs serial {x}")
        print(f"{label}, {name}: largest difference {worst:.3g}")


def run_variant(label, scene, *extra):
    """Writes `scene` (a dict) into the work folder and runs it serially and on 2 and 4 ranks
    (to 30 ms), the slab made in blocks and its mesh never read whole; returns each run's output
    folder by rank count."""
    path = os.path.join(work, label + ".json")
    with open(path, "w") as f:
        json.dump(scene, f)
    outs = {}
    for ranks in (1, 2, 4):
        outs[ranks] = os.path.join(work, f"{label}{ranks}")
        code, text = run(ranks, outs[ranks], *extra, scene=path)
        check(code == 0, f"{label} on {ranks} ranks: exit {code}: {text}")
        if ranks > 1:
            check("(split over them: tissue (Monodomain, in blocks))" in text or "-q" in extra,
                  f"{label} on {ranks} ranks: the slab is not made in blocks:\n{text}")
            check("reads this file whole" not in text,
                  f"{label} on {ranks} ranks: the slab's file is read whole:\n{text}")
    return outs


def compare_heart(label, reference, out, names):
    """The heart's probes `names` in `out` have `reference`'s rows, values within 1e-4 relative
    (activation times within 2e-3 ms shift the active tension by that; at the steepest pressure
    rise, ~200 kPa/s, that is 0.4 Pa of ~10 kPa)."""
    for name in names:
        a = rows(os.path.join(reference, "probes", name + ".csv"))
        b = rows(os.path.join(out, "probes", name + ".csv"))
        check(a[0] == b[0] and len(a) == len(b) and len(a) > 1,
              f"{label}, {name}: {len(b)} rows with {b[0]}, reference {len(a)} with {a[0]}")
        worst = 0.0
        for ra, rb in zip(a[1:], b[1:]):
            for column, x, y in zip(a[0], ra, rb):
                diff = abs(float(x) - float(y))
                scale = max(abs(float(x)), 1e-300)
                worst = max(worst, diff / scale if float(x) != 0 else diff)
                check(diff <= 1e-4 * abs(float(x)) or diff == 0,
                      f"{label}, {name}.{column}: {y} vs {x}")
        print(f"{label}, {name}: largest relative difference {worst:.3g}")


def compare_cantilever(label, reference, out, least_rows):
    """The cantilever's probes in `out` have `reference`'s rows (at least `least_rows`), the
    tip motion and clamp reaction within 1e-6 of their scale (7 cm, 0.1 N), the kinetic energy
    within 1e-6 relative and Newton's iterations within one."""
    for name, scale in (("tip", 0.07), ("clamp", 0.1), ("newton", None)):
        a = rows(os.path.join(reference, "probes", name + ".csv"))
        b = rows(os.path.join(out, "probes", name + ".csv"))
        check(a[0] == b[0] and len(a) == len(b) and len(a) > least_rows,
              f"{label}, {name}: {len(b)} rows, reference {len(a)}")
        worst = 0.0
        for ra, rb in zip(a[1:], b[1:]):
            for column, x, y in zip(a[0], ra, rb):
                x, y = float(x), float(y)
                if column == "newton_iterations":  # one more or fewer near the tolerance
                    check(abs(x - y) <= 1, f"{label}, {column}: {y} vs {x}")
                    continue
                bound = 1e-6 * (scale if scale else max(abs(x), 1e-12))
                worst = max(worst, abs(x - y) / (scale if scale else max(abs(x), 1e-300)))
                check(abs(x - y) <= bound, f"{label}, {name}.{column}: {y} vs {x}")
        print(f"{label}, {name}: largest relative difference {worst:.3g}")


def run_in_blocks(label, scene, rank_counts, until, split="beam (FemSolid, in blocks)"):
    """Runs `scene` on each of `rank_counts` (to `until` s); each run must succeed, and a split
    one name `split` among its split objects (by default the cantilever's beam, made in
    blocks). Returns each run's folder by rank count."""
    outs = {}
    for ranks in rank_counts:
        outs[ranks] = os.path.join(work, f"{label}{ranks}")
        code, text = run(ranks, outs[ranks], scene=scene, until=until)
        check(code == 0, f"{label} on {ranks} ranks: exit {code}: {text}")
        if ranks > 1:
            check(f"(split over them: {split})" in text,
                  f"{label} on {ranks} ranks: not split as '{split}':\n{text}")
    return outs


def compare_scaled(label, reference, out, scales, factor, least_rows):
    """Each probe (name, scale) of `scales` in `out` has `reference`'s header and more than
    `least_rows` rows, every value within `factor` times its scale of the reference's."""
    for name, scale in scales:
        a = rows(os.path.join(reference, "probes", name + ".csv"))
        b = rows(os.path.join(out, "probes", name + ".csv"))
        check(a[0] == b[0] and len(a) == len(b) and len(a) > least_rows,
              f"{label}, {name}: {len(b)} rows, reference {len(a)}")
        worst = max(abs(float(x) - float(y)) for ra, rb in zip(a[1:], b[1:])
                    for x, y in zip(ra[1:], rb[1:]))
        check(worst <= factor * scale, f"{label}, {name}: differs by {worst:.3g}")
        print(f"{label}, {name}: largest difference {worst:.3g}")


def resumed_across(label, folder, ranks, logged, before):
    """The slab checkpointed at 20 ms in `folder` by a run of the other kind, resumed on `ranks`
    to 30 ms: it logs `logged`, writes the serial run's probes within BOUNDS, and its series
    lists the earlier run's frames (`before`: ".vtu" or ".pvtu") up to the checkpoint and its
    own after, every one on disk."""
    code, text = run(ranks, folder, "--resume", os.path.join(folder, "checkpoint.gck"))
    check(code == 0 and logged in text, f"{label}: exit {code}: {text}")
    compare_probes(label, os.path.join(work, "serial"), folder,
                   ("far_corner", "activated", "diagonal"))
    with open(os.path.join(folder, "tissue.pvd")) as pvd:
        listed = re.findall(r'timestep="([^"]+)" group="" part="0" file="([^"]+)"', pvd.read())
    check(listed and all(f.endswith(before) == (float(t) <= 0.02 + 1e-12) for t, f in listed)
          and all(os.path.exists(os.path.join(folder, f)) for _, f in listed),
          f"{label}: tissue.pvd lists {listed}")


def resumes_bitwise(label, scene, every, stop, end):
    """On 2 ranks, a run checkpointed every `every` s up to `stop` and resumed to `end` writes the
    uninterrupted run's files byte for byte."""
    full = os.path.join(work, label + "_full")
    code, text = run(2, full, "-q", scene=scene, until=end)
    check(code == 0, f"{label} to {end} s on 2 ranks: exit {code}: {text}")
    resumed = os.path.join(work, label + "_resumed")
    code, text = run(2, resumed, "-q", "--checkpoint-every", every, scene=scene, until=stop)
    check(code == 0, f"{label} to {stop} s with checkpoints: exit {code}: {text}")
    code, text = run(2, resumed, "-q", "--resume", os.path.join(resumed, "checkpoint.gck"),
                     scene=scene, until=end)
    check(code == 0, f"{label} resumed on 2 ranks: exit {code}: {text}")
    for f in files(full):
        with open(os.path.join(full, f), "rb") as a, open(os.path.join(resumed, f), "rb") as b:
            check(a.read() == b.read(), f"{label} resumed on 2 ranks: {f} differs")


with tempfile.TemporaryDirectory() as work:
    serial = os.path.join(work, "serial")
    code, text = run(1, serial)
    check(code == 0, f"serial run exited {code}: {text}")
    for ranks in (2, 4):
        out = os.path.join(work, f"ranks{ranks}")
        code, text = run(ranks, out)
        check(code == 0, f"{ranks} ranks: exit {code}: {text}")
        check(f"MPI ranks:        {ranks} (split over them: tissue (Monodomain, in blocks))" in text,
              f"{ranks} ranks: the summary does not name the ranks:\n{text}")
        check(text.count("simulated time:") == 1, f"{ranks} ranks: more than one rank printed")
        expected = expected_files(files(serial), ranks)
        check(files(out) == expected,
              f"{ranks} ranks: files differ: {set(files(out)) ^ set(expected)}")
        with open(os.path.join(out, "tissue.pvd")) as pvd:
            listed = re.findall(r'file="([^"]+)"', pvd.read())
        check(listed and all(f.endswith(".pvtu") for f in listed),
              f"{ranks} ranks: tissue.pvd lists {listed[:3]}")
        last = sorted(f for f in files(serial) if f.endswith(".vtu"))[-1]
        compare_frame(os.path.join(serial, last),
                      os.path.join(out, last[:-len(".vtu")] + ".pvtu"), ranks,
                      f"{ranks} ranks, frame {last}")
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
    # The output limit counts the split slab's whole frames, as serially: the same estimate,
    # the same refusal, on 2 ranks.
    refusals = {}
    for ranks in (1, 2):
        code, text = run(ranks, os.path.join(work, f"limited{ranks}"), "--max-output", "100000")
        check(code != 0 and "over the limit of" in text,
              f"--max-output on {ranks} ranks: exit {code}: {text}")
        refusals[ranks] = re.findall(r"would write about [^,]*", text)[:1]
    check(refusals[1] and refusals[1] == refusals[2],
          f"--max-output: serially {refusals[1]}, on 2 ranks {refusals[2]}")
    # An earlier distributed run's series (4 pieces per frame) is refused, or with --overwrite
    # cleared (pieces and .pvtu files included) before a run on 2 ranks writes its own.
    again = os.path.join(work, "ranks4")
    result = subprocess.run([MPIEXEC, "-np", "2", GIPSI, "run", SCENE, "--until", "0.01", "-o",
                             again, "-q"], capture_output=True, text=True, timeout=120)
    check(result.returncode == 1 and "holds VTU series of an earlier run" in result.stderr,
          f"no --overwrite over an earlier series: exit {result.returncode}: {result.stderr}")
    code, text = run(2, again)
    check(code == 0 and files(again) == expected_files(files(serial), 2),
          f"--overwrite over 4 ranks' series: exit {code}, stale files "
          f"{set(files(again)) - set(expected_files(files(serial), 2))}")
    heart = os.path.join(SOURCE, "scenes", "heart.json")
    heart_runs = {}
    for ranks in (1, 2):
        out = os.path.join(work, f"heart{ranks}")
        code, text = run(ranks, out, scene=heart, until="0.8")
        check(code == 0, f"heart on {ranks} ranks: exit {code}: {text}")
        heart_runs[ranks] = out
    # Nothing outside the heart reads its parts, and its own connectors couple the parts
    # (excitation-contraction) or use only the wall's cavity and global fields (the cavity
    # coupling): its bioelectricity and muscle are made in blocks, cut alike from one mesh.
    check("(split over them: bioelectricity (Monodomain, in blocks), muscle (FemSolid, in blocks))"
          in text, f"the heart on 2 ranks is not made in blocks:\n{text}")
    compare_heart("heart on 2 ranks", heart_runs[1], heart_runs[2], ("pv", "summary"))
    # The heart with a mass-spring muscle (scenes/heart_mass_spring.json, its first 0.15 s): the
    # muscle runs whole on every rank, and the excitation-contraction asks the bioelectricity's
    # parts for V at its nodes, so the bioelectricity is made in blocks all the same.
    springs = os.path.join(SOURCE, "scenes", "heart_mass_spring.json")
    spring_runs = run_in_blocks("heart_mass_spring", springs, (1, 2), "0.15",
                                "bioelectricity (Monodomain, in blocks)")
    compare_heart("mass-spring heart on 2 ranks", spring_runs[1], spring_runs[2], ("pv",))
    # The ventricle's activation (scenes/lv_activation.json, its first 50 ms): its transmural
    # fibre rule's Laplace problem is solved over the ranks (CG + Jacobi to 1e-12: fibres
    # within 1e-9 of the serial direct solve's, tests/parallel/distributed_fibres_test.cc), so
    # nothing needs its whole mesh and it is made in blocks; its probes give the serial run's
    # within the bounds above.
    ventricle = os.path.join(SOURCE, "scenes", "lv_activation.json")
    ventricle_runs = run_in_blocks("lv_activation", ventricle, (1, 2, 4), "0.05",
                                   "ep (Monodomain, in blocks)")
    for ranks in (2, 4):
        compare_probes(f"lv_activation on {ranks} ranks", ventricle_runs[1], ventricle_runs[ranks],
                       ("activated", "base"))
    # Two meshes: the slab's tissue copies V barycentrically (1 Pa/mV) onto the active tension
    # of a muscle on a coarser box that sticks out of the slab by 1.5 mm in x and 0.5 mm in y
    # (its items there take the nearest point of the slab), clamped at its x-min face and solved
    # statically every 1 ms. Both are made in blocks, each cut from its own mesh: the copy asks
    # the tissue's parts for V at the muscle's nodes, each rank at its own. The muscle's
    # probes give the serial run's within what the tissue's bound on V allows (0.5 mV of 85:
    # 6e-3 of their scale, the response being linear in the tension at this strain).
    with open(SCENE) as f:
        scene = json.load(f)
    scene["meshes"]["coarse"] = {"generate": "box", "min": [0.001, -0.0005, 0],
                                 "max": [0.0215, 0.0075, 0.003], "cells": [8, 3, 2]}
    scene["objects"]["muscle"] = {
        "type": "FemSolid", "domain": "coarse", "dt": 0.001, "integrator": "Static",
        "material": {"law": "Corotational", "youngs_modulus": 1e5, "poisson_ratio": 0.45},
        "gravity": [0, 0, 0], "fibres": {"direction": [1, 0, 0]},
        "boundary_conditions": [{"name": "clamp", "region": {"group": "xmin"}, "fix": True}]}
    scene["connectors"] = {"excite": {"type": "FieldCopy", "from": "tissue.V",
                                      "to": "muscle.nodal_active_tension",
                                      "mapping": "barycentric", "scale": "1 Pa/mV"}}
    scene["schedule"]["dt"] = 0.001
    scene["probes"] = {
        "tension": {"object": "muscle", "region": {"group": "xmax"},
                    "fields": ["nodal_active_tension"], "reduce": "mean", "every": 0.001},
        "tip": {"object": "muscle", "region": {"group": "xmax"}, "fields": ["displacement"],
                "reduce": "mean", "every": 0.001},
        "far_corner": scene["probes"]["far_corner"]}
    scene["outputs"] = {"directory": "out/two_meshes"}
    two_meshes = os.path.join(work, "two_meshes.json")
    with open(two_meshes, "w") as f:
        json.dump(scene, f)
    two_runs = run_in_blocks("two_meshes", two_meshes, (1, 2, 4), "0.03",
                             "tissue (Monodomain, in blocks), muscle (FemSolid, in blocks)")
    tip = rows(os.path.join(two_runs[1], "probes", "tip.csv"))
    tip_scale = max(abs(float(x)) for row in tip[1:] for x in row[1:])
    check(tip_scale > 1e-7, f"two meshes: the muscle does not move ({tip_scale} m)")
    for ranks in (2, 4):
        compare_scaled(f"two meshes on {ranks} ranks", two_runs[1], two_runs[ranks],
                       (("tension", 85.0), ("tip", tip_scale)), 6e-3, 25)
        compare_probes(f"two meshes on {ranks} ranks", two_runs[1], two_runs[ranks],
                       ("far_corner",))
    # The benchmark ventricle (scenes/lv_inflation.json) with a cavity on its endocardium,
    # inflated to 2 kPa in two increments: the cavity's faces are selected on the parts and
    # gathered, so the wall is made in blocks too; its enclosed volume and the apex give the
    # serial run's within 1e-6 of their scale (direct solves, Newton to 1e-8; measured 2e-15
    # relative for the volume).
    with open(os.path.join(SOURCE, "scenes", "lv_inflation.json")) as f:
        scene = json.load(f)
    wall = scene["objects"]["lv"]
    wall["cavities"] = {"lumen": {"group": "endo"}}
    wall["load_steps"] = 2
    wall["boundary_conditions"][1]["pressure"] = 2000
    scene["probes"]["cavity"] = {"object": "lv", "fields": ["lumen_volume"], "every": 1}
    scene["outputs"].pop("vtu")
    cavity_scene = os.path.join(work, "lv_cavity.json")
    with open(cavity_scene, "w") as f:
        json.dump(scene, f)
    cavity_runs = run_in_blocks("lv_cavity", cavity_scene, (1, 2, 4), "1",
                                "lv (FemSolid, in blocks)")
    for ranks in (2, 4):
        compare_scaled(f"the ventricle's cavity on {ranks} ranks", cavity_runs[1],
                       cavity_runs[ranks], (("cavity", 2.5e-6), ("apex", 1e-4)), 1e-6, 1)
    # The soft cantilever (scenes/cantilever.json, 1 s: the sag and two swings), its FemSolid
    # split over 2 and 4 ranks (GAMG), against the serial run (block Gauss-Seidel CG): both
    # solve each step's Newton equations to 1e-8 of the load scale with CG to 1e-6, which bounds
    # their difference at ~1e-6 of the motion (a mass-dominated tangent amplifies little).
    # Measured: 4e-10 m on a 7 cm sag.
    cantilever = os.path.join(SOURCE, "scenes", "cantilever.json")
    solid_runs = run_in_blocks("cantilever", cantilever, (1, 2, 4), "1")
    for ranks in (2, 4):
        check(files(solid_runs[ranks]) == expected_files(files(solid_runs[1]), ranks, "beam"),
              f"cantilever on {ranks} ranks: files differ from the serial run's")
    for ranks in (2, 4):
        compare_cantilever(f"cantilever on {ranks} ranks", solid_runs[1], solid_runs[ranks], 50)
    # The cantilever integrated explicitly (scenes/cantilever_explicit.json: RK4, lumped mass,
    # 0.1 ms), split over 2 ranks: the same arithmetic as the serial run but the order of the
    # sums at shared nodes, so its probes agree to rounding, amplified little over 1,000 steps
    # (bound 1e-9 of the sag and of the weight).
    explicit = os.path.join(SOURCE, "scenes", "cantilever_explicit.json")
    explicit_runs = run_in_blocks("cantilever_explicit", explicit, (1, 2), "0.1")
    compare_scaled("explicit cantilever on 2 ranks", explicit_runs[1], explicit_runs[2],
                   (("tip", 0.07), ("clamp", 0.1)), 1e-9, 5)
    # The cantilever with a slab glued on its top (a BoundaryCoupling between two FemSolids
    # meshed apart, on grids that do not match), both made in blocks: each rank couples its
    # parts of the interface. Its first 0.1 s (20 steps) gives the serial probes within 1e-6 of
    # their scale, as the cantilever does; measured 3e-7 of the clamp's 0.1 N, 6e-8 at the tips.
    with open(cantilever) as f:
        scene = json.load(f)
    scene["meshes"]["slab"] = {"generate": "box", "min": [0.04, 0, 0.01],
                               "max": [0.1, 0.01, 0.013], "cells": [9, 3, 1], "tets_per_cell": 5}
    slab = dict(scene["objects"]["beam"], domain="slab")
    slab.pop("boundary_conditions")
    scene["objects"]["slab"] = slab
    scene["connectors"] = {"glue": {"type": "BoundaryCoupling", "driver": "beam",
                                    "follower": "slab"}}
    scene["schedule"]["order"] = ["glue", "beam", "slab"]
    scene["probes"]["slab_tip"] = {"object": "slab", "region": {"group": "xmax"},
                                   "fields": ["displacement"], "reduce": "mean", "every": 0.01}
    glued = os.path.join(work, "cantilever_glued.json")
    with open(glued, "w") as f:
        json.dump(scene, f)
    glued_runs = run_in_blocks("cantilever_glued", glued, (1, 2, 4), "0.1",
                               "beam (FemSolid, in blocks), slab (FemSolid, in blocks)")
    for ranks in (2, 4):
        compare_scaled(f"glued cantilever on {ranks} ranks", glued_runs[1], glued_runs[ranks],
                       (("tip", 0.07), ("slab_tip", 0.07), ("clamp", 0.1)), 1e-6, 5)
    # The liver (scenes/meshes/liver.msh, Gmsh 1.0), fixed at a ligament patch and sagging for
    # 0.2 s, made in blocks: each rank streams the file keeping its block (nothing says it is
    # read whole), and the probes give the serial run's within 1e-6 of their scale (5 cm of
    # motion, 1 N of reaction, 1 cN of its mean over the surface). With a display mesh the liver
    # keeps its whole mesh on every rank; its region probes of the reaction (a sum over the
    # patch, a mean over the surface group, whose count a vertex on the cut counted twice would
    # change by 10 %) are then reduced over each rank's own boundary vertices too, and agree the
    # same way. Measured: 1e-11 m at the tip, 1.4e-9 N for the sum, 1e-11 N for the mean.
    meshes = os.path.join(SOURCE, "scenes", "meshes")
    patch = {"box": {"min": [0.01, 0.0, -0.02], "max": [0.02, 0.06, 0.03]}}
    liver = {
        "gipsi": 1, "units": "SI",
        "meshes": {"liver": {"file": os.path.join(meshes, "liver.msh"), "scale": 0.01}},
        "objects": {"liver": {
            "type": "FemSolid", "domain": "liver", "dt": 0.01, "density": 1060,
            "material": {"law": "NeoHookean", "youngs_modulus": 3000, "poisson_ratio": 0.45},
            "damping": {"mass": 1.0, "stiffness": 0.005}, "integrator": "BackwardEuler",
            "boundary_conditions": [{"name": "ligament", "region": patch, "fix": True}]}},
        "schedule": {"end": 0.2},
        "probes": {
            "tip": {"object": "liver", "point": [-0.044, 0.0184, 0.0075],
                    "fields": ["displacement"], "every": 0.02},
            "ligament": {"object": "liver", "region": patch, "fields": ["reaction_force"],
                         "reduce": "sum", "every": 0.02},
            "surface": {"object": "liver", "region": {"group": "physical_1"},
                        "fields": ["reaction_force"], "reduce": "mean", "every": 0.02}},
        "outputs": {"directory": "out"}}
    liver_scales = (("tip", 0.05), ("ligament", 1.0), ("surface", 0.01))
    for label, display, split in (("liver", False, "liver (FemSolid, in blocks)"),
                                  ("liver_whole", True, "liver (FemSolid)")):
        if display:
            liver["meshes"]["skin"] = {"file": os.path.join(meshes, "liver-smooth.obj"),
                                       "scale": 0.01}
            liver["objects"]["liver"]["display"] = {"mesh": "skin", "mapping": "barycentric",
                                                    "max_distance": 0.01}
        path = os.path.join(work, label + ".json")
        with open(path, "w") as f:
            json.dump(liver, f)
        liver_runs = run_in_blocks(label, path, (1, 2), "0.2", split)
        compare_scaled(f"{label} on 2 ranks", liver_runs[1], liver_runs[2], liver_scales, 1e-6, 10)
    code, text = run(2, os.path.join(work, "liver_read"), scene=os.path.join(work, "liver.json"),
                     until="0.01")
    check(code == 0 and "reads this file whole" not in text,
          f"the liver's Gmsh 1.0 file on 2 ranks is read whole: exit {code}: {text}")
    # The cantilever under more kinds of conditions, made in blocks like the others (no rank
    # holds its mesh): a total force on the tip's face group (split over its vertices, counted
    # once over the ranks), a pressure on the top face group's triangles, a traction on the
    # faces whose three vertices a box selects, and a displacement of a node given by id; the
    # clamp's largest reaction (a boundary field) over a box. Its probes give the serial run's
    # within 1e-6 of their scale, as above; measured 1e-9 N for the reactions, 3e-11 m at the tip.
    with open(cantilever) as f:
        scene = json.load(f)
    scene["objects"]["beam"]["boundary_conditions"] += [
        {"name": "tip", "region": {"group": "xmax"}, "total_force": [0, 0.002, -0.01]},
        {"name": "top", "region": {"group": "zmax"}, "pressure": 5},
        {"name": "side", "traction": [0, 0, -20],
         "region": {"box": {"min": [0.03, -1, -1], "max": [0.07, 0.0001, 1]}}},
        {"name": "corner", "region": {"nodes": [20]}, "displacement": [0, 0, -0.002],
         "axes": ["z"]}]
    scene["probes"]["reaction_box"] = {
        "object": "beam", "fields": ["reaction_force"], "reduce": "max",
        "region": {"box": {"min": [-1, -1, -1], "max": [0.0001, 1, 1]}}}
    loaded = os.path.join(work, "cantilever_loaded.json")
    with open(loaded, "w") as f:
        json.dump(scene, f)
    loaded_runs = run_in_blocks("cantilever_loaded", loaded, (1, 2, 4), "0.2")
    for ranks in (2, 4):
        compare_scaled(f"loaded cantilever on {ranks} ranks", loaded_runs[1], loaded_runs[ranks],
                       (("tip", 0.07), ("clamp", 0.1), ("reaction_box", 0.1)), 1e-6, 10)
    # A condition whose region selects no boundary vertex on any rank is refused on every
    # rank, once, with its JSON path, as in a serial run.
    scene["objects"]["beam"]["boundary_conditions"].append(
        {"region": {"box": {"min": [1, 1, 1], "max": [2, 2, 2]}}, "fix": True})
    with open(loaded, "w") as f:
        json.dump(scene, f)
    code, text = run(2, os.path.join(work, "cantilever_empty"), scene=loaded, until="0.01")
    errors = [line for line in text.splitlines() if line.startswith("gipsi: error:")]
    check(code == 1 and len(errors) == 1 and "boundary_conditions[5]" in text
          and "selects no boundary vertex" in text,
          f"an empty region on 2 ranks: exit {code}: {text}")
    # Events may name an object made in blocks: they set its part's conditions. The loaded
    # cantilever pushed sideways from 0.05 s (a total force on its ymax face group) and its tip
    # load removed at 0.1 s runs in blocks on 2 ranks as serially, within the bounds above.
    # Checkpointed at 0.15 s on 2 ranks and resumed on 4, it gives the uninterrupted run's
    # probes within them too: the push and the tip's release come only from the checkpoint (the
    # scene sets the tip load again, and the events have fired), so the conditions the events
    # set have moved with the state.
    scene["objects"]["beam"]["boundary_conditions"].pop()  # the empty region
    scene["schedule"]["events"] = [
        {"at": 0.05, "object": "beam",
         "apply": {"name": "push", "region": {"group": "ymax"}, "total_force": [0, -0.004, 0]}},
        {"at": 0.1, "object": "beam", "remove": "tip"}]
    evented = os.path.join(work, "cantilever_events.json")
    with open(evented, "w") as f:
        json.dump(scene, f)
    loaded_scales = (("tip", 0.07), ("clamp", 0.1), ("reaction_box", 0.1))
    event_runs = run_in_blocks("cantilever_events", evented, (1, 2), "0.2")
    compare_scaled("cantilever with events on 2 ranks", event_runs[1], event_runs[2],
                   loaded_scales, 1e-6, 10)
    moved = os.path.join(work, "cantilever_events_moved")
    code, text = run(2, moved, "-q", "--checkpoint-every", "0.05", scene=evented, until="0.15")
    check(code == 0, f"cantilever with events, checkpointed on 2 ranks: exit {code}: {text}")
    code, text = run(4, moved, "--resume", os.path.join(moved, "checkpoint.gck"), scene=evented,
                     until="0.2")
    check(code == 0 and "the checkpoint was written on 2 ranks" in text,
          f"cantilever with events, resumed on 4 ranks: exit {code}: {text}")
    compare_scaled("cantilever with events, 2 ranks' checkpoint resumed on 4", event_runs[2],
                   moved, loaded_scales, 1e-6, 10)
    # A divergence on one rank's part stops every rank, at the serial run's step.
    with open(SCENE) as f:
        scene = json.load(f)
    scene["objects"]["tissue"]["clamps"] = {"bad": {
        "region": {"box": {"min": [0.0195, 0.0065, 0.0025], "max": [0.0201, 0.0071, 0.0031]}},
        "voltage": "5 V", "start": "5 ms", "duration": "1 ms"}}
    bad = os.path.join(work, "diverging.json")
    with open(bad, "w") as f:
        json.dump(scene, f)
    diverged = {}
    for ranks in (1, 2):
        out = os.path.join(work, f"diverged{ranks}")
        code, text = run(ranks, out, "-q", scene=bad, until="0.01")
        check(code == 3 and "diverged" in text, f"diverging clamp on {ranks} ranks: exit {code}: {text}")
        diverged[ranks] = rows(os.path.join(out, "probes", "far_corner.csv"))
    times = {ranks: [row[0] for row in table] for ranks, table in diverged.items()}
    check(times[1] == times[2] and len(times[1]) > 5,
          f"diverging clamp: probe rows at {times[2][-3:]} on 2 ranks, {times[1][-3:]} serially")
    # Region probes on the slab, which no rank holds whole (nothing but probes reads it): a
    # box's mean, the xmin face's largest activation time, a sum over node ids, and a point at
    # the middle of the slab, where the parts meet; each within the bounds above of the serial
    # run's (a sum of three V values: three times V's).
    with open(SCENE) as f:
        scene = json.load(f)
    scene["probes"] = {
        "box_mean": {"object": "tissue", "field": "V", "reduce": "mean",
                     "region": {"box": {"min": [0.004, 0.001, 0], "max": [0.011, 0.005, 0.0015]}}},
        "face_max": {"object": "tissue", "field": "activation_time", "reduce": "max",
                     "region": {"group": "xmin"}},
        "ids_sum": {"object": "tissue", "field": "V", "reduce": "sum",
                    "region": {"nodes": [0, 1234, 4000]}},
        "middle": {"object": "tissue", "fields": ["V", "activation_time"],
                   "point": [0.01, 0.0035, 0.0015]}}
    scene["outputs"].pop("plots", None)
    region_runs = run_variant("regions", scene)
    for ranks in (2, 4):
        compare_probes(f"region probes on {ranks} ranks", region_runs[1], region_runs[ranks],
                       ("box_mean", "face_max", "ids_sum", "middle"), {"ids_sum": 3})
    # The slab's box as a Gmsh 4.1 file, a legacy VTK file and a compressed VTK XML file
    # (another tet mesh of it, written by bench/mpi/slab_msh.py: six tets per cell, each cell cut
    # along its main diagonal), which each rank reads in blocks: the serial run's probes, within
    # the bounds above, on 2 and 4 ranks.
    written = subprocess.run([sys.executable, os.path.join(SOURCE, "bench", "mpi", "slab_msh.py"),
                              "40", "14", "6", os.path.join(work, "slab"), "--vtk", "--vtu"],
                             capture_output=True, text=True, timeout=60)
    check(written.returncode == 0, f"slab_msh.py: {written.stdout}{written.stderr}")
    for kind in ("msh", "vtk", "vtu"):
        with open(SCENE) as f:
            scene = json.load(f)
        scene["meshes"]["slab"] = {"file": os.path.join(work, "slab." + kind)}
        scene["outputs"].pop("plots", None)
        file_runs = run_variant("from_" + kind, scene)
        for ranks in (2, 4):
            compare_probes(f"the slab from a .{kind} file on {ranks} ranks", file_runs[1],
                           file_runs[ranks], ("far_corner", "activated", "diagonal"))
    # The object's "parallel" block chooses the distributed diffusion solver: BoomerAMG needs
    # one CG iteration per step, and fewer in all than the default Jacobi; the activated fraction
    # stays the serial one within one node of the 4,305 (the solves agree to their tolerance).
    with open(SCENE) as f:
        scene = json.load(f)
    scene["probes"]["iterations"] = {"object": "tissue", "field": "diffusion_iterations"}
    counted = os.path.join(work, "counted.json")
    with open(counted, "w") as f:
        json.dump(scene, f)
    scene["objects"]["tissue"]["parallel"] = {"linear_solver": {"preconditioner": "hypre"}}
    hypre = os.path.join(work, "hypre.json")
    with open(hypre, "w") as f:
        json.dump(scene, f)
    iterations = {}
    for label, scene_file in (("jacobi", counted), ("hypre", hypre)):
        out = os.path.join(work, label)
        code, text = run(2, out, "-q", scene=scene_file, until="0.01")
        check(code == 0, f"the parallel block ({label}): exit {code}: {text}")
        iterations[label] = [int(r[1]) for r in rows(os.path.join(out, "probes", "iterations.csv"))[2:]]
        fractions = rows(os.path.join(out, "probes", "activated.csv"))[1:]
        serial_fractions = rows(os.path.join(serial, "probes", "activated.csv"))[1:len(fractions) + 1]
        for a, b in zip(serial_fractions, fractions):
            check(a[0] == b[0] and abs(float(a[1]) - float(b[1])) <= 1 / 4305 + 1e-12,
                  f"the parallel block ({label}): activated fraction {b} vs serial {a}")
    check(iterations["hypre"] and max(iterations["hypre"]) == 1 and
          sum(iterations["jacobi"]) > sum(iterations["hypre"]),
          f"the parallel block: CG iterations per step with hypre {sorted(set(iterations['hypre']))} "
          f"({sum(iterations['hypre'])} in all), Jacobi {sorted(set(iterations['jacobi']))} "
          f"({sum(iterations['jacobi'])})")
    print(f"the parallel block: {sum(iterations['hypre'])} CG iterations with hypre, "
          f"{sum(iterations['jacobi'])} with Jacobi")
    # Checkpoints: each rank writes its own file; a run stopped at 20 ms and resumed to 30 ms
    # on 2 ranks writes the uninterrupted run's files, every byte (frames, pieces, probes).
    resumed = os.path.join(work, "resumed")
    code, text = run(2, resumed, "--checkpoint-every", "0.01", until="0.02")
    check(code == 0, f"2 ranks with checkpoints: exit {code}: {text}")
    early = {}
    for k in (0, 1):
        with open(os.path.join(resumed, f"checkpoint_p{k}.gck"), "rb") as f:
            early[k] = f.read()
    code, text = run(2, resumed, "--resume", os.path.join(resumed, "checkpoint.gck"),
                     "--checkpoint-every", "0.01")
    check(code == 0, f"2 ranks resumed: exit {code}: {text}")
    uninterrupted = os.path.join(work, "ranks2")
    for f in files(uninterrupted):
        with open(os.path.join(uninterrupted, f), "rb") as a, open(os.path.join(resumed, f), "rb") as b:
            check(a.read() == b.read(), f"resumed on 2 ranks: {f} differs from the uninterrupted run")
    check(set(files(resumed)) - set(files(uninterrupted)) ==
          {"checkpoint_p0.gck", "checkpoint_p1.gck"},
          f"resumed on 2 ranks: files {set(files(resumed)) ^ set(files(uninterrupted))}")
    # The heart with its muscle split (its tangent factorised on every rank, redundantly: the
    # same bits in every run) resumes bitwise too, stopped at 0.2 s and resumed to 0.4 s; so does
    # the cantilever split (CG + GAMG kept across tangents while it works: the checkpoint saves
    # the values it was built from), stopped at 0.25 s and resumed to 0.5 s.
    resumes_bitwise("heart", heart, "0.1", "0.2", "0.4")
    resumes_bitwise("cantilever", cantilever, "0.05", "0.25", "0.5")
    # On another rank count the slab's state moves to the new parts: checkpointed at 20 ms on
    # N ranks and resumed to 30 ms on M, it writes the uninterrupted N-rank run's probes within
    # the bounds above (not bitwise: another cut sums in another order); measured 1e-13 ms.
    # The 4-rank run goes on past its checkpoint (at 20 ms) to 30 ms: the 2-rank run that
    # resumes from it rewrites the last frame in 2 pieces, and the other 2 are deleted.
    for before, after in ((2, 4), (2, 3), (4, 2)):
        moved = os.path.join(work, f"moved{before}to{after}")
        code, text = run(before, moved, "-q", "--checkpoint-every", "0.01" if before == 2 else "0.02",
                         until="0.02" if before == 2 else "0.03")
        check(code == 0, f"{before} ranks with checkpoints: exit {code}: {text}")
        code, text = run(after, moved, "--resume", os.path.join(moved, "checkpoint.gck"))
        check(code == 0 and f"the checkpoint was written on {before} ranks" in text,
              f"{before} ranks' checkpoint resumed on {after}: exit {code}: {text}")
        compare_probes(f"{before} ranks' checkpoint resumed on {after}",
                       os.path.join(work, f"ranks{before}"), moved,
                       ("far_corner", "activated", "diagonal"))
        last = sorted(f for f in files(moved) if f.endswith(".pvtu"))[-1]
        with open(os.path.join(moved, last)) as f:
            listed = re.findall(r'Source="([^"]+)"', f.read())
        pieces = sorted(f for f in files(moved) if f.startswith(last[:-len(".pvtu")] + "_p"))
        check(len(listed) == after and len(pieces) == after,
              f"{before} ranks' checkpoint resumed on {after}: the last frame {last} lists "
              f"{listed} and has the pieces {pieces}")
    # A split FemSolid's state moves too (per node, tet and boundary face; Newton starts
    # afresh): the cantilever checkpointed at 0.25 s on 2 ranks and resumed on 4 to 0.5 s, and
    # the heart checkpointed at 0.2 s on 2 ranks and resumed on 3 to 0.4 s (its bioelectricity
    # and muscle both split), give the uninterrupted 2-rank runs' probes within the bounds of
    # their serial comparisons above.
    beam = os.path.join(work, "cantilever_resumed")
    code, text = run(4, beam, "--resume", os.path.join(beam, "checkpoint.gck"), scene=cantilever,
                     until="0.5")
    check(code == 0 and "the checkpoint was written on 2 ranks" in text,
          f"the cantilever's 2-rank checkpoint on 4 ranks: exit {code}: {text}")
    compare_cantilever("the cantilever's 2-rank checkpoint resumed on 4",
                       os.path.join(work, "cantilever_full"), beam, 20)
    beating = os.path.join(work, "heart_resumed")
    code, text = run(3, beating, "--resume", os.path.join(beating, "checkpoint.gck"), scene=heart,
                     until="0.4")
    check(code == 0 and "the checkpoint was written on 2 ranks" in text,
          f"the heart's 2-rank checkpoint on 3 ranks: exit {code}: {text}")
    compare_heart("the heart's 2-rank checkpoint resumed on 3", os.path.join(work, "heart_full"),
                  beating, ("pv",))
    # A serial run's checkpoint resumes on several ranks (the split objects take their parts of
    # its one file): the slab checkpointed at 20 ms serially and resumed to 30 ms on 2 ranks
    # writes the serial run's probes within the bounds above, and its series lists the serial
    # run's whole frames before the checkpoint and the split run's after; the heart checkpointed
    # at 0.2 s serially and resumed on 2 ranks to 0.4 s gives the uninterrupted 2-rank run's PV
    # loop within the bound of its serial comparison.
    grown = os.path.join(work, "from_serial")
    code, text = run(1, grown, "-q", "--checkpoint-every", "0.02", until="0.02")
    check(code == 0, f"serial run with a checkpoint: exit {code}: {text}")
    resumed_across("a serial checkpoint resumed on 2 ranks", grown, 2,
                   "the checkpoint was written by a run on one process", ".vtu")
    grown_heart = os.path.join(work, "heart_from_serial")
    code, text = run(1, grown_heart, "-q", "--checkpoint-every", "0.2", scene=heart, until="0.2")
    check(code == 0, f"the serial heart with a checkpoint: exit {code}: {text}")
    code, text = run(2, grown_heart, "--resume", os.path.join(grown_heart, "checkpoint.gck"),
                     scene=heart, until="0.4")
    check(code == 0 and "the checkpoint was written by a run on one process" in text,
          f"the serial heart's checkpoint on 2 ranks: exit {code}: {text}")
    compare_heart("the serial heart's checkpoint resumed on 2", os.path.join(work, "heart_full"),
                  grown_heart, ("pv",))
    # And the other way: a 2-rank checkpoint resumed by a run on one process (its serial objects
    # gather the parts). The slab checkpointed at 20 ms on 2 ranks and resumed serially to 30 ms
    # gives the serial run's probes within the bounds, its series listing the 2-rank frames
    # before the checkpoint and whole ones after; the cantilever's 2-rank checkpoint at 0.25 s
    # resumed serially to 0.5 s gives the 2-rank run's probes within its serial bounds.
    shrunk = os.path.join(work, "to_serial")
    code, text = run(2, shrunk, "-q", "--checkpoint-every", "0.02", until="0.02")
    check(code == 0, f"2 ranks with a checkpoint: exit {code}: {text}")
    resumed_across("a 2-rank checkpoint resumed on one process", shrunk, 1,
                   "the checkpoint was written on 2 ranks: the split objects' parts are gathered",
                   ".pvtu")
    code, text = run(1, beam, "--resume", os.path.join(beam, "checkpoint.gck"), scene=cantilever,
                     until="0.5")
    check(code == 0 and "the checkpoint was written on 2 ranks" in text,
          f"the cantilever's 2-rank checkpoint on one process: exit {code}: {text}")
    compare_cantilever("the cantilever's 2-rank checkpoint resumed on one process",
                       os.path.join(work, "cantilever_full"), beam, 20)
    # The ranks' files resume only as the set written together; the refusals name the files
    # and the way out, and leave the outputs as they were.
    checkpoint = os.path.join(resumed, "checkpoint.gck")
    with open(os.path.join(resumed, "checkpoint_p1.gck"), "wb") as f:
        f.write(early[1])  # rank 1's file of the checkpoint at 20 ms, rank 0's at 30 ms
    before = rows(os.path.join(resumed, "probes", "far_corner.csv"))
    code, text = run(2, resumed, "--resume", checkpoint, until="0.04")
    check(code == 1 and "the ranks' checkpoint files are from different checkpoints" in text,
          f"a mixed set of checkpoint files: exit {code}: {text}")
    check(rows(os.path.join(resumed, "probes", "far_corner.csv")) == before,
          "a refused checkpoint changed the outputs")
    # Refusals keep the serial exit codes, on every rank.
    missing = os.path.join(work, "no-such-scene.json")
    result = subprocess.run([MPIEXEC, "-np", "2", GIPSI, "run", missing], capture_output=True,
                            text=True, timeout=120)
    check(result.returncode == 1 and "no-such-scene.json" in result.stderr,
          f"a missing scene under MPI: exit {result.returncode}: {result.stderr}")
    # An error every rank meets is printed once (rank 0's), not once per rank.
    errors = [line for line in result.stderr.splitlines() if line.startswith("gipsi: error:")]
    check(len(errors) == 1, f"a missing scene under MPI: {len(errors)} error lines: {errors}")

print("FAILED" if failures else "PASSED", f"({len(failures)} failures)")
sys.exit(1 if failures else 0)
