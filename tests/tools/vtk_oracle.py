#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Renders an unstructured volume with VTK's vtkUnstructuredGridVolumeRayCastMapper (Bunyk,
Kaufman and Silva 1997: rays walk from tetrahedron to tetrahedron across faces; each segment is
integrated in closed form by vtkUnstructuredGridLinearRayIntegrator, Williams, Max and Stein
1998), an oracle from outside uvr for `uvr render --method exact`. Same flags as `uvr render`:

  vtk_oracle.py MESH -o OUT.png --tf MAP.json [--field NAME] [--range LO,HI]
                [--opacity-unit U] [--camera FILE.pvcc | --camera-position X,Y,Z
                --camera-focal X,Y,Z] [--camera-up X,Y,Z] [--view-angle DEG]
                [--parallel] [--parallel-scale S] [--azimuth DEG] [--elevation DEG]
                [--size WxH] [--background R,G,B] [--opacity-law attenuation|transmittance]

Run it with Debian's /usr/bin/python3 (python3-vtk9, numpy). VTK 9.1's X11 render window needs
an X display even off-screen: where there is none, run it under `xvfb-run -a`.

How it matches uvr's conventions (docs/TRANSFER_FUNCTIONS.md, docs/METHOD.md "Exact
integration", src/uvr/render/camera.cpp, src/uvr/tf/paraview_json.cpp):
- transfer function: a ParaView colour-map JSON. RGBPoints and Points positions are normalised
  over [first, last] RGBPoints x and stretched over the value range (default: the field's
  range); values beyond the range take the ends' colour and opacity. Colours are interpolated in
  the JSON's ColorSpace (RGB, Lab, Diverging, HSV) by vtkColorTransferFunction.
- opacity: an opacity alpha applies per --opacity-unit u (ParaView's ScalarOpacityUnitDistance,
  the same default) under uvr's --opacity-law: attenuation (the default) is the extinction
  alpha / u, VTK's unstructured integrators' own reading (linear between control points);
  transmittance is -ln(1 - alpha) / u, so the oracle then hands VTK -ln(1 - alpha(x)) as its
  "opacity". Either way the emission is colour * extinction, and the function goes to VTK on
  knots dense enough for linear interpolation. The colour goes to VTK at the same knots: its
  integrators split segments only at the colour function's control points and read the opacity
  function only there (see resample).
- mesh: other cells are split into tetrahedra; zero-volume tetrahedra are dropped, as uvr does
  (the Bunyk caster loses the rays that meet one).
- camera: a .pvcc file (position, focal point, view up, vertical view angle, and its parallel
  projection and scale), or position and focal point, or VTK's ResetCamera (ParaView's, which
  uvr mimics); then vtkCamera's Azimuth and Elevation. uvr casts one ray through each pixel centre; the mapper's rays and the texture
  that shows them are laid out differently, so VTK's projection is adapted (see ray_grid and
  set_camera) to cast exactly uvr's rays.
- image: premultiplied colour composited over --background (default black) into 8-bit RGB,
  rounded. The oracle renders over transparent black, reads the mapper's premultiplied RGBA
  back and composites it itself.

Residual differences that remain: the mapper truncates its premultiplied RGBA to 8 bits before
compositing (uvr rounds once, after; --unbias adds the half level back on average), stops a ray
once its opacity reaches 0.99 (uvr: 1 - 1e-6), and integrates in float.
"""
import argparse
import json
import math
import os
import sys
import xml.etree.ElementTree as ElementTree

import numpy as np
import vtk
from vtkmodules.util import numpy_support


def fail(message):
    """Exits with status 2 and a message naming what was wrong."""
    sys.stderr.write(f"vtk_oracle: {message}\n")
    sys.exit(2)


def parse_floats(text, count, flag):
    """count comma-separated finite numbers, or an error naming the flag."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        fail(f"{flag} '{text}': expected {count} finite comma-separated numbers")
    return values


def parse_size(text):
    """WIDTHxHEIGHT as two positive integers."""
    parts = text.lower().split("x")
    if len(parts) != 2 or not all(p.isdigit() and int(p) > 0 for p in parts):
        fail(f"--size '{text}': expected WIDTHxHEIGHT, e.g. 256x256")
    return int(parts[0]), int(parts[1])


