#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Writes a small mixed-cell legacy VTK file with VTK's own writer, plus the expected mesh as JSON.

Usage: write_legacy_vtk.py OUT.vtk {42|51} {ascii|binary}
Writes OUT.vtk and OUT.vtk.json. The JSON holds what a reader should return after reducing
cells to uvr's model: float32 points, volumetric cells as (uvr type code, corner ids), the
dropped 2D cell count, and every point/cell field as float32 values (tuple-major).
"""
import json
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk


def make_array(values, name, vtk_type=None):
    arr = numpy_to_vtk(np.ascontiguousarray(values), deep=1, array_type=vtk_type)
    arr.SetName(name)
    return arr


def main():
    out, version, mode = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    rng = np.random.default_rng(1234)

    # Points: doubles with a wide range of magnitudes (one large enough to print as 1.5e+10).
    n_points = 24
    pts = rng.uniform(-5.0, 5.0, size=(n_points, 3))
    pts[7, 0] = 1.5e10
    pts[8, 2] = -2.5e-7
    points = vtk.vtkPoints()
    points.SetDataTypeToDouble()
    points.SetData(make_array(pts, "Points"))

    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points)
    # (VTK type, node ids): tetra, hexahedron, wedge, pyramid, triangle (dropped), quadratic tetra.
    cells = [
        (vtk.VTK_TETRA, [0, 1, 2, 3]),
        (vtk.VTK_HEXAHEDRON, [4, 5, 6, 7, 8, 9, 10, 11]),
        (vtk.VTK_WEDGE, [12, 13, 14, 15, 16, 17]),
        (vtk.VTK_PYRAMID, [18, 19, 20, 21, 22]),
        (vtk.VTK_TRIANGLE, [0, 5, 9]),
        (vtk.VTK_QUADRATIC_TETRA, [23, 1, 2, 3, 4, 5, 6, 7, 8, 9]),
    ]
    corners = {vtk.VTK_TETRA: (10, 4), vtk.VTK_HEXAHEDRON: (12, 8), vtk.VTK_WEDGE: (13, 6),
               vtk.VTK_PYRAMID: (14, 5), vtk.VTK_QUADRATIC_TETRA: (10, 4)}
    for cell_type, ids in cells:
        grid.InsertNextCell(cell_type, len(ids), ids)
    n_cells = len(cells)
    kept = [i for i, (t, _) in enumerate(cells) if t in corners]

    fields = []

    def add(data, values, name, association, setter=None, expected=None):
        arr = make_array(values, name)
        if values.ndim == 2:
            # Component names make VTK >= 8 write a METADATA block after the array.
            arr.SetComponentName(0, "first")
        if setter is None:
            data.AddArray(arr)
        else:
            getattr(data, setter)(arr)
        exp = np.asarray(values if expected is None else expected, dtype=np.float64)
        exp = exp.reshape(exp.shape[0], -1)
        if association == "cell":
            exp = exp[kept]
        fields.append({"name": name, "association": association,
                       "components": int(exp.shape[1]),
                       "values": [float(np.float32(v)) for v in exp.ravel()]})

    pd = grid.GetPointData()
    idx = np.arange(n_points)
    add(pd, rng.uniform(-100, 100, n_points), "temperature", "point", "SetScalars")
    add(pd, rng.uniform(-1, 1, (n_points, 3)).astype(np.float32), "velocity", "point",
        "SetVectors")
    add(pd, rng.uniform(-1, 1, (n_points, 3)).astype(np.float32), "normals", "point",
        "SetNormals")
    add(pd, rng.uniform(0, 1, (n_points, 2)).astype(np.float32), "tex", "point", "SetTCoords")
    add(pd, (idx * 7 % 256).astype(np.uint8), "flags", "point")
    add(pd, (idx * 1000 - 12000).astype(np.int16), "level", "point")
    add(pd, (idx * 100000 - 7).astype(np.int32), "id32", "point")
    add(pd, (idx * 3000000000 - 5).astype(np.int64), "id64", "point")
    add(pd, rng.uniform(-3, 3, (n_points, 2)).astype(np.float32), "pair", "point")
    add(pd, rng.uniform(-3, 3, n_points), "my field", "point")

    cd = grid.GetCellData()
    colors = (np.arange(n_cells * 3).reshape(n_cells, 3) * 37 % 256).astype(np.uint8)
    add(cd, colors, "color", "cell", "SetScalars")
    add(cd, rng.uniform(-1e3, 1e3, (n_cells, 9)), "stress", "cell", "SetTensors")
    add(cd, (np.arange(n_cells) + 1).astype(np.int32), "material", "cell")
    add(cd, rng.uniform(0, 1, n_cells), "volume", "cell")
    add(cd, (np.arange(n_cells) * -4000000000).astype(np.int64), "gid", "cell")
    add(cd, rng.uniform(-1, 1, (n_cells, 3)).astype(np.float32), "flux", "cell", "SetVectors")

    writer = vtk.vtkUnstructuredGridWriter()
    writer.SetInputData(grid)
    writer.SetFileName(out)
    writer.SetFileVersion(version)
    if mode == "binary":
        writer.SetFileTypeToBinary()
    else:
        writer.SetFileTypeToASCII()
    if not writer.Write():
        sys.exit("VTK writer failed")

    expected = {
        "points": [float(np.float32(v)) for v in pts.ravel()],
        "cells": [{"type": corners[cells[i][0]][0], "ids": cells[i][1][:corners[cells[i][0]][1]]}
                  for i in kept],
        "dropped": n_cells - len(kept),
        "fields": fields,
    }
    with open(out + ".json", "w") as f:
        json.dump(expected, f)


if __name__ == "__main__":
    main()
