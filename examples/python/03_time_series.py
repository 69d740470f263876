#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A time series: the field is a function of time on a fixed mesh; each step only refreshes the
values (set_field: the tetrahedra, BVHs and k-d partitions are not rebuilt), and the frames are
written side by side.

Usage: 03_time_series.py [OUT_DIR] [MESH]   (writes time_series.png; MESH defaults to Blunt Fin)
"""

import os
import pathlib
import sys
import time

import numpy as np

import uvr

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)
data = pathlib.Path(os.environ.get("UVR_SHARED_DATA_DIR",
                                   pathlib.Path(__file__).resolve().parents[3] / "shared" / "data"))
mesh = uvr.read(pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else data / "bluntfin_tets.vtk")
p = np.asarray(mesh.points)
centre = p.mean(axis=0)
extent = p.max(axis=0) - p.min(axis=0)


def field(t):
    """A pulse travelling along the mesh's longest axis, on top of the file's density."""
    axis = int(np.argmax(extent))
    x = (p[:, axis] - p[:, axis].min()) / extent[axis]
    pulse = np.exp(-((x - t) / 0.08) ** 2)
    return (mesh.point_data["density"] * (1.0 + 2.0 * pulse)).astype(np.float32)


start = time.perf_counter()
renderer = uvr.Renderer(mesh, field=field(0.0), methods=("adaptive",))
prepare = time.perf_counter() - start
camera = renderer.camera((240, 180), azimuth=35, elevation=25)
frames = []
updates = []
for t in np.linspace(0.0, 1.0, 6):
    start = time.perf_counter()
    renderer.set_field(field(t))
    updates.append(time.perf_counter() - start)
    frames.append(renderer.render(tf="Inferno", opacity="0:0,0.4:0,1:0.6", range=(0.0, 3.0),
                                  camera=camera, size=(240, 180)))
info = renderer.info
print(f"prepared {info['tetrahedra']} tetrahedra in {prepare:.2f} s; each time step's value "
      f"update took {np.median(updates) * 1e3:.1f} ms (median), {info['value_updates']} updates")
uvr.contact_sheet(frames, columns=3, background=(0, 0, 0)).save(out / "time_series.png")
assert info["value_updates"] == 6
