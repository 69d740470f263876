#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Prints the rows of uvr's built-in colour presets (src/uvr/tf/presets.cpp) from a ParaView
ColorMaps.json (ParaView's Remoting/Views/ColorMaps.json; its "Export presets" files have the
same layout). Run it with Debian's /usr/bin/python3:

  scripts/paraview_presets.py ColorMaps.json > /tmp/rows.inc

Maps of at most 64 control points are written as ParaView has them. Larger ones (Turbo and the
matplotlib maps, 256 points each) are subsampled greedily: a run of points is dropped while
interpolating between its ends in the map's colour space stays within TOLERANCE of ParaView's
full map at 4096 positions and at every one of its points (the same sRGB <-> CIE L*a*b* formulas as
src/uvr/tf/transfer_function.cpp)."""

import json
import math
import re
import sys

# Largest difference per sRGB component between a subsampled map and ParaView's full map (the
# test allows 0.5 / 255: the rest is float rounding in uvr's evaluation).
TOLERANCE = 0.45 / 255

# uvr name (ParaView's), the name in ColorMaps.json (ParaView 6 dropped "(matplotlib)").
PRESETS = [
    ("Cool to Warm", "Cool to Warm"),
    ("Cool to Warm (Extended)", "Cool to Warm (Extended)"),
    ("Warm to Cool", "Warm to Cool"),
    ("Warm to Cool (Extended)", "Warm to Cool (Extended)"),
    ("Black-Body Radiation", "Black-Body Radiation"),
    ("X Ray", "X Ray"),
    ("Grayscale", "Grayscale"),
    ("Inferno (matplotlib)", "Inferno"),
    ("Magma (matplotlib)", "Magma"),
    ("Plasma (matplotlib)", "Plasma"),
    ("Viridis (matplotlib)", "Viridis"),
    ("Cividis", "Cividis"),
    ("Turbo", "Turbo"),
    ("Jet", "Jet"),
    ("Rainbow Uniform", "Rainbow Uniform"),
    ("Rainbow Desaturated", "Rainbow Desaturated"),
    ("Blue to Red Rainbow", "Blue to Red Rainbow"),
    ("Blue Orange (divergent)", "Blue Orange (divergent)"),
    ("Blue - Green - Orange", "Blue - Green - Orange"),
    ("Cold and Hot", "Cold and Hot"),
    ("Yellow - Gray - Blue", "Yellow - Gray - Blue"),
    ("Linear Green (Gr4L)", "Linear Green (Gr4L)"),
    ("Black, Blue and White", "Black, Blue and White"),
    ("Black, Orange and White", "Black, Orange and White"),
    ("erdc_rainbow_bright", "erdc_rainbow_bright"),
    ("Spectral_lowBlue", "Spectral_lowBlue"),
    ("gist_earth", "gist_earth"),
    ("Haze", "Haze"),
    ("Fast", "Fast"),
]

WHITE = (0.9505, 1.0, 1.089)


def to_linear(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def from_linear(c):
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def lab_f(t):
    return t ** (1 / 3) if t > 0.008856 else 7.787 * t + 16 / 116


def lab_f_inv(f):
    t = f ** 3
    return t if t > 0.008856 else (f - 16 / 116) / 7.787


def to_lab(rgb):
    r, g, b = (to_linear(c) for c in rgb)
    x = 0.4124 * r + 0.3576 * g + 0.1805 * b
    y = 0.2126 * r + 0.7152 * g + 0.0722 * b
    z = 0.0193 * r + 0.1192 * g + 0.9505 * b
    fx, fy, fz = lab_f(x / WHITE[0]), lab_f(y / WHITE[1]), lab_f(z / WHITE[2])
    return (116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz))


def from_lab(lab):
    fy = (lab[0] + 16) / 116
    fx, fz = fy + lab[1] / 500, fy - lab[2] / 200
    x, y, z = WHITE[0] * lab_f_inv(fx), WHITE[1] * lab_f_inv(fy), WHITE[2] * lab_f_inv(fz)
    r = 3.2406 * x - 1.5372 * y - 0.4986 * z
    g = -0.9689 * x + 1.8758 * y + 0.0415 * z
    b = 0.0557 * x - 0.2040 * y + 1.0570 * z
    return tuple(min(1.0, max(0.0, from_linear(c))) for c in (r, g, b))


def mix(space, a, b, f):
    if space == "Lab":
        la, lb = to_lab(a), to_lab(b)
        return from_lab(tuple(p + f * (q - p) for p, q in zip(la, lb)))
    return tuple(p + f * (q - p) for p, q in zip(a, b))


def color_at(space, pts, t):
    if t <= pts[0][0]:
        return pts[0][1]
    for (x0, c0), (x1, c1) in zip(pts, pts[1:]):
        if x0 <= t < x1:
            return mix(space, c0, c1, (t - x0) / (x1 - x0))
    return pts[-1][1]


def subsample(space, pts):
    """Greedy: from each kept point, the farthest next point whose chord stays in tolerance."""
    probes = sorted(set([i / 4095 for i in range(4096)] + [x for x, _ in pts]))
    full = {t: color_at(space, pts, t) for t in probes}
    kept = [0]
    while kept[-1] < len(pts) - 1:
        i = kept[-1]
        j = i + 1
        while j + 1 < len(pts):
            trial = [pts[i], pts[j + 1]]
            inside = [t for t in probes if pts[i][0] <= t <= pts[j + 1][0]]
            if all(max(abs(p - q) for p, q in zip(color_at(space, trial, t), full[t])) <= TOLERANCE
                   for t in inside):
                j += 1
            else:
                break
        kept.append(j)
    return [pts[k] for k in kept]


def literal(v):
    """A C++ float literal of v as ParaView writes it (the shortest repr of the double)."""
    s = repr(float(v))
    return s + ("f" if "." in s or "e" in s else ".f")


def main():
    text = open(sys.argv[1]).read()
    maps = {m["Name"]: m for m in json.loads(re.sub(r",\s*\]\s*$", "]", text))}
    for name, source in PRESETS:
        m = maps[source]
        raw = m["RGBPoints"]
        lo, hi = raw[0], raw[-4]
        pts = [((raw[i] - lo) / (hi - lo), tuple(raw[i + 1:i + 4])) for i in range(0, len(raw), 4)]
        space = {"CIELAB": "Lab"}.get(m.get("ColorSpace", "RGB"), m.get("ColorSpace", "RGB"))
        count = len(pts)
        if count > 64:
            pts = subsample(space, pts)
        nan = m.get("NanColor", [1, 1, 0])
        ident = "k" + re.sub(r"[^A-Za-z0-9]", "", name.title())
        print(f"// ParaView's \"{source}\": {count} points" +
              (f", {len(pts)} kept (within {TOLERANCE * 255:.2f}/255)" if len(pts) < count else ""))
        print(f"constexpr PresetPoint {ident}[] = {{")
        row = ", ".join("{" + ", ".join(literal(v) for v in (x,) + c) + "}" for x, c in pts)
        print("    " + row)
        print("};")
        print(f"// {{\"{name}\", \"{space}\", {{{', '.join(literal(v) for v in nan)}}}, {ident}}},")


if __name__ == "__main__":
    main()
