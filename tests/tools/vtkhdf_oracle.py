#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Reads a VTKHDF file with VTK's own vtkHDFReader (python3-vtk9) and prints what it holds as
JSON: points, cell types, offsets (cells + 1), connectivity, the point and cell arrays
(components and values) and what VTK warned or complained of while reading ("messages"), for src/uvr/mesh/io/vtkhdf_test.cpp to compare with uvr's reader and
writer. Exit status 77 when vtk or its HDF reader is missing.
Usage: vtkhdf_oracle.py FILE
"""
import json
import sys

try:
    from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow
    from vtkmodules.vtkIOHDF import vtkHDFReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
except ImportError:
    sys.exit(77)


def arrays(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        if a is None:
            continue
        out[a.GetName()] = {
            "components": a.GetNumberOfComponents(),
            "values": vtk_to_numpy(a).astype(float).ravel().tolist(),
        }
    return out


def main():
    log = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(log)
    reader = vtkHDFReader()
    reader.SetFileName(sys.argv[1])
    reader.Update()
    grid = reader.GetOutput()
    cells = grid.GetCells()
    result = {
        "points": vtk_to_numpy(grid.GetPoints().GetData()).astype(float).ravel().tolist()
        if grid.GetPoints() else [],
        "types": [grid.GetCellType(i) for i in range(grid.GetNumberOfCells())],
        "offsets": vtk_to_numpy(cells.GetOffsetsArray()).astype(int).tolist(),
        "connectivity": vtk_to_numpy(cells.GetConnectivityArray()).astype(int).tolist(),
        "point_data": arrays(grid.GetPointData()),
        "cell_data": arrays(grid.GetCellData()),
        "messages": log.GetOutput(),
    }
    json.dump(result, sys.stdout)


if __name__ == "__main__":
    main()
