#!/usr/bin/env python3
"""Checks the include graph of src/gipsi against the layers of docs/architecture.md.

Each folder under src/gipsi/ is a layer and a CMake library (src/CMakeLists.txt); a file may
include its own layer and the layers below it, never one above or beside it:

    base -> geometry -> numerics -> core -> {models, collision, haptics} -> io -> {viz, parallel}

(models, collision and haptics sit side by side above core: none includes another). Every
`#include "gipsi/<layer>/..."` in src/ is checked. The few upward includes that remain from before
the layers were enforced are listed in KNOWN below, each with the file that has it; the check fails
on any other upward include, and also on a KNOWN entry that is gone, so the list only shrinks.

Usage: python3 scripts/check-layers.py [--graph]   (--graph prints the layer graph as found)
Exit 0 when the graph is as allowed, 1 otherwise (each offending file and include printed).
"""
import os
import re
import sys

BELOW = {
    "base": set(),
    "geometry": {"base"},
    "numerics": {"base", "geometry"},
    "core": {"base", "geometry", "numerics"},
    "models": {"base", "geometry", "numerics", "core"},
    "collision": {"base", "geometry", "numerics", "core"},
    "haptics": {"base", "geometry", "numerics", "core"},
    "io": {"base", "geometry", "numerics", "core", "models", "collision", "haptics"},
    "viz": {"base", "geometry", "numerics", "core", "models", "collision", "haptics", "io"},
    "parallel": {"base", "geometry", "numerics", "core", "models", "collision", "haptics", "io"},
}

# Upward includes still to be removed (issue 18): (file, included layer) -> why it is there.
KNOWN = {}

INCLUDE = re.compile(r'^\s*#\s*include\s*"gipsi/([a-z_]+)/')


def main():
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    src = os.path.join(root, "src", "gipsi")
    found = {}
    graph = {}
    unknown_layers = set()
    for folder, _, files in os.walk(src):
        for name in sorted(files):
            if not name.endswith((".h", ".cc")):
                continue
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, root)
            layer = rel.split(os.sep)[2]
            if layer not in BELOW:
                unknown_layers.add(layer)
                continue
            with open(path, encoding="utf-8", errors="replace") as f:
                for number, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if not m or m.group(1) == layer:
                        continue
                    target = m.group(1)
                    graph.setdefault(layer, set()).add(target)
                    if target not in BELOW[layer]:
                        found.setdefault((rel, target), (number, line.strip()))
    errors = []
    for layer in sorted(unknown_layers):
        errors.append(f"src/gipsi/{layer}/: a folder that is no layer; add it to BELOW in "
                      f"scripts/check-layers.py and to src/CMakeLists.txt")
    for (rel, target), (number, text) in sorted(found.items()):
        if (rel, target) not in KNOWN:
            layer = rel.split(os.sep)[2]
            errors.append(f"{rel}:{number}: layer '{layer}' includes '{target}' ({text}); "
                          f"'{layer}' may include only: {', '.join(sorted(BELOW[layer])) or 'nothing'}")
    for (rel, target), why in sorted(KNOWN.items()):
        if (rel, target) not in found:
            errors.append(f"{rel}: no longer includes '{target}' ({why}): remove it from KNOWN "
                          f"in scripts/check-layers.py")
    if "--graph" in sys.argv:
        for layer in BELOW:
            print(f"{layer} -> {', '.join(sorted(graph.get(layer, ()))) or '-'}")
    for e in errors:
        print(e, file=sys.stderr)
    if errors:
        print(f"check-layers: {len(errors)} problem(s)", file=sys.stderr)
        return 1
    print(f"check-layers: include graph within the layers ({len(KNOWN)} known upward includes left)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
