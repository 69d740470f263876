#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The ParaView plugin end to end (ctest paraview.plugin): pvbatch on an Xvfb display loads the plugin
and renders the scenes of pv_scenes.py; this script judges them.

- tf_camera: the Blunt Fin with a ParaView colour map, opacity and camera (perspective; parallel
  with a log-scaled map and the exact method; opacity midpoints and sharpness, which the plugin
  samples) equals `uvr render` given that colour map (exported as ParaView's colour-map JSON)
  and camera: SSIM >= 0.99 and no pixel off by more than 4 levels.
- settings: the panel's Shade (with the Lighting group's Ambient and Specular), Clip with Clip
  Surface, Isosurfaces, a vector's Magnitude and X component, and cell data: each equals
  `uvr render` with the matching flags and field.
- slice: an opaque slice through the volume: inside it, the picture is uvr's rendering of the
  volume in front of the slice's plane (a clip plane) over the slice alone; outside it, the
  volume alone.
- series: three time steps of one geometry: the pictures change, the preparation is not redone.
- errors: no array, only 2D cells, CUDA asked for without a GPU, a polydata input, a multiblock
  data set with an empty block:
  ParaView errors naming the problem, no crash, the Blunt Fin block still rendered.
Exit 77 (skipped) when the shared data is missing.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from matplotlib import image as mpimg

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def start_xvfb():
    """One X server for every scene, on a display it picks itself (-displayfd): `xvfb-run -a`
    races other tests that start X servers at the same moment (ctest -j). -noreset: by default the
    server resets when its last client leaves, and a pvbatch connecting during the reset fails
    ("bad X server connection"), as it did under ctest -j2 in CI."""
    read, write = os.pipe()
    server = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1024x768x24",
                               "-nolisten", "tcp", "-noreset"], pass_fds=(write,),
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write)
    number = b""
    while not number.endswith(b"\n"):
        chunk = os.read(read, 16)
        if not chunk:
            break
        number += chunk
    os.close(read)
    if not number.strip():
        server.kill()
        raise SystemExit("paraview_plugin_test: Xvfb did not start")
    return server, ":" + number.decode().strip()


def run_scene(args, scene, out):
    os.makedirs(out, exist_ok=True)
    env = dict(os.environ, DISPLAY=args.display)
    if args.pythonpath:
        env["PYTHONPATH"] = args.pythonpath + os.pathsep + env.get("PYTHONPATH", "")
    cmd = [args.pvbatch, os.path.join(os.path.dirname(os.path.abspath(__file__)), "pv_scenes.py"),
           args.plugin, args.data, out, scene]
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    log = p.stdout + p.stderr
    check(p.returncode == 0, "pvbatch %s exits 0 (got %d)" % (scene, p.returncode))
    if p.returncode != 0:
        print(log[-3000:])
        return None, log
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f), log


def rgb(path):
    """An image as float RGB in [0, 1] (alpha dropped)."""
    return mpimg.imread(path)[:, :, :3].astype(np.float64)


def uvr_render(args, out_png, tf, frame, extra):
    tf_path = out_png + ".tf.json"
    with open(tf_path, "w") as f:
        json.dump(tf, f)
    cam = frame["camera"]
    cmd = [args.uvr, "-q", "render",
           frame.get("mesh", os.path.join(args.data, "bluntfin_tets.vtk")), "-o", out_png,
           "--field", frame.get("field", "density"), "--tf", tf_path,
           "--range", "%r,%r" % tuple(frame["range"]),
           "--size", "%dx%d" % tuple(frame["size"]),
           "--camera-position", ",".join(repr(x) for x in cam["position"]),
           "--camera-focal", ",".join(repr(x) for x in cam["focal_point"]),
           "--camera-up", ",".join(repr(x) for x in cam["view_up"]),
           "--opacity-unit", repr(frame["opacity_unit"])] + extra
    if cam["parallel"]:
        cmd += ["--parallel", "--parallel-scale", repr(cam["parallel_scale"])]
    else:
        cmd += ["--view-angle", repr(cam["view_angle"])]
    subprocess.run(cmd, check=True)


