#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The outside-oracle test: renders real meshes with `uvr render --method exact` and with VTK's
vtkUnstructuredGridVolumeRayCastMapper (Bunyk ray casting, closed-form integration per
tetrahedron; vtk_oracle.py) under the same flags, and checks that they agree to SSIM >= 0.99
(scikit-image's SSIM on 8-bit RGB over black, computed here, not by uvr).

Usage: vtk_oracle_test.py --uvr PATH/TO/uvr --data SHARED_DATA_DIR
                          [--methods exact,reference,adaptive] [--assert-methods exact]
                          [--size 256x256] [--min-ssim 0.99] [--cases REGEX] [--keep DIR]
                          [--opacity-law attenuation|transmittance] [--truncated]
                          [--oracle-flags=...]

Cases: Blunt Fin (density) and the Oxygen Post (speed), each with two transfer functions
(tests/data/oracle/*.json: a cool-to-warm Diverging map with an opacity ramp, a black-body Lab
map with two opacity bands) and three views (ParaView's reset camera orbited with --azimuth 35
--elevation 25, each tool doing its own orbit; a ParaView .pvcc camera; the orbit in parallel
projection, --parallel, with the reset camera's parallel scale), under --opacity-law (both tools
read the transfer function's opacity by the same law; default attenuation). VTK's 8-bit frame is
unbiased (vtk_oracle.py --unbias) unless --truncated. uvr prepares each mesh once per method
(`uvr prepare`, a cache in the temporary folder) and renders each case with every method in
--methods from it; those in --assert-methods must reach --min-ssim, the others are reported.
Images go to a temporary folder removed at the end (unless --keep).

Exit status: 0 all asserted comparisons pass, 1 one fails, 77 skipped (a mesh missing from the
data folder, no VTK/scikit-image in this Python, or no X display and no xvfb-run).
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

SKIP = 77
HERE = os.path.dirname(os.path.abspath(__file__))
ORACLE_DATA = os.path.join(os.path.dirname(HERE), "data", "oracle")

# (name, mesh file, field, .pvcc view)
MESHES = [("bluntfin", "bluntfin_tets.vtk", "density", "bluntfin_oblique.pvcc"),
          ("post", "post_tets.vtk", "speed", "post_oblique.pvcc")]
TRANSFER_FUNCTIONS = ["ramp_cool_to_warm.json", "bands_lab.json"]


def views(pvcc):
    """The three views: (name, flags shared by uvr and the oracle)."""
    return [("orbit", ["--azimuth", "35", "--elevation", "25"]),
            ("pvcc", ["--camera", os.path.join(ORACLE_DATA, pvcc)]),
            ("parallel", ["--azimuth", "35", "--elevation", "25", "--parallel"])]


def skip(message):
    print(f"SKIPPED: {message}")
    sys.exit(SKIP)


def ensure_display():
    """VTK's X11 render window needs a display even off-screen: without one, run this script
    again under xvfb-run (once)."""
    if os.environ.get("DISPLAY"):
        return
    if os.environ.get("UVR_ORACLE_UNDER_XVFB"):
        skip("xvfb-run started no X display")
    xvfb = shutil.which("xvfb-run")
    if not xvfb:
        skip("no X display and no xvfb-run (Debian package xvfb)")
    os.environ["UVR_ORACLE_UNDER_XVFB"] = "1"
    sys.stdout.flush()
    os.execv(xvfb, [xvfb, "-a", sys.executable, os.path.abspath(__file__)] + sys.argv[1:])


def ssim(path_a, path_b):
    """scikit-image's SSIM of two 8-bit RGB PNGs (the parameters of tests/tools/ssim_reference.py
    and uvr compare: Gaussian window sigma 1.5, population covariance, data range 255)."""
    import numpy as np
    from PIL import Image
    from skimage.metrics import structural_similarity
    a, b = (np.asarray(Image.open(p).convert("RGB")) for p in (path_a, path_b))
    return float(structural_similarity(a, b, channel_axis=2, gaussian_weights=True, sigma=1.5,
                                       use_sample_covariance=False, data_range=255))


def prepared(uvr, mesh_path, field, method, work, caches, failures):
    """The prepared cache of (mesh, field, method), written by `uvr prepare` into work once, so
    each of the case's renders reads it instead of reading and preparing the mesh again; None
    (and a failure) when prepare fails."""
    key = (mesh_path, field, method)
    if key not in caches:
        path = os.path.join(work, f"{os.path.basename(mesh_path)}.{method}.uvrprep")
        cmd = [uvr, "-q", "prepare", mesh_path, "-o", path, "--field", field,
               "--method", method]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            failures.append(f"{' '.join(cmd)} exited {run.returncode}: {run.stderr.strip()}")
            path = None
        caches[key] = path
    return caches[key]


def main():
    parser = argparse.ArgumentParser(
        description="uvr against VTK's Bunyk ray caster on real meshes (SSIM).")
    parser.add_argument("--uvr", required=True, help="the uvr binary")
    parser.add_argument("--data", required=True, help="folder with the shared real meshes")
    parser.add_argument("--methods", default="exact",
                        help="uvr methods to render, comma-separated (default exact)")
    parser.add_argument("--assert-methods", default="exact",
                        help="methods that must reach --min-ssim (default exact)")
    parser.add_argument("--size", default="256x256", help="image size (default 256x256)")
    parser.add_argument("--min-ssim", type=float, default=0.99)
    parser.add_argument("--cases", default="", help="only cases whose name matches this regex")
    parser.add_argument("--keep", help="write the images here and keep them")
    parser.add_argument("--oracle-flags", default="",
                        help="more vtk_oracle.py flags, e.g. '--opacity-law transmittance' "
                             "(VTK's reading against uvr's other law) or '--integrator partial' "
                             "(what each convention is worth)")
    parser.add_argument("--truncated", action="store_true",
                        help="compare with VTK's 8-bit truncated frame as it is (default: the "
                             "oracle's --unbias adds the half level back)")
    parser.add_argument("--opacity-law", default="attenuation",
                        choices=["attenuation", "transmittance"],
                        help="the opacity law both tools render with (default attenuation)")
    args = parser.parse_args()
    methods = [m for m in args.methods.split(",") if m]
    asserted = {m for m in args.assert_methods.split(",") if m}

    # Step 1: what the test needs, else skip (never a silent pass).
    for _, mesh, _, _ in MESHES:
        if not os.path.isfile(os.path.join(args.data, mesh)):
            skip(f"{os.path.join(args.data, mesh)} is missing (UVR_SHARED_DATA_DIR)")
    try:
        import numpy  # noqa: F401
        import PIL  # noqa: F401
        import skimage  # noqa: F401
        import vtk  # noqa: F401
    except ImportError as e:
        skip(f"{sys.executable} cannot import {e.name} (python3-vtk9, python3-skimage, "
             "python3-pil)")
    if not os.access(args.uvr, os.X_OK):
        print(f"FAILED: {args.uvr} is not an executable")
        return 1
    ensure_display()
    sys.dont_write_bytecode = True  # no __pycache__ in the source tree
    sys.path.insert(0, HERE)
    import vtk_oracle

    # Step 2: every case, rendered by VTK once and by uvr once per method.
    work = args.keep or tempfile.mkdtemp(prefix="uvr-oracle-")
    os.makedirs(work, exist_ok=True)
    failures = []
    rows = []
    caches = {}
    started = time.monotonic()
    try:
        for name, mesh_file, field, pvcc in MESHES:
            mesh_path = os.path.join(args.data, mesh_file)
            mesh = None
            for tf in TRANSFER_FUNCTIONS:
                for view, view_flags in views(pvcc):
                    case = f"{name}/{tf[:-5]}/{view}"
                    if not re.search(args.cases, case):
                        continue
                    flags = ["--field", field, "--tf", os.path.join(ORACLE_DATA, tf),
                             "--size", args.size, "--background", "0,0,0",
                             "--opacity-law", args.opacity_law] + view_flags
                    stem = os.path.join(work, case.replace("/", "_"))
                    # VTK truncates its frame to 8 bits, half a level low on average: over
                    # the dark, translucent regions the attenuation law shows (the Post's base
                    # disk) that bias alone took SSIM to 0.983 (at most 9/255 apart, 1/255 at
                    # the 99.9th percentile), so the half level is added back (--unbias).
                    unbias = [] if args.truncated else ["--unbias"]
                    oracle_args = vtk_oracle.make_parser().parse_args(
                        [mesh_path, "-o", stem + "_vtk.png"] + flags + unbias +
                        shlex.split(args.oracle_flags))
                    t0 = time.monotonic()
                    if mesh is None:
                        mesh = vtk_oracle.load_mesh(mesh_path)
                    summary = vtk_oracle.render(oracle_args, mesh)
                    vtk_seconds = time.monotonic() - t0
                    scores = {}
                    t0 = time.monotonic()
                    for method in methods:
                        out = f"{stem}_uvr_{method}.png"
                        cache = prepared(args.uvr, mesh_path, field, method, work, caches,
                                         failures)
                        if cache is None:
                            continue
                        cmd = [args.uvr, "-q", "render", mesh_path, "-o", out,
                               "--method", method, "--cache", cache] + flags
                        run = subprocess.run(cmd, capture_output=True, text=True)
                        if run.returncode != 0:
                            failures.append(f"{case}: {' '.join(cmd)} exited {run.returncode}: "
                                            f"{run.stderr.strip()}")
                            continue
                        scores[method] = ssim(out, stem + "_vtk.png")
                        if method in asserted and not scores[method] >= args.min_ssim:
                            failures.append(f"{case}: uvr {method} against VTK: SSIM "
                                            f"{scores[method]:.4f} < {args.min_ssim}")
                    uvr_seconds = time.monotonic() - t0
                    rows.append((case, summary["knots"], vtk_seconds, scores))
                    print(f"{case:34s} knots {summary['knots']:4d}  vtk {vtk_seconds:4.1f} s  "
                          f"uvr {uvr_seconds:4.1f} s  SSIM " +
                          "  ".join(f"{m} {s:.4f}" for m, s in scores.items()), flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)

    # Step 3: the verdict, with the worst case per method.
    for method in methods:
        got = [(scores[method], case) for case, _, _, scores in rows if method in scores]
        if got:
            worst = min(got)
            print(f"worst SSIM, uvr {method} against VTK: {worst[0]:.4f} ({worst[1]})"
                  + ("" if method in asserted else " (reported, not asserted)"))
    print(f"cases: {len(rows)}, {time.monotonic() - started:.1f} s")
    if not rows:
        print("FAILED: no case matched --cases")
        return 1
    for f in failures:
        print(f"FAILED: {f}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
