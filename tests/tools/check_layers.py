#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The layer check: the library's folders form a ladder (docs/ARCHITECTURE.md, "Layers"), and a
source may include only its own folder and the rungs below it. Prints each upward or sideways
include (file, line, the include, both layers) and exits 1 when there is one; prints the ladder's
include counts otherwise.

Tests beside the code (*_test.cpp) are exempt from the ladder: they are linked into one binary
with everything and render through the CPU renderer to check a lower layer's work. They still may
not include the server (only its own tests do) or anything outside src/.

Usage: check_layers.py [REPO_ROOT]
"""
import os
import re
import sys

# Bottom to top; folders on one rung do not include each other.
LADDER = [
    ["core"],
    ["mesh"],
    ["accel"],
    ["tf"],
    ["prepare"],
    ["render"],
    ["cpu", "cuda", "annotate", "cache"],
    ["dist"],
    ["facade"],
    ["uvr.h"],  # the public header: the facade and what its users need beside it
    ["server"],
]
RANK = {layer: i for i, rung in enumerate(LADDER) for layer in rung}
INCLUDE = re.compile(r'\s*#\s*include\s*"uvr/([A-Za-z0-9_.]+)')
SOURCE = re.compile(r"\.(h|cpp|cu|cuh)$")


def layer_of(rel):
    """The layer of a path under src/uvr ("mesh/io/vtu.cpp" -> "mesh", "uvr.h" -> "uvr.h")."""
    return rel.split("/")[0]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), "..", ".."))
    src = os.path.join(root, "src", "uvr")
    if not os.path.isdir(src):
        print(f"check_layers: {src}: no such folder", file=sys.stderr)
        return 2
    problems, counts, files = [], {}, 0
    for folder, _, names in sorted(os.walk(src)):
        for name in sorted(names):
            if not SOURCE.search(name):
                continue
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, src).replace(os.sep, "/")
            layer = layer_of(rel)
            if layer not in RANK:
                problems.append(f"src/uvr/{rel}: folder '{layer}' is not on the ladder "
                                "(add it to LADDER in tests/tools/check_layers.py and to "
                                "docs/ARCHITECTURE.md)")
                continue
            files += 1
            test = name.endswith("_test.cpp")
            with open(path, encoding="utf-8", errors="replace") as f:
                for number, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    target = m.group(1)
                    if target not in RANK:
                        problems.append(f"src/uvr/{rel}:{number}: includes uvr/{target}, which "
                                        "is not on the ladder")
                        continue
                    if target == layer:
                        continue
                    upward = RANK[target] >= RANK[layer]
                    if test:
                        upward = target == "server" and layer != "server"
                    if upward:
                        side = "sideways" if RANK[target] == RANK[layer] else "upward"
                        problems.append(f"src/uvr/{rel}:{number}: {line.strip()}: {side} from "
                                        f"'{layer}' to '{target}'")
                    elif not test:
                        counts[(layer, target)] = counts.get((layer, target), 0) + 1
    if problems:
        print("\n".join(problems))
        print(f"check_layers: {len(problems)} include(s) against the ladder "
              "(docs/ARCHITECTURE.md, \"Layers\")", file=sys.stderr)
        return 1
    edges = ", ".join(f"{a}->{b} {n}" for (a, b), n in sorted(counts.items(),
                      key=lambda kv: (RANK[kv[0][0]], kv[0][0], RANK[kv[0][1]])))
    print(f"check_layers: {files} files, no upward or sideways include; downward: {edges}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
