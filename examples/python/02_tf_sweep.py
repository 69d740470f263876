#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A transfer-function sweep as a contact sheet: one opacity band moved across the value range
of a real mesh, the mesh prepared once (changing the transfer function rebuilds nothing).

Usage: 02_tf_sweep.py [OUT_DIR] [MESH]   (writes tf_sweep.png; MESH defaults to the Oxygen Post
in ../shared/data, UVR_SHARED_DATA_DIR)
"""

import os
import pathlib
import sys

import uvr

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)
data = pathlib.Path(os.environ.get("UVR_SHARED_DATA_DIR",
                                   pathlib.Path(__file__).resolve().parents[3] / "shared" / "data"))
mesh_path = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else data / "post_tets.vtk"

renderer = uvr.Renderer(mesh_path, methods=("adaptive",))
camera = renderer.camera((200, 200), azimuth=-30, elevation=25)
frames = []
for centre in (0.15, 0.3, 0.45, 0.6, 0.75, 0.9):
    band = f"0:0,{centre - 0.08:.2f}:0,{centre:.2f}:0.9,{centre + 0.08:.2f}:0,1:0"
    frames.append(renderer.render(tf="Turbo", opacity=band, camera=camera, size=(200, 200)))
    print(f"band at {centre:.2f}: {frames[-1].stats['render_seconds'] * 1e3:.1f} ms, transfer-function "
          f"update {frames[-1].stats['tf_update_seconds'] * 1e3:.2f} ms")
sheet = uvr.contact_sheet(frames, columns=3, background=(1, 1, 1))
sheet.save(out / "tf_sweep.png")
print("tf_sweep.png:", sheet.shape[1], "x", sheet.shape[0])
assert renderer.info["value_updates"] == 0