def compare(args, a, b, background):
    p = subprocess.run([args.uvr, "compare", a, b, "--json", "--background",
                        ",".join(map(str, background))], capture_output=True, text=True,
                       check=True)
    return json.loads(p.stdout)


def tf_camera(args, out):
    summary, _ = run_scene(args, "tf_camera", out)
    if not summary:
        return
    for frame in summary["frames"]:
        check("error" not in frame["report"], "%s: the frame renders" % frame["name"])
        if frame["method"] != "auto":
            check(frame["report"].get("method") == frame["method"],
                  "%s: the panel's Method %s reaches the renderer (report: %s)"
                  % (frame["name"], frame["method"], frame["report"].get("method")))
        mine = os.path.join(out, frame["name"] + "_uvr.png")
        uvr_render(args, mine, frame["tf"], frame,
                   ["--background", ",".join(map(str, frame["background"])),
                    "--method", frame["method"]])
        m = compare(args, mine, frame["png"], frame["background"])
        print("      %s: SSIM %.4f, 99.9th percentile %s, max %s (8-bit levels)" %
              (frame["name"], m["ssim"], m["p999_difference"], m["max_abs_difference"]))
        check(m["ssim"] >= 0.99, "%s: ParaView's picture equals uvr render's (SSIM %.4f >= 0.99)"
              % (frame["name"], m["ssim"]))
        # Node for node (ParaView's default midpoints and sharpness) the two transfer functions
        # are one; the midpoints frame's is sampled at 1024 values (measured: max 10 levels,
        # 99.9th percentile 4).
        worst = 4 if frame["name"] != "midpoints" else 16
        check(m["max_abs_difference"] <= worst, "%s: its worst pixel is off by %s <= %d levels"
              % (frame["name"], m["max_abs_difference"], worst))


def settings(args, out):
    summary, _ = run_scene(args, "settings", out)
    if not summary:
        return
    for frame in summary["frames"]:
        check("error" not in frame["report"], "%s: the frame renders (%s)"
              % (frame["name"], frame["report"].get("error", "")))
        mine = os.path.join(out, frame["name"] + "_uvr.png")
        uvr_render(args, mine, frame["tf"], frame,
                   ["--background", ",".join(map(str, frame["background"]))] + frame["flags"])
        m = compare(args, mine, frame["png"], frame["background"])
        print("      %s: SSIM %.4f, 99.9th percentile %s, max %s (8-bit levels)" %
              (frame["name"], m["ssim"], m["p999_difference"], m["max_abs_difference"]))
        check(m["ssim"] >= 0.99 and m["max_abs_difference"] <= 4,
              "%s: ParaView's picture equals uvr render %s's (SSIM %.4f >= 0.99, max %s <= 4)"
              % (frame["name"], " ".join(frame["flags"]) or "--field " + frame["field"],
                 m["ssim"], m["max_abs_difference"]))


def slice_scene(args, out):
    summary, _ = run_scene(args, "slice", out)
    if not summary:
        return
    both, volume, slc = (rgb(os.path.join(out, n + ".png")) for n in ("both", "volume", "slice"))
    covered = slc.max(axis=2) > 0.02  # the slice covers these pixels (black elsewhere)
    # Its inside: 2 pixels in from its edge, where the rasterised slice and the volume's
    # boundary cover pixels differently.
    mask = covered.copy()
    near = covered.copy()  # the slice and 2 pixels around it
    for dy in (-2, -1, 0, 1, 2):
        for dx in (-2, -1, 0, 1, 2):
            shifted = np.roll(np.roll(covered, dy, axis=0), dx, axis=1)
            mask &= shifted
            near |= shifted
    check(mask.mean() > 0.05, "the slice covers part of the view (%.1f%%)" % (100 * mask.mean()))
    # The volume in front of the plane: the side of it the camera is on.
    plane = summary["plane"]
    side = 1.0 if summary["camera"]["position"][2] > plane[2] else -1.0
    front = os.path.join(out, "front_uvr.png")
    frame = dict(summary, size=summary["size"])
    uvr_render(args, front, summary["tf"], frame,
               ["--clip-plane", "%r,%r,%r,0,0,%r" % (plane[0], plane[1], plane[2], side)])
    rgba = mpimg.imread(front).astype(np.float64)  # straight alpha
    expected = rgba[:, :, :3] * rgba[:, :, 3:] + (1 - rgba[:, :, 3:]) * slc
    diff_in = np.abs(both - expected).max(axis=2)[mask] * 255
    diff_out = np.abs(both - volume).max(axis=2)[~near] * 255
    shown = np.abs(both - volume).max(axis=2)[mask] * 255
    print("      inside the slice: max %.1f, 99.9th percentile %.1f (8-bit levels); outside: "
          "max %.1f" % (diff_in.max(), np.percentile(diff_in, 99.9), diff_out.max()))
    check(np.percentile(diff_in, 99.9) <= 6,
          "inside the slice: the volume in front of it over the slice (99.9th percentile %.1f "
          "<= 6)" % np.percentile(diff_in, 99.9))
    check(np.median(shown) > 20, "the slice shows: it changes the picture where it lies "
          "(median %.0f levels)" % np.median(shown))
    check(diff_out.max() <= 1, "outside the slice: the volume alone (max %.1f <= 1)"
          % diff_out.max())


