#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Measures the opacity law of VTK's unstructured volume mappers (issue 29): a slab of
tetrahedra L thick (parallel view straight through it) with a constant transfer-function opacity
a per opacity unit u = 1 and black colour, rendered over a white background by
vtkProjectedTetrahedraMapper (ParaView's default volume mapper for unstructured grids) and
vtkUnstructuredGridVolumeRayCastMapper (Bunyk, linear ray integrator). The slab's alpha is
1 - (the centre pixel's grey level); the table sets it beside the two laws:
  transmittance  1 - (1 - a)^(L / u)   (uvr before issue 29: extinction -ln(1 - a) / u)
  attenuation    1 - exp(-a L / u)     (extinction a / u)

Run with Debian's python3-vtk9 under an X display: xvfb-run -a /usr/bin/python3 opacity_law.py
"""
import argparse
import math
import sys

import numpy as np
import vtk
from vtkmodules.util import numpy_support


# The view direction: slightly oblique (seen exactly edge-on, the tetrahedra's vertical faces
# make the projected tetrahedra degenerate and put Bunyk's rays on faces).
VIEW = (0.3, 0.2, 1.0)
PARALLEL = False


def slab(thickness):
    """A 4 x 4 x thickness box split into tetrahedra, point scalar s = x / 4 + 1 / 2."""
    image = vtk.vtkImageData()
    image.SetDimensions(9, 9, 5)
    image.SetOrigin(-2.0, -2.0, 0.0)
    image.SetSpacing(0.5, 0.5, thickness / 4.0)
    xs = vtk.vtkFloatArray()
    xs.SetName("s")
    for k in range(5):
        for j in range(9):
            for i in range(9):
                xs.InsertNextValue(i / 8.0)
    image.GetPointData().SetScalars(xs)
    tets = vtk.vtkDataSetTriangleFilter()
    tets.SetInputData(image)
    tets.TetrahedraOnlyOn()
    tets.Update()
    return tets.GetOutput()


def make_window(size):
    """One off-screen window for every render (VTK 9.1 under Xvfb loses its X connection after
    a few windows)."""
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(size, size)
    window.AddRenderer(renderer)
    return window, renderer


SIZE = 64
WINDOW = None


def alpha_of(mapper_name, a, path, size=SIZE):
    """The slab's alpha where the view crosses `path` of it (the median over the centre
    pixels), as the mapper renders it."""
    norm = math.sqrt(sum(v * v for v in VIEW))
    thickness = path * VIEW[2] / norm
    grid = slab(thickness)
    colour = vtk.vtkColorTransferFunction()
    colour.AddRGBPoint(0.0, 0.0, 0.0, 0.0)
    colour.AddRGBPoint(1.0, 0.0, 0.0, 0.0)
    opacity = vtk.vtkPiecewiseFunction()
    opacity.AddPoint(0.0, a)
    opacity.AddPoint(1.0, a)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(1.0)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    if mapper_name == "projected":
        mapper = vtk.vtkProjectedTetrahedraMapper()
    else:
        mapper = vtk.vtkUnstructuredGridVolumeRayCastMapper()
        mapper.SetRayIntegrator(vtk.vtkUnstructuredGridLinearRayIntegrator())
        mapper.SetImageSampleDistance(1.0)
        mapper.AutoAdjustSampleDistancesOff()
    mapper.SetInputData(grid)
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectScalarArray("s")
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    window, renderer = WINDOW
    renderer.RemoveAllViewProps()
    renderer.AddVolume(volume)
    camera = renderer.GetActiveCamera()
    # Perspective: under a parallel projection VTK 9.1's projected tetrahedra take depths
    # about half too small (measured: 0.125 for a = 0.3, L = 1; see --parallel).
    if PARALLEL:
        camera.ParallelProjectionOn()
        camera.SetParallelScale(1.0)
    else:
        camera.SetViewAngle(10.0)
    camera.SetFocalPoint(0.0, 0.0, 0.5 * thickness)
    camera.SetPosition(*(10.0 * v / norm + (0.5 * thickness if k == 2 else 0.0)
                         for k, v in enumerate(VIEW)))
    camera.SetViewUp(0.0, 1.0, 0.0)
    renderer.ResetCameraClippingRange()
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOff()
    grab.Update()
    frame = grab.GetOutput()
    rgb = numpy_support.vtk_to_numpy(frame.GetPointData().GetScalars()).reshape(size, size, -1)
    grey = float(np.median(rgb[size // 2 - 4:size // 2 + 4, size // 2 - 4:size // 2 + 4, :3]))
    return 1.0 - grey / 255.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--opacities", default="0.1,0.3,0.6,0.9,1.0")
    parser.add_argument("--thickness", default="0.25,1,4")
    parser.add_argument("--parallel", action="store_true", help="parallel projection")
    args = parser.parse_args()
    global PARALLEL, WINDOW
    PARALLEL = args.parallel
    WINDOW = make_window(SIZE)
    opacities = [float(v) for v in args.opacities.split(",")]
    thicknesses = [float(v) for v in args.thickness.split(",")]
    print("| a | L/u | projected tetrahedra | Bunyk (linear) | 1-(1-a)^(L/u) | 1-exp(-a L/u) |")
    print("|---|---|---|---|---|---|")
    for a in opacities:
        for length in thicknesses:
            pt = alpha_of("projected", a, length)
            bunyk = alpha_of("bunyk", a, length)
            trans = 1.0 - (1.0 - a) ** length
            atten = 1.0 - math.exp(-a * length)
            print(f"| {a:g} | {length:g} | {pt:.3f} | {bunyk:.3f} | {trans:.3f} | {atten:.3f} |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
