# SPDX-License-Identifier: MIT
"""Scenes of the uvr Volume representation in ParaView, run by pvbatch (paraview_plugin_test.py
drives them and judges the results): each writes its screenshots and a summary.json into OUT.

    pvbatch pv_scenes.py PLUGIN DATA OUT SCENE
    (SCENE: tf_camera, settings, slice, series, errors)
"""
import json
import os
import sys

from paraview.simple import (AppendDatasets, Calculator, ColorBy, CreateView, GetAnimationScene,
                             GetColorTransferFunction, GetOpacityTransferFunction, GroupDatasets,
                             LegacyVTKReader, LoadPlugin, PassArrays, Render, SaveData,
                             SaveScreenshot, Show, Hide, Slice, Sphere, Threshold,
                             XMLUnstructuredGridReader)

PLUGIN, DATA, OUT, SCENE = sys.argv[1:5]
LoadPlugin(PLUGIN, ns=globals())
BLUNT_FIN = os.path.join(DATA, "bluntfin_tets.vtk")
summary = {}


def view(width, height, background=(0.1, 0.2, 0.3)):
    v = CreateView("RenderView")
    v.ViewSize = [width, height]
    v.OrientationAxesVisibility = 0
    v.Background = list(background)
    # ParaView 5.11 takes the background from its colour palette unless told not to.
    if hasattr(v, "UseColorPaletteForBackground"):
        v.UseColorPaletteForBackground = 0
    return v


def uvr_volume(source, v, array="density"):
    d = Show(source, v)
    d.SetRepresentationType("uvr Volume")
    ColorBy(d, ("POINTS", array))
    return d


def report(d):
    d.UpdatePropertyInformation()
    return json.loads(d.GetProperty("UvrLastFrameReport").GetElement(0))


def camera_of(v):
    c = v.GetActiveCamera()
    return {"position": list(c.GetPosition()), "focal_point": list(c.GetFocalPoint()),
            "view_up": list(c.GetViewUp()), "view_angle": c.GetViewAngle(),
            "parallel": bool(c.GetParallelProjection()), "parallel_scale": c.GetParallelScale()}


def tf_json(lut, pwf):
    """The colour map as ParaView's colour-map JSON export writes it."""
    return [{"Name": "from ParaView", "ColorSpace": lut.GetProperty("ColorSpace").GetElement(0),
             "RGBPoints": list(lut.RGBPoints), "Points": list(pwf.Points),
             "UseLogScale": int(lut.UseLogScale), "NanColor": list(lut.NanColor)}]


if SCENE == "tf_camera":
    # Two frames: a perspective view with Viridis and a custom opacity, and a parallel view
    # of the log-scaled colour map; each with what `uvr render` needs to make it again.
    reader = LegacyVTKReader(FileNames=[BLUNT_FIN])
    frames = []
    # The third frame's opacity has midpoints and sharpness other than ParaView's defaults: the
    # plugin samples it (the first two go over node for node).
    for name, parallel, log, method in (("perspective", False, False, "auto"),
                                        ("parallel_log", True, True, "exact"),
                                        ("midpoints", False, False, "reference")):
        v = view(480, 360)
        d = uvr_volume(reader, v)
        d.UvrMethod = method  # the panel's Method, a name of the vocabulary's choices
        lut = GetColorTransferFunction("density")
        pwf = GetOpacityTransferFunction("density")
        lut.ApplyPreset("Viridis (matplotlib)", True)
        lut.RescaleTransferFunction(0.2, 4.7)
        pwf.RescaleTransferFunction(0.2, 4.7)
        pwf.Points = [0.2, 0.0, 0.5, 0.0, 1.5, 0.05, 0.5, 0.0, 3.0, 0.4, 0.5, 0.0,
                      4.7, 0.9, 0.5, 0.0]
        if name == "midpoints":
            pwf.Points = [0.2, 0.0, 0.5, 0.0, 2.0, 0.1, 0.3, 0.0, 4.7, 0.8, 0.7, 0.0]
        lut.UseLogScale = 1 if log else 0
        v.ResetCamera()
        cam = v.GetActiveCamera()
        cam.Azimuth(35)
        cam.Elevation(25)
        cam.SetParallelProjection(1 if parallel else 0)
        v.CameraParallelProjection = 1 if parallel else 0
        v.ResetCamera()
        Render(v)
        png = os.path.join(OUT, name + ".png")
        SaveScreenshot(png, v)
        frames.append({"name": name, "png": png, "camera": camera_of(v),
                       "tf": tf_json(lut, pwf), "opacity_unit": d.ScalarOpacityUnitDistance,
                       "range": [lut.RGBPoints[0], lut.RGBPoints[-4]],
                       "size": [480, 360], "background": [0.1, 0.2, 0.3], "method": method,
                       "report": report(d)})
        Hide(reader, v)
    summary["frames"] = frames

