#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The README's method figure: the Oxygen Post under two opacity bands (the issue-11 case where
point samples showed wood-grain), rendered by the exact integrator, the pre-integrated reference
and the default adaptive method, with each one's SSIM against exact and its samples per pixel.

Usage: scripts/figures/post_methods.py [UVR_BINARY] [SHARED_DATA] [OUT.png]
(defaults: build/release/uvr, ../shared/data, docs/images/adaptive_post.png)
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
out = sys.argv[3] if len(sys.argv) > 3 else "docs/images/adaptive_post.png"
view = ["--size", "512x512", "--azimuth", "-30", "--elevation", "25", "--background", "0,0,0",
        "--tf", "cool-to-warm", "--opacity", "0:0,0.3:0,0.32:0.8,0.34:0,0.6:0,0.62:0.8,0.64:0,1:0"]
methods = [("exact", ["--method", "exact"]),
           ("reference, point samples (before)", ["--method", "reference", "--sampling", "point"]),
           ("reference (pre-integrated)", ["--method", "reference"]),
           ("adaptive (the default)", [])]
with tempfile.TemporaryDirectory() as tmp:
    images, labels = [], []
    for i, (name, flags) in enumerate(methods):
        png, stats = f"{tmp}/{i}.png", f"{tmp}/{i}.json"
        subprocess.run([uvr, "-q", "render", str(data / "post_tets.vtk"), "-o", png, "--stats",
                        stats, "--device", "cpu", *view, *flags], check=True)
        s = json.load(open(stats))
        label = f"{name}\n{s['samples'] / (512 * 512):.0f} samples/pixel" if i else \
            f"{name}\n{s['samples'] / (512 * 512):.0f} cells/pixel"
        if i:
            cmp = subprocess.run([uvr, "compare", "--json", f"{tmp}/0.png", png], check=True,
                                 capture_output=True, text=True)
            label += f", SSIM {json.loads(cmp.stdout)['ssim']:.3f} vs exact"
        images.append(mpimg.imread(png))
        labels.append(label)
    fig, axes = plt.subplots(1, len(images), figsize=(4 * len(images), 4.6))
    for ax, img, label in zip(axes, images, labels):
        ax.imshow(img[56:456, 56:456])  # the mesh's part of the frame
        ax.set_title(label, fontsize=10)
        ax.axis("off")
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.86, wspace=0.03)
    fig.savefig(out, dpi=80)
print("wrote", out)