# Step 1: the mesh and its field ------------------------------------------------------------


def load_mesh(path):
    """Reads a legacy .vtk or XML .vtu unstructured grid with all its arrays, as tetrahedra: the
    Bunyk caster walks only tetrahedra, so other 3D cells are split by vtkDataSetTriangleFilter
    (a hexahedron's trilinear field then becomes linear per tetrahedron, which need not match
    another renderer's split); zero-volume tetrahedra are dropped. Returns the grid and ParaView's
    default opacity unit distance of the mesh as read."""
    if not os.path.isfile(path):
        fail(f"{path}: no such file")
    if path.endswith(".vtu"):
        reader = vtk.vtkXMLUnstructuredGridReader()
    else:
        reader = vtk.vtkUnstructuredGridReader()
        reader.ReadAllScalarsOn()
        reader.ReadAllVectorsOn()
        reader.ReadAllFieldsOn()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    if grid is None or grid.GetNumberOfCells() == 0:
        fail(f"{path}: no unstructured grid cells read")
    types = vtk.vtkCellTypes()
    grid.GetCellTypes(types)
    if any(types.GetCellType(i) != vtk.VTK_TETRA for i in range(types.GetNumberOfTypes())):
        sys.stderr.write(f"vtk_oracle: {path}: splitting non-tetrahedral cells into "
                         "tetrahedra (vtkDataSetTriangleFilter)\n")
        split = vtk.vtkDataSetTriangleFilter()
        split.SetInputData(grid)
        split.TetrahedraOnlyOn()
        split.Update()
        grid = split.GetOutput()
    return drop_zero_volume(grid), paraview_unit_distance(reader.GetOutput())


def drop_zero_volume(grid):
    """The grid without its zero-volume tetrahedra (|6V| below 1e-7 of the longest edge cubed,
    uvr's criterion), which contribute nothing to an image: uvr leaves them out, and the Bunyk
    caster loses a ray that meets one (Blunt Fin has 77)."""
    points = numpy_support.vtk_to_numpy(grid.GetPoints().GetData()).astype(np.float64)
    tets = numpy_support.vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    corners = points[tets]
    edges = corners[:, 1:] - corners[:, :1]
    six_volume = np.abs(np.linalg.det(edges))
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    longest = np.max([np.linalg.norm(corners[:, i] - corners[:, j], axis=1) for i, j in pairs],
                     axis=0)
    keep = np.nonzero(six_volume >= 1e-7 * longest ** 3)[0]
    if len(keep) == len(tets):
        return grid
    ids = vtk.vtkIdList()
    for i in keep:
        ids.InsertNextId(int(i))
    extract = vtk.vtkExtractCells()
    extract.SetInputData(grid)
    extract.SetCellList(ids)
    extract.Update()
    return extract.GetOutput()


def select_field(grid, name):
    """The named one-component point array (default: the active scalars, else the first
    one-component point array) and its range."""
    data = grid.GetPointData()
    if name is None:
        arrays = [data.GetScalars()] + [data.GetArray(i) for i in range(data.GetNumberOfArrays())]
        scalars = [a for a in arrays if a is not None and a.GetNumberOfComponents() == 1]
        if not scalars:
            fail("the mesh has no one-component point array")
        array = scalars[0]
    else:
        array = data.GetArray(name)
        if array is None:
            known = [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]
            cell = grid.GetCellData().GetArray(name) is not None
            fail(f"no point array '{name}'" +
                 (" (it is cell data, which the oracle does not render)" if cell else "") +
                 f"; point arrays: {', '.join(known)}")
    if array.GetNumberOfComponents() != 1:
        fail(f"point array '{array.GetName()}' has {array.GetNumberOfComponents()} "
             "components; expected a scalar")
    return array.GetName(), array.GetRange(0)


def paraview_unit_distance(grid):
    """ParaView's default ScalarOpacityUnitDistance: bounds diagonal / cbrt(cell count)."""
    b = grid.GetBounds()
    diagonal = math.sqrt(sum((b[2 * i + 1] - b[2 * i]) ** 2 for i in range(3)))
    return diagonal / grid.GetNumberOfCells() ** (1.0 / 3.0)