def series(args, out):
    summary, _ = run_scene(args, "series", out)
    if not summary:
        return
    steps = summary["steps"]
    check(len(steps) == 3, "three time steps (%d)" % len(steps))
    check(all(s["error"] is None for s in steps), "every step renders")
    check(all(s["prepare_seconds"] == steps[0]["prepare_seconds"] for s in steps),
          "the geometry is prepared once: the later steps only take new values")
    images = [rgb(s["png"]) for s in steps]
    d01 = np.abs(images[0] - images[1]).max() * 255
    d12 = np.abs(images[1] - images[2]).max() * 255
    check(d01 > 10 and d12 > 10, "each step's picture differs (%.0f, %.0f levels)" % (d01, d12))


def errors(args, out):
    summary, log = run_scene(args, "errors", out)
    if not summary:
        return
    cases = summary["cases"]
    check("no array to render" in cases["no_array"].get("error", ""),
          "no array: %r" % cases["no_array"].get("error"))
    check("no volume cells" in cases["no_volume_cells"].get("error", ""),
          "only 2D cells: %r" % cases["no_volume_cells"].get("error"))
    check(log.count("uvr Volume: no array to render") == 1,
          "the error reaches ParaView's output once, not at every frame")
    cuda = cases["cuda"]
    if "error" in cuda:
        check("CUDA" in cuda["error"] or "cuda" in cuda["error"],
              "Device cuda without a GPU: %r" % cuda["error"])
    else:
        check(cuda.get("device") == "cuda", "Device cuda renders there (%s)" % cuda.get("device"))
    check(cases["polydata_offers"] is False, "a polydata input is not offered uvr Volume")
    check("error" not in cases["multiblock"], "a multiblock data set with an empty block renders")
    img = rgb(cases["multiblock_png"])
    check((np.abs(img - np.array([0.1, 0.2, 0.3])).max(axis=2) > 0.05).mean() > 0.05,
          "the Blunt Fin block shows")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pvbatch", default="pvbatch")
    ap.add_argument("--plugin", required=True, help="UvrVolume.so")
    ap.add_argument("--uvr", required=True, help="the uvr CLI")
    ap.add_argument("--data", required=True, help="../shared/data")
    ap.add_argument("--pythonpath", default="", help="python3-paraview's files for pvbatch")
    ap.add_argument("--out", help="keep the pictures here (default: a temporary folder)")
    args = ap.parse_args()
    if not os.path.exists(os.path.join(args.data, "bluntfin_tets.vtk")):
        print("skipped: no %s/bluntfin_tets.vtk" % args.data)
        return 77
    server, args.display = start_xvfb()
    try:
        with tempfile.TemporaryDirectory(prefix="uvr_paraview_") as tmp:
            out = args.out or tmp
            for name, fn in (("tf_camera", tf_camera), ("settings", settings),
                             ("slice", slice_scene), ("series", series), ("errors", errors)):
                fn(args, os.path.join(out, name))
    finally:
        server.terminate()
        server.wait()
    if failures:
        print("%d check(s) failed" % len(failures))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
