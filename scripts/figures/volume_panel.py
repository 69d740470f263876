#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The README's lighting, clipping and isosurface figure (issue 32): the NASA Blunt Fin's
density rendered by the default method unshaded, shaded (`--shade`), clipped by a plane
(`--clip-plane`), with two isosurfaces inside the volume (`--iso`) and clipped with the cut face
drawn (`--clip-surface`), each captioned with the
flags and its worst pixels against the exact integrator at the same settings (99.9th percentile
and maximum of the per-pixel difference, 8-bit levels, `uvr compare`).

Usage: scripts/figures/volume_panel.py [UVR_BINARY] [SHARED_DATA] [OUT.png]
(defaults: build/release/uvr, ../shared/data, docs/images/volume_panel.png)
"""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

uvr = sys.argv[1] if len(sys.argv) > 1 else "build/release/uvr"
data = Path(sys.argv[2] if len(sys.argv) > 2 else "../shared/data")
out = sys.argv[3] if len(sys.argv) > 3 else "docs/images/volume_panel.png"
size = (512, 384)
view = ["--azimuth", "30", "--elevation", "20", "--view-angle", "21", "--background", "1,1,1",
        "--tf", "Viridis",
        "--opacity", "0:0,0.15:0.1,1:0.6"]
panels = [
    ("unshaded", []),
    ("--shade --specular 0.3", ["--shade", "--specular", "0.3", "--specular-power", "20"]),
    ("--shade --clip-plane 3,0,0,-1,0,0",
     ["--shade", "--specular", "0.3", "--specular-power", "20", "--clip-plane", "3,0,0,-1,0,0"]),
    ("--iso 1.3,0.6,#ff6020 --iso 2.5", ["--iso", "1.3,0.6,#ff6020", "--iso", "2.5",
                                         "--specular", "0.3", "--specular-power", "20"]),
    ("--clip-plane 0,0,1.5,0,0,-1 --clip-surface",
     ["--clip-plane", "0,0,1.5,0,0,-1", "--clip-surface", "--ambient", "0.2", "--diffuse",
      "0.8"]),
]
with tempfile.TemporaryDirectory() as tmp:
    images, labels = [], []
    for i, (name, flags) in enumerate(panels):
        common = [str(data / "bluntfin_tets.vtk"), "--size", f"{size[0]}x{size[1]}",
                  "--device", "cpu", *view, *flags]
        png, exact = f"{tmp}/{i}.png", f"{tmp}/{i}_exact.png"
        subprocess.run([uvr, "-q", "render", *common, "-o", png], check=True)
        subprocess.run([uvr, "-q", "render", *common, "--method", "exact", "-o", exact],
                       check=True)
        cmp = subprocess.run([uvr, "compare", "--json", exact, png], check=True,
                             capture_output=True, text=True)
        c = json.loads(cmp.stdout)
        labels.append(f"{name}\nvs exact: p99.9 {c['p999_difference']:.0f}, "
                      f"max {c['max_abs_difference']:.0f}")
        images.append(mpimg.imread(png))
    fig, axes = plt.subplots(1, len(images), figsize=(4 * len(images), 3.8))
    for ax, img, label in zip(axes, images, labels):
        ax.imshow(img)
        ax.set_title(label, fontsize=9)
        ax.axis("off")
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.84, wspace=0.03)
    fig.savefig(out, dpi=96)
print("wrote", out)