# Step 2: the transfer function -------------------------------------------------------------


def load_colour_map(path):
    """The first colour map of a ParaView JSON export: (ColorSpace, RGBPoints, Points), with
    Points defaulting to a linear ramp from 0 to 1 over the RGBPoints' span, as in uvr."""
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")
    cmap = doc[0] if isinstance(doc, list) and doc else doc
    if not isinstance(cmap, dict) or "RGBPoints" not in cmap:
        fail(f"{path}: expected a colour-map object with RGBPoints")
    rgb = [float(v) for v in cmap["RGBPoints"]]
    if not rgb or len(rgb) % 4:
        fail(f"{path}: RGBPoints must hold x, r, g, b per point")
    points = [float(v) for v in cmap.get("Points", [])]
    if len(points) % 4:
        fail(f"{path}: Points must hold x, opacity, midpoint, sharpness per point")
    if not points:
        points = [rgb[0], 0.0, 0.5, 0.0, rgb[-4], 1.0, 0.5, 0.0]
    return cmap.get("ColorSpace", "RGB"), rgb, points


def build_colour(space, rgb, to_value):
    """vtkColorTransferFunction over the value range in the map's colour space, and its knots."""
    colour = vtk.vtkColorTransferFunction()
    key = space.lower()
    if key == "rgb":
        colour.SetColorSpaceToRGB()
    elif key in ("lab", "cielab"):
        colour.SetColorSpaceToLab()
    elif key == "diverging":
        colour.SetColorSpaceToDiverging()
    elif key == "hsv":
        colour.SetColorSpaceToHSV()
        colour.HSVWrapOn()
    else:
        fail(f"ColorSpace '{space}' is not supported (RGB, Lab, Diverging, HSV)")
    knots = []
    for i in range(0, len(rgb), 4):
        colour.AddRGBPoint(to_value(rgb[i]), rgb[i + 1], rgb[i + 2], rgb[i + 3])
        knots.append(to_value(rgb[i]))
    colour.ClampingOn()
    return colour, knots


def build_opacity(points, to_value):
    """vtkPiecewiseFunction of the opacity Points (midpoint and sharpness as VTK reads them) over
    the value range, and its knots (with the midpoints, where a piece bends)."""
    opacity = vtk.vtkPiecewiseFunction()
    knots = []
    for i in range(0, len(points), 4):
        x, alpha, mid, sharp = points[i:i + 4]
        opacity.AddPoint(to_value(x), alpha, mid, sharp)
        knots.append(to_value(x))
        if i + 4 < len(points):
            knots.append(to_value(x + mid * (points[i + 4] - x)))
    opacity.ClampingOn()
    return opacity, knots


def resample(colour, opacity, knots, lo, hi, model, tolerance):
    """The colour and the function VTK's integrators read as attenuation * unit distance, both
    with control points at the same knots on [lo, hi] (clamped beyond).

    VTK's unstructured integrators (vtkUnstructuredGridLinearRayIntegrator and the partial
    pre-integration, VTK 9.1) split each segment only at the colour function's control points:
    of the opacity function they take the first point alone (their loop stops at the range's
    lower end), and between control points they interpolate colour in RGB and attenuation
    linearly. So both are given here at the same knots: the transfer function's own and, between
    them, as many more (by bisection) as keep the linear interpolation of the colour (evaluated
    in the map's colour space) and of the attenuation (the opacity itself for "attenuation",
    -ln(1 - alpha) for "transmittance") within tolerance of the curve (relative where the
    attenuation exceeds 1)."""
    # An opacity of 1 has infinite extinction: 1 - 1e-7 leaves 1e-7 of the light after one unit.
    max_alpha = 1.0 - 1e-7

    def curve(x):
        alpha = min(max(opacity.GetValue(x), 0.0), 1.0)
        tau = alpha if model == "attenuation" else -math.log1p(-min(alpha, max_alpha))
        return list(colour.GetColor(x)) + [tau]

    def straight(xa, fa, xb, fb):
        """True when the chord from a to b follows the curve at its quarter points."""
        for w in (0.25, 0.5, 0.75):
            f = curve(xa + w * (xb - xa))
            for k in range(4):
                chord = fa[k] + w * (fb[k] - fa[k])
                scale = max(1.0, abs(f[k])) if k == 3 else 1.0
                if abs(f[k] - chord) > tolerance * scale:
                    return False
        return True

    shortest = (hi - lo) / 65536.0
    hard = sorted({x for x in knots + [lo, hi] if lo <= x <= hi})
    xs = [hard[0]]
    for xa, xb in zip(hard, hard[1:]):
        stack = [(xa, xb)]  # depth first, left half on top: the knots come out in order
        while stack:
            a, b = stack.pop()
            if b - a > shortest and not straight(a, curve(a), b, curve(b)):
                m = 0.5 * (a + b)
                stack += [(m, b), (a, m)]
            else:
                xs.append(b)

    colour_out = vtk.vtkColorTransferFunction()
    colour_out.SetColorSpaceToRGB()
    colour_out.ClampingOn()
    attenuation = vtk.vtkPiecewiseFunction()
    attenuation.ClampingOn()
    for x in xs:
        f = curve(x)
        colour_out.AddRGBPoint(x, *f[:3])
        attenuation.AddPoint(x, f[3])
    return colour_out, attenuation


