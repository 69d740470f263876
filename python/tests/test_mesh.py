# SPDX-License-Identifier: MIT
"""Meshes from files, numpy arrays, meshio and VTK; bad arrays refused naming the argument."""

import numpy as np
import pytest

import uvr


def grid(n=6, jitter=0.0):
    """An n^3 grid of hexahedra over [-1, 1]^3 in VTK's layout, with a point field."""
    ax = np.linspace(-1.0, 1.0, n + 1)
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1).astype(np.float32)
    if jitter:
        rng = np.random.default_rng(7)
        inner = np.all(np.abs(points) < 0.999, axis=1)
        points[inner] += (rng.random((inner.sum(), 3)) - 0.5) * jitter * 2.0 / n
    np1 = n + 1
    i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()

    def idx(a, b, c):
        return (c * np1 + b) * np1 + a

    hexes = np.stack([idx(i, j, k), idx(i + 1, j, k), idx(i + 1, j + 1, k), idx(i, j + 1, k),
                      idx(i, j, k + 1), idx(i + 1, j, k + 1), idx(i + 1, j + 1, k + 1),
                      idx(i, j + 1, k + 1)], axis=1).astype(np.uint32)
    f = np.sin(3 * points[:, 0]) * points[:, 1] + points[:, 2]
    return points, hexes, f.astype(np.float32)


@pytest.mark.parametrize("name", ["spx.vtk", "post.vtk", "tetraMesh.vtk", "bluntfin_tets.vtk",
                                  "hexa.vtk", "fire_ug.vtu", "cylinder_quadratic_as_tets.vtk"])
def test_read_every_shared_file_gives_views_of_uvrs_arrays(data_dir, name):
    m = uvr.read(data_dir / name)
    assert m.n_points > 0 and m.n_cells > 0
    assert m.points.shape == (m.n_points, 3) and m.points.dtype == np.float32
    assert m.offsets.shape == (m.n_cells + 1,) and m.offsets[-1] == m.connectivity.size
    assert not m.points.flags.writeable  # a view of uvr's memory, not a copy
    assert np.shares_memory(m.points, m.points)
    assert m.fields and m.copied == []
    lo, hi = m.bounds
    assert all(a < b for a, b in zip(lo, hi))


def test_numpy_arrays_in_uvrs_layout_are_not_copied(small_tets):
    points, cells = small_tets
    conn = np.ascontiguousarray(cells.ravel())
    offsets = np.array([0, 4, 8], dtype=np.int64)
    types = np.array([10, 10], dtype=np.uint8)
    values = np.arange(5, dtype=np.float32)
    m = uvr.Mesh(points, cells=conn, offsets=offsets, types=types, point_data={"v": values})
    assert m.copied == []
    assert m.points is points and m.connectivity is conn and m.types is types
    assert np.shares_memory(m.offsets, offsets)
    assert m.point_data["v"] is values


def test_other_dtypes_are_converted_once_and_named(small_tets):
    points, cells = small_tets
    m = uvr.Mesh(points.astype(np.float64), cells=cells.astype(np.int64),
                 point_data={"v": np.arange(5)})
    assert set(m.copied) >= {"points", "cells", "point_data['v']"}
    assert m.points.dtype == np.float32 and m.connectivity.dtype == np.uint32


def render_pixels(mesh, **kw):
    kw.setdefault("size", (48, 40))
    kw.setdefault("azimuth", 30)
    kw.setdefault("elevation", 20)
    return uvr.Renderer(mesh, methods=("adaptive",)).render(**kw)


def test_vtk_pyvista_and_homogeneous_layouts_render_the_same():
    points, hexes, f = grid(4, jitter=0.3)
    m = hexes.shape[0]
    vtk_layout = uvr.Mesh(points, cells=hexes.ravel(), offsets=np.arange(0, 8 * m + 1, 8),
                          types=np.full(m, 12, np.uint8), point_data={"f": f})
    padded = np.hstack([np.full((m, 1), 8), hexes]).ravel()
    pyvista_layout = uvr.Mesh(points, cells=padded, types=np.full(m, 12), point_data={"f": f})
    end_offsets = uvr.Mesh(points, cells=hexes.ravel(), offsets=np.arange(8, 8 * m + 1, 8),
                           types=np.full(m, 12), point_data={"f": f})
    homogeneous = uvr.Mesh(points, cells=hexes, point_data={"f": f})
    ref = render_pixels(vtk_layout)
    assert ref.stats["samples"] > 0
    for other in (pyvista_layout, end_offsets, homogeneous):
        assert np.array_equal(render_pixels(other), ref)


def test_voxels_quadratic_and_flat_cells_are_converted_with_their_cell_data():
    points, hexes, f = grid(2)
    voxel = hexes[:, [0, 1, 3, 2, 4, 5, 7, 6]]  # VTK's voxel order
    triangle = np.array([0, 1, 2])
    conn = np.concatenate([voxel.ravel(), triangle])
    offsets = np.concatenate([np.arange(0, 8 * 8 + 1, 8), [67]])
    types = np.array([11] * 8 + [5])
    cell_values = np.arange(9, dtype=np.float32)
    m = uvr.Mesh(points, cells=conn, offsets=offsets, types=types, point_data={"f": f},
                 cell_data={"c": cell_values})
    assert m.n_cells == 8 and list(np.unique(m.types)) == [12]
    assert np.array_equal(m.connectivity.reshape(8, 8), hexes)
    assert np.array_equal(m.cell_data["c"], cell_values[:8])
    assert any("voxel" in n for n in m.notes) and any("triangle" in n for n in m.notes)


