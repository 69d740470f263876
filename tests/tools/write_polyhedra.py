#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes meshes with polyhedron cells (VTK type 42) through VTK's own writers, for uvr's tests.

Usage: write_polyhedra.py OUT_DIR

Writes, each as VTU (ascii, binary, appended) and legacy VTK (5.1 and 4.2, ASCII and BINARY):
  cubes_poly.*  a 3x3x3 grid of unit cubes, each a 6-face polyhedron;
  cubes_hex.*   the same grid as hexahedra;
  mixed.*       the grid with cubes as hexahedra, polyhedra, two prism-shaped polyhedra, two
                wedges and six pyramids around a centre point (conforming: split diagonals go
                through each square's smallest point index), plus an octahedron polyhedron with
                a tetrahedron on one face.
  prisms.*      a regular pentagonal prism (VTK type 15) and, beside it, a regular hexagonal
                prism (type 16) with a hexahedron on one of its square faces;
  ghosts.*      cubes_hex with VTK's ghost arrays (vtkGhostType): cell 0 HIDDENCELL (32), cell 1
                DUPLICATECELL (1), cell 2 EXTERIORCELL (16, shown by ParaView), point (N, N, N)
                HIDDENPOINT (2, hides cell 26) and point 0 DUPLICATEPOINT (1, hides nothing).
Point field 'f' = x + 2y - z, cell field 'id' = the cell's index. For mixed and prisms, also
NAME_volumes.txt: VTK's volume of each cell (vtkCellSizeFilter), and
mixed_pieces.vtu: three <Piece>s. Needs python3-vtk9.
"""
import math
import os
import sys

import vtk

N = 3


def grid_mesh(kind_of):
    """The N^3 grid; kind_of(i, j, k) picks how the cube at (i, j, k) is written."""
    pts = vtk.vtkPoints()
    pid = {}

    def p(x, y, z):
        key = (x, y, z)
        if key not in pid:
            pid[key] = pts.InsertNextPoint(*key)
        return pid[key]

    for k in range(N + 1):  # lattice points first, numbered x fastest
        for j in range(N + 1):
            for i in range(N + 1):
                p(i, j, k)
    ug = vtk.vtkUnstructuredGrid()
    ug.SetPoints(pts)

    def cell(ctype, ids):
        idl = vtk.vtkIdList()
        for v in ids:
            idl.InsertNextId(v)
        ug.InsertNextCell(ctype, idl)

    def poly(faces):
        stream = [len(faces)]
        for f in faces:
            stream += [len(f)] + list(f)
        cell(vtk.VTK_POLYHEDRON, stream)

    for k in range(N):
        for j in range(N):
            for i in range(N):
                c = [p(i, j, k), p(i + 1, j, k), p(i + 1, j + 1, k), p(i, j + 1, k),
                     p(i, j, k + 1), p(i + 1, j, k + 1), p(i + 1, j + 1, k + 1), p(i, j + 1, k + 1)]
                kind = kind_of(i, j, k)
                if kind == "hex":
                    cell(vtk.VTK_HEXAHEDRON, c)
                elif kind == "poly":  # VTK's hexahedron faces, outward
                    poly([[c[0], c[3], c[2], c[1]], [c[4], c[5], c[6], c[7]],
                          [c[0], c[1], c[5], c[4]], [c[1], c[2], c[6], c[5]],
                          [c[2], c[3], c[7], c[6]], [c[3], c[0], c[4], c[7]]])
                elif kind in ("prisms", "wedges"):
                    # Split along the bottom/top diagonal c0-c2 (through the smallest index).
                    for w in ([c[0], c[1], c[2], c[4], c[5], c[6]],
                              [c[0], c[2], c[3], c[4], c[6], c[7]]):
                        if kind == "wedges":  # VTK wedge order: (0,1,2) bottom, its normal in
                            cell(vtk.VTK_WEDGE, [w[0], w[2], w[1], w[3], w[5], w[4]])
                        else:
                            poly([[w[0], w[2], w[1]], [w[3], w[4], w[5]],
                                  [w[0], w[1], w[4], w[3]], [w[1], w[2], w[5], w[4]],
                                  [w[2], w[0], w[3], w[5]]])
                elif kind == "pyramids":
                    m = p(i + 0.5, j + 0.5, k + 0.5)
                    for q in ([c[0], c[1], c[2], c[3]], [c[7], c[6], c[5], c[4]],
                              [c[0], c[4], c[5], c[1]], [c[1], c[5], c[6], c[2]],
                              [c[2], c[6], c[7], c[3]], [c[3], c[7], c[4], c[0]]):
                        cell(vtk.VTK_PYRAMID, q + [m])
    return ug, p, poly, cell


def add_fields(ug):
    f = vtk.vtkDoubleArray()
    f.SetName("f")
    for i in range(ug.GetNumberOfPoints()):
        x, y, z = ug.GetPoint(i)
        f.InsertNextValue(x + 2 * y - z)
    ug.GetPointData().AddArray(f)
    ids = vtk.vtkFloatArray()
    ids.SetName("id")
    for c in range(ug.GetNumberOfCells()):
        ids.InsertNextValue(c)
    ug.GetCellData().AddArray(ids)


def write_all(ug, out, name):
    for mode in ("ascii", "binary", "appended"):
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(os.path.join(out, f"{name}_{mode}.vtu"))
        w.SetInputData(ug)
        getattr(w, "SetDataModeTo" + mode.capitalize())()
        assert w.Write() == 1
    for version in (51, 42):
        for mode in ("ascii", "binary"):
            w = vtk.vtkUnstructuredGridWriter()
            w.SetFileName(os.path.join(out, f"{name}_{version}_{mode}.vtk"))
            w.SetInputData(ug)
            w.SetFileVersion(version)
            if mode == "ascii":
                w.SetFileTypeToASCII()
            else:
                w.SetFileTypeToBinary()
            assert w.Write() == 1


def write_volumes(ug, path):
    sizes = vtk.vtkCellSizeFilter()
    sizes.SetInputData(ug)
    sizes.ComputeVolumeOn()
    sizes.Update()
    vol = sizes.GetOutput().GetCellData().GetArray("Volume")
    with open(path, "w") as fh:
        for c in range(vol.GetNumberOfTuples()):
            fh.write(f"{vol.GetValue(c):.17g}\n")


def prisms_mesh():
    """Regular pentagonal and hexagonal prisms (bases in z = 0 and z = 1, VTK's numbering: the
    bottom base counter-clockwise seen from above, the top above it), a hexahedron on one of the
    hexagonal prism's square faces."""
    pts = vtk.vtkPoints()
    ug = vtk.vtkUnstructuredGrid()
    ug.SetPoints(pts)

    def prism(cx, n, ctype):
        ids = []
        for z in (0.0, 1.0):
            for i in range(n):
                a = 2 * math.pi * i / n
                ids.append(pts.InsertNextPoint(cx + math.cos(a), math.sin(a), z))
        idl = vtk.vtkIdList()
        for v in ids:
            idl.InsertNextId(v)
        ug.InsertNextCell(ctype, idl)
        return ids

    prism(0.0, 5, vtk.VTK_PENTAGONAL_PRISM)
    h = prism(3.0, 6, vtk.VTK_HEXAGONAL_PRISM)
    # The hexahedron on the square face (0, 1, 7, 6) of the hexagonal prism, outward along the
    # face's normal: VTK hexahedron order, bottom (on the face) then top.
    b = [h[0], h[1], h[7], h[6]]
    p0 = [pts.GetPoint(i) for i in b]
    mid = [sum(q[a] for q in p0) / 4 for a in range(3)]
    nx, ny = mid[0] - 3.0, mid[1]
    norm = math.hypot(nx, ny)
    top = [pts.InsertNextPoint(q[0] + nx / norm, q[1] + ny / norm, q[2]) for q in p0]
    idl = vtk.vtkIdList()
    for v in b + top:
        idl.InsertNextId(v)
    ug.InsertNextCell(vtk.VTK_HEXAHEDRON, idl)
    return ug


def ghost_arrays(ug):
    cells = vtk.vtkUnsignedCharArray()
    cells.SetName("vtkGhostType")
    for c in range(ug.GetNumberOfCells()):
        cells.InsertNextValue({0: 32, 1: 1, 2: 16}.get(c, 0))
    ug.GetCellData().AddArray(cells)
    points = vtk.vtkUnsignedCharArray()
    points.SetName("vtkGhostType")
    last = ug.GetNumberOfPoints() - 1  # (N, N, N): numbered x fastest
    for i in range(ug.GetNumberOfPoints()):
        points.InsertNextValue(2 if i == last else 1 if i == 0 else 0)
    ug.GetPointData().AddArray(points)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for name, kind in (("cubes_poly", "poly"), ("cubes_hex", "hex")):
        ug = grid_mesh(lambda i, j, k, kind=kind: kind)[0]
        add_fields(ug)
        write_all(ug, out, name)

    kinds = ["hex", "poly", "prisms", "wedges", "pyramids"]
    ug, p, poly, cell = grid_mesh(lambda i, j, k: kinds[(i + N * j + N * N * k) % len(kinds)])
    # An octahedron beside the grid, with a tetrahedron on its face (+x, +y, +z).
    o = (6, 1.5, 1.5)
    v = [p(o[0] + dx, o[1] + dy, o[2] + dz) for dx, dy, dz in
         ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))]
    xp, xm, yp, ym, zp, zm = v
    poly([[xp, yp, zp], [yp, xm, zp], [xm, ym, zp], [ym, xp, zp],
          [yp, xp, zm], [xm, yp, zm], [ym, xm, zm], [xp, ym, zm]])
    cell(vtk.VTK_TETRA, [xp, yp, zp, p(o[0] + 1, o[1] + 1, o[2] + 1)])
    add_fields(ug)
    write_all(ug, out, "mixed")
    # Three <Piece>s in one file (VTK 9.1's writer repeats the whole grid in each).
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(os.path.join(out, "mixed_pieces.vtu"))
    w.SetInputData(ug)
    w.SetNumberOfPieces(3)
    w.SetDataModeToBinary()
    assert w.Write() == 1
    write_volumes(ug, os.path.join(out, "mixed_volumes.txt"))

    ug = prisms_mesh()
    add_fields(ug)
    write_all(ug, out, "prisms")
    write_volumes(ug, os.path.join(out, "prisms_volumes.txt"))

    for name, kind in (("ghosts", "hex"), ("ghosts_poly", "poly")):
        ug = grid_mesh(lambda i, j, k, kind=kind: kind)[0]
        add_fields(ug)
        ghost_arrays(ug)
        write_all(ug, out, name)


if __name__ == "__main__":
    main()