# Step 3: the camera ------------------------------------------------------------------------


def load_pvcc(path):
    """Position, focal point, view up, view angle, parallel projection and parallel scale (None
    when absent) of a ParaView camera file (.pvcc)."""
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError) as e:
        fail(f"{path}: {e}")
    props = {}
    for prop in root.iter("Property"):
        elements = sorted(prop.iter("Element"), key=lambda e: int(e.get("index")))
        props[prop.get("name")] = [float(e.get("value")) for e in elements]
    need = {"CameraPosition": 3, "CameraFocalPoint": 3, "CameraViewUp": 3, "CameraViewAngle": 1}
    for name, count in need.items():
        if len(props.get(name, [])) != count:
            fail(f"{path}: expected property {name} with {count} element(s)")
    parallel = props.get("CameraParallelProjection", [0])[0] != 0
    scale = props.get("CameraParallelScale", [None])[0]
    if parallel and not (scale and scale > 0):
        fail(f"{path}: parallel projection needs a positive CameraParallelScale")
    return (props["CameraPosition"], props["CameraFocalPoint"], props["CameraViewUp"],
            props["CameraViewAngle"][0], parallel, scale)


def ray_grid(width, height):
    """The ray-cast image size (mx, my) = (2 width + 1, 2 height + 1) and the mapper's image
    sample distance that gives it.

    The mapper shows its ray-cast image of m texels as a texture stretched, with linear
    filtering, from texel centre 0 at the viewport's left edge to texel centre m - 1 at its
    right edge (vtkOpenGLRayCastImageDisplayHelper): with m = width every screen pixel would be
    a blend of two rays and the image magnified by width / (width - 1). With m = 2 width + 1 the
    centre of screen pixel p falls exactly on texel 2p + 1, so every screen pixel is one ray
    (the even texels are cast and never shown). One sample distance serves both axes when the
    aspect ratio is below 2."""
    lo = max(1.0 / width, 1.0 / height)  # 1/distance - 2 must lie in [lo, hi) for both axes
    hi = min(2.0 / width, 2.0 / height)
    if not lo < hi:
        fail(f"image {width}x{height}: the oracle needs an aspect ratio below 2")
    return (2 * width + 1, 2 * height + 1), 1.0 / (2.0 + 0.5 * (lo + hi))