elif SCENE == "settings":
    # The panel's settings and ParaView's array choices, each frame with the `uvr render` flags
    # that make it: a vector's magnitude shaded, a component clipped with the cut face drawn,
    # isosurfaces, and cell data of a mesh that has the name as point and cell data.
    frames = []
    cases = (
        ("shaded_magnitude", BLUNT_FIN, ("POINTS", "momentum"), "Magnitude", "momentum:magnitude",
         {"UvrShade": 1, "Ambient": 0.2, "Specular": 0.3},
         ["--shade", "--ambient", "0.2", "--specular", "0.3"]),
        ("clipped_component", BLUNT_FIN, ("POINTS", "momentum"), "X", "momentum:x",
         {"UvrClip": 1, "UvrClipSurface": 1},
         ["--clip-surface"]),
        ("isosurfaces", BLUNT_FIN, ("POINTS", "density"), None, "density",
         {"UvrIsoValues": [1.5, 3.0], "UvrIsoOpacity": 0.6},
         ["--iso", "1.5,0.6", "--iso", "3.0,0.6"]),
        ("cell_data", os.path.join(DATA, "cylinder_quadratic_as_tets.vtk"),
         ("CELLS", "pressure"), None, "pressure:cell", {}, []),
    )
    for name, path, array, mode, field, props, flags in cases:
        reader = LegacyVTKReader(FileNames=[path])
        v = view(400, 300)
        d = Show(reader, v)
        d.SetRepresentationType("uvr Volume")
        ColorBy(d, array)
        lut = GetColorTransferFunction(array[1])
        if mode:
            lut.VectorMode = "Magnitude" if mode == "Magnitude" else "Component"
            lut.VectorComponent = 0
        d.RescaleTransferFunctionToDataRange(False, True)
        b = reader.GetDataInformation().GetBounds()
        centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
        if "UvrClip" in props:
            d.UvrClipOrigin = centre
            d.UvrClipNormal = [0.0, 0.0, 1.0]
            flags = flags + ["--clip-plane", "%r,%r,%r,0,0,1" % tuple(centre)]
        for key, value in props.items():
            setattr(d, key, value)
        v.ResetCamera()
        v.GetActiveCamera().Azimuth(30)
        v.GetActiveCamera().Elevation(20)
        v.ResetCamera()
        Render(v)
        png = os.path.join(OUT, name + ".png")
        SaveScreenshot(png, v)
        pwf = GetOpacityTransferFunction(array[1])
        frames.append({"name": name, "png": png, "mesh": path, "field": field,
                       "flags": flags, "camera": camera_of(v), "tf": tf_json(lut, pwf),
                       "opacity_unit": d.ScalarOpacityUnitDistance,
                       "range": [lut.RGBPoints[0], lut.RGBPoints[-4]], "size": [400, 300],
                       "background": [0.1, 0.2, 0.3], "method": "auto", "report": report(d)})
        Hide(reader, v)
    summary["frames"] = frames

elif SCENE == "slice":
    # An opaque slice through the middle of the volume, seen at an angle: where it is in front
    # it shows, behind it the volume; the volume alone and the slice alone for the judge.
    reader = LegacyVTKReader(FileNames=[BLUNT_FIN])
    v = view(400, 300, (0.0, 0.0, 0.0))
    d = uvr_volume(reader, v)
    lut = GetColorTransferFunction("density")
    lut.ApplyPreset("Cool to Warm", True)
    b = reader.GetDataInformation().GetBounds()
    centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
    s = Slice(Input=reader)
    s.SliceType.Origin = centre
    s.SliceType.Normal = [0.0, 0.0, 1.0]
    sd = Show(s, v)
    ColorBy(sd, None)
    sd.AmbientColor = sd.DiffuseColor = [1.0, 0.6, 0.1]
    # Translucent geometry beside the volume: VTK would render volumes inside its depth
    # peeling passes then, unless told not to.
    ball = Sphere(Center=[b[1] + 2.0, centre[1], centre[2]], Radius=1.5)
    bd = Show(ball, v)
    bd.Opacity = 0.4
    v.ResetCamera()
    v.GetActiveCamera().Azimuth(20)
    v.GetActiveCamera().Elevation(30)
    v.ResetCamera()
    Render(v)
    SaveScreenshot(os.path.join(OUT, "both.png"), v)
    Hide(s, v)
    Render(v)
    SaveScreenshot(os.path.join(OUT, "volume.png"), v)
    Show(s, v)
    Hide(reader, v)
    Render(v)
    SaveScreenshot(os.path.join(OUT, "slice.png"), v)
    summary.update({"camera": camera_of(v), "tf": tf_json(lut, GetOpacityTransferFunction(
        "density")), "opacity_unit": d.ScalarOpacityUnitDistance, "plane": centre,
        "range": [lut.RGBPoints[0], lut.RGBPoints[-4]], "size": [400, 300]})

