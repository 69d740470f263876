#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Figures of a `uvr bench --json` run, drawn with matplotlib (python3-matplotlib).

  plot_bench.py BENCH.json --out FIG.png [--heatmaps HEAT.png]

FIG.png: time per frame and SSIM against the exact integrator over s2 / s1 for skipping +
adaptive (Morrical et al. 2019, Fig. 4 style; s2 = s1 is "skipping only"), the reference's time
as a dashed line. HEAT.png (needs the run's --images): the sample heat maps of the reference and
the adaptive variants side by side on their common scale, with a labelled colour bar (the heat
map PNGs carry an unlabelled one).
"""

import argparse
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import ListedColormap, Normalize  # noqa: E402


def time_and_ssim(bench, out):
    rows = bench["rows"]
    skipping = next(r for r in rows if r["configuration"] == "skipping only")
    sweep = [r for r in rows if r["configuration"].startswith("both, s2 = ")]
    xs = [1.0] + [r["s2_over_s1"] for r in sweep]
    ms = [skipping["seconds_per_frame"] * 1e3] + [r["seconds_per_frame"] * 1e3 for r in sweep]
    ssim = [skipping["ssim"]] + [r["ssim"] for r in sweep]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
    ax.plot(xs, ms, "o-", color="tab:blue", label="ms per frame")
    ax.axhline(rows[0]["seconds_per_frame"] * 1e3, color="tab:blue", ls="--", lw=1,
               label="reference")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("s2 / s1")
    ax.set_ylabel("ms per frame")
    ax.set_ylim(bottom=0)
    right = ax.twinx()
    right.plot(xs, ssim, "s-", color="tab:red", label="SSIM vs exact")
    right.set_ylabel(f"SSIM against {bench.get('ssim_against', 'exact')}")
    lo = min(ssim + [rows[0]["ssim"]])
    right.set_ylim(min(lo, 0.98) - 0.005, 1.0)
    lines = ax.get_lines() + right.get_lines()
    ax.legend(lines, [line.get_label() for line in lines], loc="center right", fontsize=8)
    name = pathlib.Path(bench["file"]).name
    w, h = bench["image"]
    ax.set_title(f"{name}: skipping + adaptive against s2 ({w}x{h}, {bench['device']})",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def heatmaps(bench, images, out):
    w, h = bench["image"]
    wanted = ["reference", "skipping only", "adaptive only", "skipping + adaptive"]
    rows = [r for r in bench["rows"] if r["configuration"] in wanted and "image" in r]
    if not rows:
        sys.exit("plot_bench.py: the run has no images (run uvr bench with --images)")
    cmap = ListedColormap(bench["heatmap"]["colors"], name="uvr-samples")
    top = max(1, bench["heatmap"]["max_samples"])
    fig, axes = plt.subplots(1, len(rows), figsize=(3.2 * len(rows) + 0.8, 3.4), dpi=120,
                             squeeze=False)
    for ax, row in zip(axes[0], rows):
        picture = plt.imread(images / f"{row['image']}_samples.png")[:, :w, :3]  # no bar
        ax.imshow(picture, interpolation="nearest")
        spp = row["samples"] / (w * h)
        ax.set_title(f"{row['configuration']}\n{spp:.1f} samples/pixel, SSIM {row['ssim']:.3f}",
                     fontsize=8)
        ax.set_axis_off()
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=Normalize(0, top), cmap=cmap),
                       ax=list(axes[0]), fraction=0.02, pad=0.02)
    bar.set_label("samples per pixel")
    fig.savefig(out, bbox_inches="tight")
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("json", type=pathlib.Path, help="the JSON of `uvr bench --json`")
    parser.add_argument("--out", type=pathlib.Path, required=True,
                        help="time and SSIM against s2 (PNG, SVG or PDF)")
    parser.add_argument("--heatmaps", type=pathlib.Path,
                        help="sample heat maps side by side (needs the run's --images)")
    args = parser.parse_args()
    bench = json.loads(args.json.read_text())
    time_and_ssim(bench, args.out)
    if args.heatmaps:
        if "images" not in bench:
            sys.exit("plot_bench.py: the run has no images (run uvr bench with --images)")
        images = pathlib.Path(bench["images"])
        if not images.is_absolute():
            images = args.json.parent / images if not images.exists() else images
        heatmaps(bench, images, args.heatmaps)


if __name__ == "__main__":
    main()