def set_camera(renderer, args, grid_size):
    """Places the camera as uvr does, then adapts VTK's projection to the ray-cast image of
    grid_size = (mx, my) texels so that texel 2p + 1 is uvr's ray through the centre of pixel p:

    - the Bunyk caster projects a vertex to x = (ndc + 1) / 2 * mx and casts texel j's ray at
      x = j, i.e. at ndc = 2j / mx - 1 (vtkUnstructuredGridBunykRayCastFunction);
    - uvr casts pixel p's ray at tan = tan(half view angle) * ((2p + 1) / width - 1), likewise
      in y with rows from the top (VTK's y grows upwards and the PNG is flipped: the same rays);
    - so VTK gets tan(half view angle) * my / (my - 1), aspect ratio mx / my and its window
      centre at (1 / mx, 1 / my) (vtkCamera's frustum shift: ndc = tan / tan(half) - centre).
    Returns the camera as uvr sees it."""
    camera = renderer.GetActiveCamera()
    parallel, scale = args.parallel, None
    if args.camera:
        position, focal, up, angle, file_parallel, scale = load_pvcc(args.camera)
        camera.SetPosition(*position)
        camera.SetFocalPoint(*focal)
        camera.SetViewUp(*up)
        camera.SetViewAngle(angle)
        parallel = parallel or file_parallel
    elif args.camera_position or args.camera_focal:
        if not (args.camera_position and args.camera_focal):
            fail("--camera-position and --camera-focal go together")
        camera.SetPosition(*parse_floats(args.camera_position, 3, "--camera-position"))
        camera.SetFocalPoint(*parse_floats(args.camera_focal, 3, "--camera-focal"))
    else:
        # ParaView's reset camera: a fresh vtkCamera looks down -Z with +Y up, view angle 30
        # degrees, and ResetCamera fits the bounding sphere into the view (and sets the parallel
        # scale to its radius).
        renderer.ResetCamera()
        scale = camera.GetParallelScale()
    if args.parallel_scale is not None:
        scale = args.parallel_scale
    if parallel:
        if scale is None:
            fail("--parallel with a camera file without CameraParallelScale needs "
                 "--parallel-scale")
        camera.ParallelProjectionOn()
        camera.SetParallelScale(scale)
    if args.camera_up:
        camera.SetViewUp(*parse_floats(args.camera_up, 3, "--camera-up"))
    if args.view_angle is not None:
        camera.SetViewAngle(args.view_angle)
    if args.azimuth:
        camera.Azimuth(args.azimuth)
    if args.elevation:
        camera.Elevation(args.elevation)
        camera.OrthogonalizeViewUp()
    seen = {"position": camera.GetPosition(), "focal": camera.GetFocalPoint(),
            "up": camera.GetViewUp(), "angle": camera.GetViewAngle(),
            "parallel_scale": camera.GetParallelScale() if parallel else None}

    mx, my = grid_size
    if parallel:
        # uvr's parallel rays sit at offsets scale * ((2p + 1) / height - 1) from the centre, as
        # its perspective rays sit at those tangents: the same adaptation.
        camera.SetParallelScale(camera.GetParallelScale() * my / (my - 1))
    else:
        half = math.radians(0.5 * camera.GetViewAngle())
        camera.SetViewAngle(math.degrees(2.0 * math.atan(math.tan(half) * my / (my - 1))))
    camera.SetUseExplicitAspectRatio(True)
    camera.SetExplicitAspectRatio(mx / my)
    camera.SetWindowCenter(1.0 / mx, 1.0 / my)
    renderer.ResetCameraClippingRange()  # the near plane must not cut the mesh
    return seen


# Step 4: render ----------------------------------------------------------------------------


def make_integrator(name):
    """VTK's ray integrators for point scalars: 'linear' evaluates the closed form of Williams,
    Max and Stein (1998) for colour and attenuation linear along a segment; 'partial' is
    Moreland and Angel's (2004) partial pre-integration (the same integral from a 512x512 table);
    'preintegration' is the mapper's default (a pre-integrated table with 128 scalar bins)."""
    return {"linear": vtk.vtkUnstructuredGridLinearRayIntegrator,
            "partial": vtk.vtkUnstructuredGridPartialPreIntegration,
            "preintegration": vtk.vtkUnstructuredGridPreIntegration}[name]()


