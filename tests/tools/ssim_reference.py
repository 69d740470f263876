#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Prints scikit-image's SSIM and PSNR of pairs of 8-bit RGB PNG files as JSON, the oracle for
uvr's compareImages: structural_similarity(channel_axis=2, gaussian_weights=True, sigma=1.5,
use_sample_covariance=False, data_range=255) and peak_signal_noise_ratio(data_range=255); and
numpy's 99.9th percentile (linear interpolation), maximum and fraction above 4 of the per-pixel
difference max_c |a_c - b_c|.

Usage: ssim_reference.py A.png B.png [A2.png B2.png ...]
Output, one line per pair: {"ssim": S, "ssim_channels": [R, G, B], "psnr": P, or null when the
images are identical, "p999": Q, "max": M, "fraction_off": F}
"""
import json
import math
import sys

import numpy as np
from PIL import Image
from skimage.metrics import peak_signal_noise_ratio, structural_similarity


def load_rgb(path):
    with Image.open(path) as im:
        if im.mode not in ("RGB", "L"):
            sys.exit(f"{path}: expected an RGB or grey PNG, got mode {im.mode}")
        return np.asarray(im.convert("RGB"), dtype=np.uint8)


def compare(path_a, path_b):
    a, b = load_rgb(path_a), load_rgb(path_b)
    kwargs = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                  data_range=255)
    ssim = structural_similarity(a, b, channel_axis=2, **kwargs)
    channels = [structural_similarity(a[:, :, c], b[:, :, c], **kwargs) for c in range(3)]
    psnr = peak_signal_noise_ratio(a, b, data_range=255) if np.any(a != b) else math.inf
    diff = np.abs(a.astype(np.int32) - b.astype(np.int32)).max(axis=2)
    return {"ssim": float(ssim), "ssim_channels": [float(c) for c in channels],
            "psnr": None if math.isinf(psnr) else float(psnr),
            "p999": float(np.percentile(diff, 99.9)), "max": float(diff.max()),
            "fraction_off": float(np.mean(diff > 4))}


def main():
    paths = sys.argv[1:]
    if not paths or len(paths) % 2:
        sys.exit("usage: ssim_reference.py A.png B.png [A2.png B2.png ...]")
    for i in range(0, len(paths), 2):
        print(json.dumps(compare(paths[i], paths[i + 1])))


if __name__ == "__main__":
    main()
