#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Render a mesh made of numpy arrays: a jittered box of tetrahedra with a field, no file.

Usage: 01_numpy_render.py [OUT_DIR]   (writes numpy_render.png)
"""

import pathlib
import sys

import numpy as np

import uvr

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)

# Points of an n^3 grid over [-1, 1]^3 and each cube split into 6 tetrahedra (Kuhn's split).
n = 24
ax = np.linspace(-1.0, 1.0, n + 1, dtype=np.float32)
z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
i, j, k = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij"))


def corner(di, dj, dk):
    return ((k + dk) * (n + 1) + (j + dj)) * (n + 1) + (i + di)


c = [corner(d & 1, (d >> 1) & 1, d >> 2) for d in range(8)]  # the cube's corners, bit-coded
paths = [(1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)]  # Kuhn: 0 -> a -> b -> 7
tets = np.concatenate([np.stack([c[0], c[a], c[b], c[7]], axis=1) for a, b in paths])
tets = tets.astype(np.uint32)
# Orient every tetrahedron positively (uvr re-orients inverted cells anyway, with a note).
p = points[tets]
vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
tets[vol < 0] = tets[vol < 0][:, [0, 2, 1, 3]]

# A field: two Gaussian blobs.
r1 = np.sum((points - [0.4, 0.2, 0.0]) ** 2, axis=1)
r2 = np.sum((points + [0.4, 0.3, 0.1]) ** 2, axis=1)
field = (np.exp(-8 * r1) + 0.7 * np.exp(-5 * r2)).astype(np.float32)

mesh = uvr.Mesh(points, cells=tets, point_data={"blobs": field})
print(mesh, "copied:", mesh.copied or "nothing")
renderer = uvr.Renderer(mesh)
img = renderer.render(tf="Viridis", opacity="0:0,0.3:0,1:0.8", size=(320, 320), azimuth=35,
                      elevation=25)
img.save(out / "numpy_render.png", background=(1, 1, 1))
print(f"numpy_render.png: {img.stats['mean_samples_per_pixel']:.1f} samples per pixel, "
      f"{img.stats['render_seconds'] * 1e3:.1f} ms on {renderer.device}")
assert img[..., 3].max() > 0.5, "the blobs should be visible"