def composite(rgba, background, unbias):
    """8-bit RGB of the premultiplied 8-bit RGBA over the background, rounded as uvr rounds.

    The mapper truncates colour and opacity to 8 bits, half a level low on average; unbias adds
    the half level back to covered pixels (any channel above 0). Over black a level v then
    becomes v + 1/2, which uvr would show as v or v + 1 alike: rounding half to even (numpy's
    rint) splits those between the two. Which reading agrees better with uvr varies from image
    to image, so the default leaves the mapper's values as they are."""
    value = rgba.astype(np.float64)
    if unbias:
        covered = np.any(rgba > 0, axis=-1, keepdims=True)
        value += np.where(covered, 0.5, 0.0)
    colour, alpha = value[..., :3] / 255.0, np.minimum(value[..., 3:] / 255.0, 1.0)
    out = colour + np.asarray(background) * (1.0 - alpha)
    return np.clip(np.rint(out * 255.0), 0, 255).astype(np.uint8)


def render(args, mesh=None):
    """Renders the scene the arguments describe and writes args.output (to a temporary name,
    then renamed); mesh, when given, is load_mesh(args.mesh) loaded before. Returns a summary of
    what was rendered."""
    width, height = parse_size(args.size)
    background = parse_floats(args.background, 3, "--background")
    if not all(0.0 <= c <= 1.0 for c in background):
        fail(f"--background '{args.background}': components must lie in [0, 1]")
    if not args.tolerance > 0.0:
        fail("--tolerance must be positive")

    grid, default_unit = mesh if mesh is not None else load_mesh(args.mesh)
    field, field_range = select_field(grid, args.field)
    lo, hi = parse_floats(args.range, 2, "--range") if args.range else field_range
    if not hi > lo:
        fail(f"value range [{lo}, {hi}] is empty; give --range LO,HI with LO < HI")
    unit = default_unit if args.opacity_unit is None else args.opacity_unit
    if not unit > 0.0:
        fail("--opacity-unit must be positive")

    # JSON positions are normalised over [first, last] RGBPoints x, then stretched over [lo, hi].
    space, rgb, points = load_colour_map(args.tf)
    x0, x1 = rgb[0], rgb[-4]

    def to_value(x):
        return lo + ((x - x0) / (x1 - x0) if x1 > x0 else 0.0) * (hi - lo)

    colour, colour_knots = build_colour(space, rgb, to_value)
    opacity, opacity_knots = build_opacity(points, to_value)
    colour, attenuation = resample(colour, opacity, colour_knots + opacity_knots, lo, hi,
                                   args.opacity_law, args.tolerance)

    prop = vtk.vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(attenuation)
    prop.SetScalarOpacityUnitDistance(unit)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()

    mapper = vtk.vtkUnstructuredGridVolumeRayCastMapper()
    mapper.SetInputData(grid)
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectScalarArray(field)
    mapper.SetRayIntegrator(make_integrator(args.integrator))
    grid_size, sample_distance = ray_grid(width, height)
    mapper.AutoAdjustSampleDistancesOff()  # the same rays, whatever the render time
    mapper.SetImageSampleDistance(sample_distance)
    mapper.IntermixIntersectingGeometryOff()
    if args.threads:
        mapper.SetNumberOfThreads(args.threads)
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    # Render over transparent black with an alpha channel: the framebuffer then holds the
    # mapper's premultiplied RGBA (its texture is blended with ONE, ONE_MINUS_SRC_ALPHA).
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(0.0, 0.0, 0.0)
    renderer.SetBackgroundAlpha(0.0)
    renderer.AddVolume(volume)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetAlphaBitPlanes(1)
    window.SetMultiSamples(0)
    window.SetSize(width, height)
    window.AddRenderer(renderer)
    camera = set_camera(renderer, args, grid_size)
    window.Render()
    if tuple(mapper.GetImageViewportSize()) != grid_size:
        fail(f"the mapper cast {tuple(mapper.GetImageViewportSize())} rays, "
             f"expected {grid_size}")

    # Step 5: read the frame back, composite it over the background and write it.
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGBA()
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOff()  # the frame is there; another render would cast every ray again
    grab.Update()
    frame = grab.GetOutput()
    rgba = numpy_support.vtk_to_numpy(frame.GetPointData().GetScalars()).reshape(-1, 4)
    rgb_out = composite(rgba, background, args.unbias)
    image = vtk.vtkImageData()
    image.SetDimensions(frame.GetDimensions())
    pixels = numpy_support.numpy_to_vtk(rgb_out, deep=True,
                                        array_type=vtk.VTK_UNSIGNED_CHAR)
    image.GetPointData().SetScalars(pixels)
    temporary = args.output + ".part.png"
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(temporary)
    writer.SetInputData(image)
    writer.Write()
    if writer.GetErrorCode():
        fail(f"{args.output}: PNG write failed")
    os.replace(temporary, args.output)
    summary = {"field": field, "range": [lo, hi], "opacity_unit": unit, "camera": camera,
               "knots": attenuation.GetSize(), "rays": list(grid_size)}
    if args.verbose:
        sys.stderr.write(f"vtk_oracle: {args.mesh} -> {args.output}: {json.dumps(summary)}\n")
    return summary