elif SCENE == "series":
    # Three steps of the same geometry (density times 1, 2, 3) as .vtu files, stepped through:
    # the values change, the preparation is not repeated.
    reader = LegacyVTKReader(FileNames=[BLUNT_FIN])
    files = []
    for k in range(3):
        calc = Calculator(Input=reader, ResultArrayName="f", Function="density*%d" % (k + 1))
        path = os.path.join(OUT, "step_%d.vtu" % k)
        SaveData(path, proxy=calc)
        files.append(path)
    series = XMLUnstructuredGridReader(FileName=files)
    v = view(256, 256)
    d = uvr_volume(series, v, "f")
    GetColorTransferFunction("f").AutomaticRescaleRangeMode = "Never"
    GetColorTransferFunction("f").RescaleTransferFunction(0.2, 14.0)
    GetOpacityTransferFunction("f").RescaleTransferFunction(0.2, 14.0)
    v.ResetCamera()
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    steps = []
    for t in series.TimestepValues:
        scene.AnimationTime = t
        Render(v)
        png = os.path.join(OUT, "t%d.png" % len(steps))
        SaveScreenshot(png, v)
        r = report(d)
        steps.append({"time": t, "png": png, "prepare_seconds": r.get("prepare_seconds"),
                      "samples": r.get("samples"), "error": r.get("error")})
    summary["steps"] = steps

elif SCENE == "errors":
    # Inputs uvr cannot render: each must give a ParaView error, never a crash, and leave
    # ParaView rendering what it can.
    reader = LegacyVTKReader(FileNames=[BLUNT_FIN])
    cases = {}
    # 1. No scalar array to render.
    bare = PassArrays(Input=reader, PointDataArrays=[], CellDataArrays=[])
    v = view(128, 128)
    d = Show(bare, v)
    d.SetRepresentationType("uvr Volume")
    v.ResetCamera()
    Render(v)
    cases["no_array"] = report(d)
    # 2. Only 2D cells (a sphere's triangles as an unstructured grid).
    tris = AppendDatasets(Input=[Calculator(Input=Sphere(), ResultArrayName="f",
                                            Function="coordsX")])
    v = view(128, 128)
    d = uvr_volume(tris, v, "f")
    v.ResetCamera()
    Render(v)
    cases["no_volume_cells"] = report(d)
    # CUDA asked for: an error naming it where no GPU can be used, else a CUDA frame.
    v = view(128, 128)
    d = uvr_volume(reader, v)
    d.UvrDevice = "cuda"
    v.ResetCamera()
    Render(v)
    cases["cuda"] = report(d)
    # 3. A polydata input: no uvr Volume representation is offered.
    v = view(128, 128)
    d = Show(Sphere(), v)
    cases["polydata_offers"] = "uvr Volume" in d.Representation.Available
    # 4. A multiblock data set with an empty block beside the Blunt Fin: the Blunt Fin renders.
    empty = Threshold(Input=reader, Scalars=["POINTS", "density"], LowerThreshold=1e9,
                      UpperThreshold=2e9)
    group = GroupDatasets(Input=[reader, empty])
    v = view(128, 128)
    d = uvr_volume(group, v)
    v.ResetCamera()
    Render(v)
    png = os.path.join(OUT, "multiblock.png")
    SaveScreenshot(png, v)
    cases["multiblock"] = report(d)
    cases["multiblock_png"] = png
    summary["cases"] = cases
else:
    raise SystemExit("pv_scenes.py: unknown scene " + SCENE)

with open(os.path.join(OUT, "summary.json"), "w") as f:
    json.dump(summary, f, indent=1)
print("pv_scenes: %s done" % SCENE)
