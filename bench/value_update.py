#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Time a renderer's preparation against a time step's value update (Renderer.set_field) on
real meshes, CPU: prints one table row per mesh.

Usage: PYTHONPATH=<build>/python /usr/bin/python3 bench/value_update.py [DATA_DIR]
"""

import pathlib
import sys
import time

import numpy as np

import uvr

data = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/data")
print("| mesh | tetrahedra | partitions | Renderer() s | set_field ms (median of 5) | "
      "256x256 frame ms |")
print("|---|---|---|---|---|---|")
for name in ("bluntfin_tets.vtk", "post_tets.vtk"):
    mesh = uvr.read(data / name)
    x = np.asarray(mesh.points)[:, 0]
    start = time.perf_counter()
    r = uvr.Renderer(mesh, device="cpu", methods=("adaptive",))
    prepare = time.perf_counter() - start
    updates = []
    for t in range(5):
        values = np.sin(x + t).astype(np.float32)
        start = time.perf_counter()
        r.set_field(values)
        updates.append(time.perf_counter() - start)
    frame = r.render(size=(256, 256), range=(-1, 1), azimuth=30)
    i = r.info
    print(f"| {name} | {i['tetrahedra']} | {i['partitions']} | {prepare:.3f} | "
          f"{np.median(updates) * 1e3:.1f} | {frame.stats['render_seconds'] * 1e3:.1f} |")
