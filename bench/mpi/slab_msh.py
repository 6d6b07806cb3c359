#!/usr/bin/env python3
"""Writes the N-version slab (20 x 7 x 3 mm) as a Gmsh 4.1 ASCII file, and a copy of
scenes/slab_ep_0.1mm.json that reads it, for measuring a scene run whose mesh comes from a file
(docs/scale-out.md, "Scene runs without the whole mesh").

Each cell of the nx x ny x nz grid is cut into six tets along its main diagonal (the Kuhn
split: a conforming mesh, every tet positively oriented). Plain Python, no NumPy.

Usage: slab_msh.py NX NY NZ OUT [--vtk] [--vtu]   (writes OUT.msh and OUT.json; with --vtk
also the same mesh as a legacy VTK unstructured grid, OUT.vtk, ASCII; with --vtu as a VTK XML
unstructured grid, OUT.vtu, in the layout VTK writes by default when asked to compress: raw
appended data, zlib blocks of 32 KiB, UInt64 headers)
"""
import json
import os
import struct
import sys
import zlib

nx, ny, nz = (int(a) for a in sys.argv[1:4])
out = sys.argv[4]
flags = sys.argv[5:]
if any(flag not in ("--vtk", "--vtu") for flag in flags):
    sys.exit(__doc__)
vtk, vtu = "--vtk" in flags, "--vtu" in flags


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
if vtk or vtu:  # the same nodes and tets, numbered from 0, read back from the file just written
    with open(out + ".msh") as f:
        text = f.read().split("$Nodes\n")[1]
    node_lines = text.split("$EndNodes")[0].splitlines()[2 + n:]
    tet_lines = text.split("$Elements\n")[1].split("$EndElements")[0].splitlines()[2:]
if vtk:
    with open(out + ".vtk", "w") as f:
        f.write(f"# vtk DataFile Version 3.0\nslab\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                f"POINTS {n} double\n")
        f.write("".join(line + "\n" for line in node_lines))
        f.write(f"CELLS {m} {5 * m}\n")
        f.write("".join("4 " + " ".join(str(int(v) - 1) for v in line.split()[1:]) + "\n"
                        for line in tet_lines))
        f.write(f"CELL_TYPES {m}\n" + "10\n" * m)
if vtu:
    def compressed(data, block=32768):
        """VTK's compressed binary block: the header (block count, block size, last block's
        size, each block's compressed size; UInt64) and the zlib blocks."""
        blocks = [zlib.compress(data[p:p + block]) for p in range(0, len(data), block)]
        last = len(data) % block
        return struct.pack(f"<{3 + len(blocks)}Q", len(blocks), block, last,
                           *(len(b) for b in blocks)) + b"".join(blocks)

    arrays = [
        ("Points", 'type="Float64" NumberOfComponents="3"',
         struct.pack(f"<{3 * n}d", *(float(v) for line in node_lines for v in line.split()))),
        ("connectivity", 'type="Int64" Name="connectivity"',
         struct.pack(f"<{4 * m}q", *(int(v) - 1 for line in tet_lines for v in line.split()[1:]))),
        ("offsets", 'type="Int64" Name="offsets"',
         struct.pack(f"<{m}q", *range(4, 4 * m + 1, 4))),
        ("types", 'type="UInt8" Name="types"', bytes([10]) * m)]
    appended, tags = b"", {}
    for name, attributes, data in arrays:
        tags[name] = f'<DataArray {attributes} format="appended" offset="{len(appended)}"/>'
        appended += compressed(data)
    with open(out + ".vtu", "wb") as f:
        f.write(('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
                 'byte_order="LittleEndian" header_type="UInt64" '
                 'compressor="vtkZLibDataCompressor">\n<UnstructuredGrid>\n'
                 f'<Piece NumberOfPoints="{n}" NumberOfCells="{m}">\n'
                 f'<Points>\n{tags["Points"]}\n</Points>\n<Cells>\n{tags["connectivity"]}\n'
                 f'{tags["offsets"]}\n{tags["types"]}\n</Cells>\n</Piece>\n'
                 '</UnstructuredGrid>\n<AppendedData encoding="raw">\n_').encode())
        f.write(appended)
        f.write(b"\n</AppendedData>\n</VTKFile>\n")

here = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(here, "..", "..", "scenes", "slab_ep_0.1mm.json")) as f:
    scene = json.load(f)
scene["meshes"]["slab"] = {"file": os.path.abspath(out + ".msh")}
scene["outputs"].pop("plots", None)
with open(out + ".json", "w") as f:
    json.dump(scene, f, indent=1)
written = [out + ".msh"] + [out + ext for ext, wanted in ((".vtk", vtk), (".vtu", vtu)) if wanted]
print(f"{', '.join(written)}: {n} nodes, {m} tets; {out}.json reads the first")
