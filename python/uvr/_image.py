# SPDX-License-Identifier: MIT
"""Rendered images: numpy arrays that know their statistics and show themselves in Jupyter."""

import os

import numpy as np

from . import _uvr


def _plain(pixels):
    return np.ascontiguousarray(np.asarray(pixels, dtype=np.float32).view(np.ndarray))


def _background(background):
    if background is None:
        return None
    b = tuple(float(x) for x in background)
    if len(b) != 3 or not all(0.0 <= x <= 1.0 for x in b):
        raise _uvr.ArgumentError(f"background: expected (r, g, b) in [0, 1], got {background!r}")
    return b


class Image(np.ndarray):
    """A rendered frame: a float32 numpy array of shape (h, w, 4), RGBA with the colour
    premultiplied by alpha (as the renderer composites it; row 0 at the top).

    ``stats`` holds the frame's statistics (time, samples, ...), ``sample_counts`` the samples of
    each pixel (uint32 (h, w)), ``depth`` the view depths asked for with ``depth=`` (float32
    (h, w), else None). ``to_uint8()`` gives the 8-bit pixels of the PNG (straight RGBA,
    or RGB over a background), ``save(path)`` writes the PNG ``uvr render`` writes, and in
    Jupyter the image displays itself (``_repr_png_``) over ``background`` (transparent when
    None).
    """

    def __new__(cls, pixels, stats=None, sample_counts=None, background=None, depth=None):
        obj = np.asarray(pixels, dtype=np.float32).view(cls)
        obj.stats = dict(stats or {})
        obj.sample_counts = sample_counts
        obj.depth = depth
        obj.background = _background(background)
        return obj

    def __array_finalize__(self, obj):
        if obj is None:
            return
        self.stats = getattr(obj, "stats", {})
        self.sample_counts = getattr(obj, "sample_counts", None)
        self.depth = getattr(obj, "depth", None)
        self.background = getattr(obj, "background", None)

    def _check(self):
        if self.ndim != 3 or self.shape[2] != 4:
            raise _uvr.ArgumentError(f"image: expected shape (h, w, 4), got {self.shape}")

    def to_uint8(self, background=...):
        """The PNG's 8-bit pixels: (h, w, 4) straight RGBA, or (h, w, 3) composited over
        ``background`` (r, g, b in [0, 1]; default: the image's own background)."""
        self._check()
        bg = self.background if background is ... else _background(background)
        return _uvr.to_uint8(_plain(self), bg)

    def png_bytes(self, background=...):
        """The PNG file ``save`` writes, as bytes."""
        self._check()
        bg = self.background if background is ... else _background(background)
        return _uvr.png_bytes(_plain(self), bg)

    def save(self, path, background=...):
        """Writes the image as an 8-bit PNG (atomically), as ``uvr render -o`` does."""
        self._check()
        bg = self.background if background is ... else _background(background)
        _uvr.write_png(os.fspath(path), _plain(self), bg)

    def _repr_png_(self):
        if self.ndim != 3 or self.shape[2] != 4 or self.size == 0:
            return None
        return self.png_bytes()


def read_png(path):
    """Reads a PNG into an Image (premultiplied float RGBA), e.g. one ``uvr render`` wrote."""
    return Image(_uvr.read_png(os.fspath(path)))


def compare(a, b, background=(0.0, 0.0, 0.0)):
    """(SSIM, PSNR) of two images composited over a background, as ``uvr compare`` computes
    (PSNR is infinite for identical images). ``compare_report`` gives every measure."""
    r = compare_report(a, b, background)
    return r["ssim"], float("inf") if r["psnr"] is None else r["psnr"]


def compare_report(a, b, background=(0.0, 0.0, 0.0)):
    """Every measure of ``uvr compare --json`` for reference `a` and image `b` composited over a
    background, under the same keys: ``ssim``, ``ssim_channels``, ``psnr`` (None when identical)
    and the per-pixel ones, ``p999_difference`` and ``max_abs_difference`` (8-bit levels),
    ``fraction_off`` (pixels off by more than 4/255), ``seam_count``, ``seam_pixels``,
    ``longest_seam`` and ``speckle_fraction`` (docs/METHOD.md, "Evaluation tools")."""
    return _uvr.compare_images(_plain(a), _plain(b), tuple(background))


def contact_sheet(images, columns=None, gap=4, background=(1.0, 1.0, 1.0)):
    """Tiles images of one size into one Image (row-major), separated by `gap` pixels of
    `background`; a transfer-function sweep laid out for a glance."""
    images = list(images)
    if not images:
        raise _uvr.ArgumentError("contact_sheet: no images")
    h, w = images[0].shape[:2]
    for i, im in enumerate(images):
        if im.shape != (h, w, 4):
            raise _uvr.ArgumentError(f"contact_sheet: image {i} has shape {im.shape}, "
                                     f"expected {(h, w, 4)}")
    columns = columns or int(np.ceil(np.sqrt(len(images))))
    rows = (len(images) + columns - 1) // columns
    sheet = np.zeros((rows * h + (rows - 1) * gap, columns * w + (columns - 1) * gap, 4),
                     dtype=np.float32)
    sheet[..., :3] = background
    sheet[..., 3] = 1.0
    bg = np.asarray(background, dtype=np.float32)
    for i, im in enumerate(images):
        r, c = divmod(i, columns)
        tile = np.asarray(im, dtype=np.float32)
        over = tile[..., :3] + bg * (1.0 - tile[..., 3:4])  # premultiplied over the background
        sheet[r * (h + gap):r * (h + gap) + h, c * (w + gap):c * (w + gap) + w, :3] = over
    return Image(sheet)
