# SPDX-License-Identifier: MIT
"""Still-render time in ParaView (pvbatch) of the uvr Volume representation against ParaView's
own "Volume" mappers, on the same data set, colour map and view (docs/PERFORMANCE.md).

    PYTHONPATH=/opt/uvr/python3-paraview/usr/lib/python3/dist-packages \\
      xvfb-run -a pvbatch bench/paraview_volume.py PLUGIN FILE[:ARRAY]... [--size 1024] [--repeat 3]

Per data set and renderer: the first frame (ParaView's update plus the renderer's preparation)
and the median of --repeat frames after it, each after a 10-degree turn of the camera.
"""
import argparse
import json
import statistics
import time

from paraview.simple import (ColorBy, CreateView, Delete, GetColorTransferFunction, LoadPlugin,
                             OpenDataFile, Render, SaveScreenshot, Show)

ap = argparse.ArgumentParser()
ap.add_argument("plugin")
ap.add_argument("files", nargs="+", help="FILE or FILE:ARRAY (default: the first point array)")
ap.add_argument("--size", type=int, default=1024)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--images", help="also save each renderer's last frame into this folder "
                "(compare them with `uvr compare`, e.g. against uvr Volume with Method exact)")
ap.add_argument("--method", default="auto", help="uvr Volume's Method")
ap.add_argument("--mappers", default="uvr Volume,Projected tetra,Z sweep,Bunyk ray cast,"
                "Resample To Image")
args = ap.parse_args()
LoadPlugin(args.plugin, ns=globals())

print("| data set | renderer | first frame (s) | still frame (s, median of %d) | of which uvr's "
      "frame (s) |" % args.repeat)
print("|---|---|---:|---:|---:|")
for spec in args.files:
    path, _, chosen = spec.partition(":")
    for mapper in args.mappers.split(","):
        reader = OpenDataFile(path)
        v = CreateView("RenderView")
        v.ViewSize = [args.size, args.size]
        v.OrientationAxesVisibility = 0
        d = Show(reader, v)
        array = chosen or reader.PointData.keys()[0]
        if mapper == "uvr Volume":
            d.SetRepresentationType("uvr Volume")
            d.UvrMethod = args.method
        else:
            d.SetRepresentationType("Volume")
            d.SelectMapper = mapper
        ColorBy(d, ("POINTS", array))
        GetColorTransferFunction(array).ApplyPreset("Cool to Warm", True)
        v.ResetCamera()
        t0 = time.perf_counter()
        Render(v)
        first = time.perf_counter() - t0
        times, own = [], []
        for _ in range(args.repeat):
            v.GetActiveCamera().Azimuth(10)
            t0 = time.perf_counter()
            Render(v)
            times.append(time.perf_counter() - t0)
            if mapper == "uvr Volume":  # the library's own time for the frame (its report)
                d.UpdatePropertyInformation()
                report = json.loads(d.GetProperty("UvrLastFrameReport").GetElement(0))
                own.append(report["render_seconds"])
        if args.images:
            SaveScreenshot("%s/%s_%s.png" % (args.images, path.split("/")[-1].split(".")[0],
                                             mapper.replace(" ", "_")), v)
        print("| %s (%s) | %s | %.2f | %.3f | %s |" % (
            path.split("/")[-1], array, mapper, first, statistics.median(times),
            "%.3f" % statistics.median(own) if own else ""), flush=True)
        Delete(d)
        Delete(v)
        Delete(reader)
