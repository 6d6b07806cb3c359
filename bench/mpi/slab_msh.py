#!/usr/bin/env python3
"""Writes the N-version slab (20 x 7 x 3 mm) as a Gmsh 4.1 ASCII file, and a copy of
scenes/slab_ep_0.1mm.json that reads it, for measuring a scene run whose mesh comes from a file
(docs/scale-out.md, "Scene runs without the whole mesh").

Each cell of the nx x ny x nz grid is cut into six tets along its main diagonal (the Kuhn
split: a conforming mesh, every tet positively oriented). Plain Python, no NumPy.

Usage: slab_msh.py NX NY NZ OUT   (writes OUT.msh and OUT.json)
"""
import json
import os
import sys

nx, ny, nz = (int(a) for a in sys.argv[1:4])
out = sys.argv[4]


def vertex(i, j, k):
    return i + (nx + 1) * (j + (ny + 1) * k)


n = (nx + 1) * (ny + 1) * (nz + 1)
m = 6 * nx * ny * nz
# The six paths from a cell's corner to the opposite one; the odd permutations of the axes give
# negatively oriented tets, whose last two vertices are swapped.
paths = ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))
odd = (False, True, True, False, False, True)
with open(out + ".msh", "w") as f:
    f.write(f"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n")
    f.write("".join(f"{t}\n" for t in range(1, n + 1)))
    for k in range(nz + 1):
        f.write("".join(f"{0.020 * i / nx!r} {0.007 * j / ny!r} {0.003 * k / nz!r}\n"
                        for j in range(ny + 1) for i in range(nx + 1)))
    f.write(f"$EndNodes\n$Elements\n1 {m} 1 {m}\n3 1 4 {m}\n")
    tag = 1
    for k in range(nz):
        lines = []
        for j in range(ny):
            for i in range(nx):
                for path, flip in zip(paths, odd):
                    at = [i, j, k]
                    tet = [vertex(i, j, k)]
                    for axis in path:
                        at[axis] += 1
                        tet.append(vertex(*at))
                    if flip:
                        tet[2], tet[3] = tet[3], tet[2]
                    lines.append(f"{tag} {tet[0] + 1} {tet[1] + 1} {tet[2] + 1} {tet[3] + 1}\n")
                    tag += 1
        f.write("".join(lines))
    f.write("$EndElements\n")

here = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(here, "..", "..", "scenes", "slab_ep_0.1mm.json")) as f:
    scene = json.load(f)
scene["meshes"]["slab"] = {"file": os.path.abspath(out + ".msh")}
scene["outputs"].pop("plots", None)
with open(out + ".json", "w") as f:
    json.dump(scene, f, indent=1)
print(f"{out}.msh: {n} nodes, {m} tets; {out}.json reads it")