def make_parser():
    """The command line, shared with the test driver (vtk_oracle_test.py)."""
    parser = argparse.ArgumentParser(
        description="Render an unstructured volume with VTK's Bunyk ray caster "
                    "(vtkUnstructuredGridVolumeRayCastMapper) in uvr's conventions; the flags "
                    "mean what they mean to `uvr render`.",
        epilog="Example: xvfb-run -a /usr/bin/python3 vtk_oracle.py bluntfin_tets.vtk "
               "-o vtk.png --tf map.json --size 256x256 --background 0,0,0")
    parser.add_argument("mesh", help="mesh file (.vtk legacy or .vtu)")
    parser.add_argument("-o", "--output", required=True, help="output PNG (8-bit RGB)")
    parser.add_argument("--tf", required=True, help="ParaView colour-map JSON export")
    parser.add_argument("--field",
                        help="point scalar array (default: the active scalars, else the first "
                             "one-component point array)")
    parser.add_argument("--range", help="value range LO,HI the map spans (default: the field's)")
    parser.add_argument("--opacity-unit", type=float,
                        help="distance an opacity applies to (default: ParaView's, "
                             "bounds diagonal / cbrt(cells))")
    parser.add_argument("--camera", help="ParaView camera file (.pvcc)")
    parser.add_argument("--camera-position", help="camera position x,y,z")
    parser.add_argument("--camera-focal", help="camera focal point x,y,z")
    parser.add_argument("--camera-up", help="camera view up x,y,z")
    parser.add_argument("--view-angle", type=float, help="vertical view angle, degrees")
    parser.add_argument("--parallel", action="store_true",
                        help="parallel projection (as the .pvcc's CameraParallelProjection)")
    parser.add_argument("--parallel-scale", type=float,
                        help="half the view height with --parallel (default: the .pvcc's, else "
                             "ResetCamera's, the bounding sphere's radius)")
    parser.add_argument("--azimuth", type=float, default=0.0,
                        help="rotate the camera about view up, degrees (vtkCamera::Azimuth)")
    parser.add_argument("--elevation", type=float, default=0.0,
                        help="rotate the camera about its right axis, degrees "
                             "(vtkCamera::Elevation)")
    parser.add_argument("--size", default="1024x1024", help="image size WIDTHxHEIGHT")
    parser.add_argument("--background", default="0,0,0",
                        help="background colour r,g,b in [0, 1] (default black)")
    parser.add_argument("--opacity-law", choices=["attenuation", "transmittance"],
                        default="attenuation",
                        help="as uvr's --opacity-law: attenuation, alpha / unit, VTK's "
                             "unstructured integrators' own (default); transmittance: "
                             "-ln(1 - alpha) / unit")
    parser.add_argument("--tolerance", type=float, default=1e-3,
                        help="largest error of VTK's linear interpolation of colour and "
                             "attenuation between the knots it is given (default 1e-3)")
    parser.add_argument("--integrator", choices=["linear", "partial", "preintegration"],
                        default="linear",
                        help="VTK ray integrator (default linear: the closed form)")
    parser.add_argument("--unbias", action="store_true",
                        help="add back the half level the mapper's 8-bit truncation takes off "
                             "on average before compositing")
    parser.add_argument("--threads", type=int, default=0,
                        help="ray-casting threads (default: VTK's, one per core)")
    parser.add_argument("-v", "--verbose", action="store_true",
                        help="print the scene as set up")
    return parser


def main():
    render(make_parser().parse_args())


if __name__ == "__main__":
    main()
