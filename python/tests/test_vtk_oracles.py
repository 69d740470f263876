# SPDX-License-Identifier: MIT
"""Clipping and isosurfaces against VTK's own filters (python3-vtk9), on a real mesh.

- A clip plane cuts every cell exactly: uvr's clipped render equals the render of the mesh
  cut by vtkTableBasedClipDataSet (and differs from a whole-cell clip, vtkExtractGeometry).
- An opaque isosurface lies where vtkContourFilter puts it: rays cast here against the
  filter's triangles (vtkStaticCellLocator) give uvr's silhouette, depth and headlight shading
  (per-cell normals: a linear tetrahedron's gradient is its contour triangle's normal).
"""

import numpy as np
import pytest

import uvr

vtk = pytest.importorskip("vtkmodules.all")
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402

MESH = "bluntfin_tets.vtk"
SIZE = (128, 96)


@pytest.fixture(scope="module")
def bluntfin(data_dir):
    reader = vtk.vtkDataSetReader()
    reader.SetFileName(str(data_dir / MESH))
    reader.Update()
    grid = reader.GetOutput()
    grid.GetPointData().SetActiveScalars("density")
    renderer = uvr.Renderer(data_dir / MESH, field="density", device="cpu")
    return grid, renderer


def clip_with(grid, plane, algorithm):
    f = algorithm()
    f.SetInputData(grid)
    if isinstance(f, vtk.vtkTableBasedClipDataSet):
        f.SetClipFunction(plane)  # keeps where the plane's function is > 0: the normal's side
    else:
        f.SetImplicitFunction(plane)
        f.ExtractInsideOff()  # the normal's side, only cells wholly there
        f.ExtractBoundaryCellsOff()
    f.Update()
    return f.GetOutput()


@pytest.mark.parametrize("method", ["exact", "reference"])
def test_a_clip_plane_equals_the_mesh_cut_by_vtk(bluntfin, method):
    grid, full = bluntfin
    origin, normal = (3.0, 0.0, 0.0), (-1.0, 0.0, 0.0)
    plane = vtk.vtkPlane()
    plane.SetOrigin(*origin)
    plane.SetNormal(*normal)
    cut = clip_with(grid, plane, vtk.vtkTableBasedClipDataSet)
    whole = clip_with(grid, plane, vtk.vtkExtractGeometry)
    assert 0 < whole.GetNumberOfCells() < cut.GetNumberOfCells() < grid.GetNumberOfCells()
    # The same camera, range, opacity unit and step for all (the defaults follow the bounds).
    view = dict(size=SIZE, camera=full.camera(SIZE, 60, 20).zoom(2.5), method=method,
                range=(0.19, 4.98), opacity="0:0,1:0.6", opacity_unit=0.5, sample_distance=0.05)
    clipped = full.render(clip_planes=[(origin, normal)], **view)
    by_vtk = uvr.Renderer(uvr.from_vtk(cut), field="density", device="cpu").render(**view)
    cells = uvr.Renderer(uvr.from_vtk(whole), field="density", device="cpu").render(**view)
    same = uvr.compare_report(clipped, by_vtk)
    staircase = uvr.compare_report(clipped, cells)
    if method == "exact":  # the same cells' pieces, integrated exactly: equal to rounding
        assert same["max_abs_difference"] <= 2 and same["ssim"] > 0.9999, same
    else:  # the same samples, located in other (split) cells
        assert same["ssim"] > 0.999 and same["p999_difference"] <= 4, same
    # A whole-cell clip shows the cells' staircase along the cut.
    assert staircase["ssim"] < 0.98 and staircase["max_abs_difference"] > 20, staircase


def cast_rays(surface, camera, size):
    """Per pixel (rows from the top) the first hit of uvr's camera ray (makeCameraRays: a pinhole
    with the image plane at unit distance, pixel centres at +0.5) with the triangles: hit mask,
    view depth, and |cos| between the ray and the triangle's normal."""
    w, h = size
    pos = np.array(camera.position, float)
    d = np.array(camera.focal_point, float) - pos
    d /= np.linalg.norm(d)
    right = np.cross(d, np.array(camera.view_up, float))
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    half_h = np.tan(0.5 * np.radians(camera.view_angle))
    half_w = half_h * w / h
    tri = vtk_to_numpy(surface.GetPolys().GetData()).reshape(-1, 4)[:, 1:]
    p = vtk_to_numpy(surface.GetPoints().GetData()).astype(float)
    n = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    locator = vtk.vtkStaticCellLocator()
    locator.SetDataSet(surface)
    locator.BuildLocator()
    t, x, pc = vtk.reference(0.0), [0.0] * 3, [0.0] * 3
    sub, cell = vtk.reference(0), vtk.reference(0)
    hit = np.zeros((h, w), bool)
    depth = np.full((h, w), np.inf)
    cosine = np.zeros((h, w))
    far = 1e4 * max(1.0, np.linalg.norm(pos))
    for j in range(h):
        for i in range(w):
            ray = d + right * (-half_w + 2 * half_w * (i + 0.5) / w) \
                + up * (half_h - 2 * half_h * (j + 0.5) / h)
            ray /= np.linalg.norm(ray)
            if not locator.IntersectWithLine(pos, pos + far * ray, 1e-9, t, x, pc, sub, cell):
                continue
            hit[j, i] = True
            depth[j, i] = np.dot(np.array(x) - pos, d)
            cosine[j, i] = abs(np.dot(n[int(cell)], ray))
    return hit, depth, cosine


@pytest.mark.parametrize("value", [0.5, 2.0, 3.0])
def test_an_opaque_isosurface_lies_where_vtk_contours_it(bluntfin, value):
    grid, renderer = bluntfin
    contour = vtk.vtkContourFilter()
    contour.SetInputData(grid)
    contour.SetValue(0, value)
    contour.ComputeNormalsOff()
    contour.Update()
    surface = contour.GetOutput()
    assert surface.GetNumberOfCells() > 100
    camera = renderer.camera(SIZE, 40, 25).zoom(1.8)
    ambient, diffuse = 0.2, 0.8
    img = renderer.render(size=SIZE, camera=camera, method="exact", opacity="0:0,1:0",
                          iso=[(value, 1.0, "#ffffff")], normals="cell", ambient=ambient,
                          diffuse=diffuse, depth=0.5)
    hit, depth, cosine = cast_rays(surface, camera, SIZE)
    mine = np.asarray(img)[..., 3] > 0.5
    assert hit.sum() > 100
    # The silhouette: at most a pixel or two where a ray grazes an edge.
    assert (mine != hit).sum() <= max(2, 0.001 * hit.size), (mine != hit).sum()
    both = mine & hit
    # Depth to a thousandth of the mesh's size, headlight shading to 1/255 (per-cell normals
    # are the contour triangles' normals), on all but a grazing pixel or two.
    bounds = np.array(grid.GetBounds()).reshape(3, 2)
    size = np.linalg.norm(bounds[:, 1] - bounds[:, 0])
    depth_error = np.abs(img.depth[both] - depth[both])
    shade_error = np.abs(np.asarray(img)[..., 0] - (ambient + diffuse * cosine))[both]
    assert np.sum(depth_error > 1e-3 * size) <= 2, np.sort(depth_error)[-5:]
    assert np.sum(shade_error > 1 / 255) <= 2, np.sort(shade_error)[-5:]
    oracle = np.zeros(img.shape, np.float32)
    oracle[..., :3] = ((ambient + diffuse * cosine) * hit)[..., None]
    oracle[..., 3] = hit
    assert uvr.compare(img, uvr.Image(oracle))[0] >= 0.99
