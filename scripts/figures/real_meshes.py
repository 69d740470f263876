#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The README's real-data figure: four real meshes rendered by the default method (adaptive),
each captioned with its worst pixels against the exact integrator (99.9th percentile and maximum
of the per-pixel difference, 8-bit levels, `uvr compare`). The Blunt Fin view is issue 29's
streak case (azimuth 35, elevation 25).

Usage: scripts/figures/real_meshes.py [UVR_BINARY] [SHARED_DATA] [OUT.png]
(defaults: build/release/uvr, ../shared/data, docs/images/real_meshes.png)
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
out = sys.argv[3] if len(sys.argv) > 3 else "docs/images/real_meshes.png"
size = 512
panels = [
    ("NASA Blunt Fin, density", "bluntfin_tets.vtk",
     ["--field", "density", "--azimuth", "35", "--elevation", "25"]),
    ("Oxygen Post, speed", "post_tets.vtk",
     ["--field", "speed", "--azimuth", "-30", "--elevation", "25", "--tf", "Viridis"]),
    ("SPX", "spx.vtk", ["--tf", "Inferno", "--elevation", "20", "--background", "0.1,0.1,0.12"]),
    ("Fire (hexahedra, .vtu), temperature", "fire_ug.vtu",
     ["--field", "t", "--tf", "Black-Body Radiation", "--azimuth", "30", "--elevation", "20",
      "--background", "0.1,0.1,0.12"]),
]
with tempfile.TemporaryDirectory() as tmp:
    images, labels = [], []
    for i, (name, file, flags) in enumerate(panels):
        common = [str(data / file), "--size", f"{size}x{size}", "--device", "cpu", *flags]
        png, exact, stats = f"{tmp}/{i}.png", f"{tmp}/{i}_exact.png", f"{tmp}/{i}.json"
        subprocess.run([uvr, "-q", "render", *common, "-o", png, "--stats", stats], check=True)
        subprocess.run([uvr, "-q", "render", *common, "--method", "exact", "-o", exact],
                       check=True)
        cmp = subprocess.run([uvr, "compare", "--json", exact, png], check=True,
                             capture_output=True, text=True)
        c = json.loads(cmp.stdout)
        s = json.load(open(stats))
        labels.append(f"{name}\n{s['samples'] / (size * size):.1f} samples/pixel; vs exact: "
                      f"p99.9 {c['p999_difference']:.0f}, max {c['max_abs_difference']:.0f}")
        images.append(mpimg.imread(png))
    fig, axes = plt.subplots(1, len(images), figsize=(4 * len(images), 4.5))
    for ax, img, label in zip(axes, images, labels):
        ax.imshow(img)
        ax.set_title(label, fontsize=9)
        ax.axis("off")
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.88, wspace=0.03)
    fig.savefig(out, dpi=96)
print("wrote", out)