def test_bad_arrays_are_refused_naming_the_argument(small_tets):
    points, cells = small_tets
    with pytest.raises(uvr.ArgumentError, match=r"points: expected shape \(n, 3\), got \(5, 2\)"):
        uvr.Mesh(points[:, :2], cells=cells)
    with pytest.raises(TypeError, match="points: expected an array of real numbers"):
        uvr.Mesh(points.astype(complex), cells=cells)
    with pytest.raises(TypeError, match="cells: expected an array of integers"):
        uvr.Mesh(points, cells=cells.astype(np.float32))
    with pytest.raises(uvr.ValidationError, match="cell 1.*point 9.*below pointCount 5"):
        uvr.Mesh(points, cells=np.array([[0, 1, 2, 3], [1, 2, 3, 9]]))
    with pytest.raises(uvr.ValidationError, match="cell 0: corner 2 is point -1"):
        uvr.Mesh(points, cells=np.array([[0, 1, -1, 3]], dtype=np.int32))
    with pytest.raises(uvr.ArgumentError, match="offsets: expected 3 entries"):
        uvr.Mesh(points, cells=cells.ravel(), offsets=[0, 4, 8, 9], types=[10, 10])
    with pytest.raises(uvr.ArgumentError, match="types: required"):
        uvr.Mesh(points, cells=cells.ravel(), offsets=[0, 4, 8])
    with pytest.raises(uvr.ArgumentError, match=r"point_data\['v'\]: expected 5 tuples"):
        uvr.Mesh(points, cells=cells, point_data={"v": np.zeros(4)})
    with pytest.raises(uvr.ArgumentError, match=r"cell_data\['c'\]: expected 2 tuples"):
        uvr.Mesh(points, cells=cells, cell_data={"c": np.zeros((3, 2))})
    with pytest.raises(uvr.ParseError, match="unknown VTK cell type 99"):
        uvr.Mesh(points, cells=cells.ravel(), offsets=[0, 4, 8], types=[10, 99])
    with pytest.raises(uvr.UnsupportedError, match="polyhedron"):
        uvr.Mesh(points, cells=cells.ravel(), offsets=[0, 4, 8], types=[10, 42])
    with pytest.raises(TypeError, match="expected a mesh"):
        uvr.as_mesh(42)


def test_bad_files_raise_the_librarys_errors(tmp_path):
    with pytest.raises(uvr.FileError, match="cannot open") as e:
        uvr.read(tmp_path / "missing.vtk")
    assert isinstance(e.value, OSError)
    bad = tmp_path / "bad.vtk"
    bad.write_text("# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 "
                   "float\n0 0 0\n")
    with pytest.raises(uvr.ParseError, match="bad.vtk"):
        uvr.read(bad)


def test_meshio_meshes_convert_and_render_as_the_file_does(data_dir):
    meshio = pytest.importorskip("meshio")
    path = data_dir / "post.vtk"
    direct = uvr.read(path)
    converted = uvr.from_meshio(meshio.read(path))
    assert converted.n_cells == direct.n_cells
    assert np.array_equal(converted.points, direct.points)
    assert np.array_equal(render_pixels(converted), render_pixels(direct))
    # A meshio mesh built in memory, mixed with a 2D block that is dropped with its cell data.
    points, hexes, f = grid(2)
    m = meshio.Mesh(points, [("hexahedron", hexes.astype(np.int64)),
                             ("triangle", np.array([[0, 1, 2]]))],
                    point_data={"f": f}, cell_data={"c": [np.arange(8.0), np.array([99.0])]})
    u = uvr.as_mesh(m)
    assert u.n_cells == 8 and np.array_equal(u.cell_data["c"], np.arange(8.0))
    assert any("triangle" in n for n in u.notes)


def test_vtk_grids_convert_and_render_as_the_file_does(data_dir):
    pytest.importorskip("vtkmodules")
    from vtkmodules.vtkIOLegacy import vtkUnstructuredGridReader

    path = data_dir / "bluntfin_tets.vtk"
    reader = vtkUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.ReadAllScalarsOn()
    reader.ReadAllVectorsOn()
    reader.Update()
    grid_ = reader.GetOutput()
    converted = uvr.from_vtk(grid_)
    direct = uvr.read(path)
    assert converted.n_cells == direct.n_cells
    assert set(converted.point_data) >= {"density", "momentum"}
    assert "points" not in converted.copied  # VTK's float32 points are used in place
    a = render_pixels(converted, field="momentum:magnitude")
    b = render_pixels(direct, field="momentum:magnitude")
    assert np.array_equal(a, b)
    with pytest.raises(TypeError, match="vtkUnstructuredGrid"):
        uvr.from_vtk(reader)


def test_duck_typed_pyvista_like_objects():
    points, hexes, f = grid(2)

    class Grid:  # what a pyvista.UnstructuredGrid offers besides being a VTK object
        def __init__(self):
            self.points = points
            self.cells = np.hstack([np.full((8, 1), 8), hexes]).ravel()
            self.celltypes = np.full(8, 12, dtype=np.uint8)
            self.point_data = {"f": f}
            self.cell_data = {}

    m = uvr.as_mesh(Grid())
    assert m.n_cells == 8 and "f" in m.point_data
