#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Writes .vtu/.pvtu test files with VTK's XML writers and meshio, each beside a JSON file of the
values VTK's own reader gets back from it (float32), for uvr's VTU reader tests.

Usage: write_vtu_variants.py OUTDIR   (writes OUTDIR/manifest.json listing every file)
"""
import itertools
import json
import os
import sys

import numpy as np
import vtk
from vtk.util import numpy_support

# VTK cell type -> (uvr linear type, corner count) for the volumetric cells uvr keeps.
VOLUMETRIC = {10: (10, 4), 11: (12, 8), 12: (12, 8), 13: (13, 6), 14: (14, 5),
              24: (10, 4), 25: (12, 8), 26: (13, 6), 27: (14, 5)}

ARRAY_CLASSES = [("i8", vtk.vtkTypeInt8Array, -128, 127), ("u8", vtk.vtkTypeUInt8Array, 0, 255),
                 ("i16", vtk.vtkTypeInt16Array, -32768, 32767),
                 ("u16", vtk.vtkTypeUInt16Array, 0, 65535),
                 ("i32", vtk.vtkTypeInt32Array, -2**31, 2**31 - 1),
                 ("u32", vtk.vtkTypeUInt32Array, 0, 2**32 - 1),
                 ("i64", vtk.vtkTypeInt64Array, -2**40 + 3, 2**40 + 5),
                 ("u64", vtk.vtkTypeUInt64Array, 0, 2**52 + 1)]


def make_grid(offset=0.0):
    """A small grid of mixed cells: linear 3D cells, a voxel, a quadratic tetra, a triangle."""
    rng = np.random.default_rng(7)
    n = 26
    pts = rng.uniform(-3.0, 5.0, size=(n, 3)) + offset
    points = vtk.vtkPoints()
    points.SetDataTypeToDouble()
    for p in pts:
        points.InsertNextPoint(*p)
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points)
    cells = [(10, [0, 1, 2, 3]), (12, list(range(4, 12))), (13, list(range(12, 18))),
             (14, [0, 4, 5, 6, 18]), (24, [0, 1, 2, 3, 19, 20, 21, 22, 23, 24]), (5, [1, 2, 3]),
             (11, [4, 5, 6, 7, 8, 9, 10, 11]), (10, [25, 3, 2, 1])]
    for t, ids in cells:
        idl = vtk.vtkIdList()
        for i in ids:
            idl.InsertNextId(i)
        grid.InsertNextCell(t, idl)
    pd = grid.GetPointData()
    for k, (name, cls, lo, hi) in enumerate(ARRAY_CLASSES):
        a = cls()
        a.SetName(name)
        for i in range(n):
            v = lo if i == 0 else hi if i == 1 else lo + (i * 7919 + k * 31) % (hi - lo + 1)
            a.InsertNextValue(v)
        pd.AddArray(a)
    f32 = vtk.vtkTypeFloat32Array()
    f32.SetName("f32")
    f64 = vtk.vtkTypeFloat64Array()
    f64.SetName("f64")
    vel = vtk.vtkTypeFloat32Array()
    vel.SetName("velocity")
    vel.SetNumberOfComponents(3)
    for i in range(n):
        f32.InsertNextValue(np.sin(i) * 1e5 + offset)
        f64.InsertNextValue(np.cos(i) / 3.0 - 1e-7 * i)
        vel.InsertNextTuple3(i * 0.1, -i * 0.2, 1.0 / (i + 1))
    for a in (f32, f64, vel):
        pd.AddArray(a)
    labels = vtk.vtkStringArray()
    labels.SetName("labels")
    for i in range(n):
        labels.InsertNextValue("p%d" % i)
    pd.AddArray(labels)
    cd = grid.GetCellData()
    cid = vtk.vtkTypeInt32Array()
    cid.SetName("cell_id")
    flags = vtk.vtkTypeUInt8Array()
    flags.SetName("flags")
    flags.SetNumberOfComponents(2)
    grad = vtk.vtkTypeFloat64Array()
    grad.SetName("gradient")
    grad.SetNumberOfComponents(3)
    for c in range(grid.GetNumberOfCells()):
        cid.InsertNextValue(100 + c)
        flags.InsertNextTuple2(c, 255 - c)
        grad.InsertNextTuple3(c / 7.0, -c, c * c + 0.5)
    for a in (cid, flags, grad):
        cd.AddArray(a)
    fd = vtk.vtkFieldData()
    tv = vtk.vtkTypeFloat64Array()
    tv.SetName("TimeValue")
    tv.InsertNextValue(1.5)
    fd.AddArray(tv)
    grid.SetFieldData(fd)
    return grid


def f32list(values):
    return [float(v) for v in np.asarray(values, dtype=np.float64).astype(np.float32).ravel()]


def expected_from(grid):
    """What uvr's reader must produce: VTK's values as float32, cells reduced to corner nodes."""
    pts = numpy_support.vtk_to_numpy(grid.GetPoints().GetData())
    types, offsets, indices, kept = [], [0], [], []
    for c in range(grid.GetNumberOfCells()):
        t = grid.GetCellType(c)
        if t not in VOLUMETRIC:
            continue
        ids = grid.GetCell(c).GetPointIds()
        lin, corners = VOLUMETRIC[t]
        nodes = [ids.GetId(k) for k in range(corners)]
        if t == 11:
            nodes = [nodes[i] for i in (0, 1, 3, 2, 4, 5, 7, 6)]
        types.append(lin)
        indices += nodes
        offsets.append(len(indices))
        kept.append(c)
    fields = []
    for assoc, data in (("point", grid.GetPointData()), ("cell", grid.GetCellData())):
        for i in range(data.GetNumberOfArrays()):
            a = data.GetAbstractArray(i)
            if not a.IsNumeric():
                continue
            v = numpy_support.vtk_to_numpy(a).reshape(a.GetNumberOfTuples(), -1)
            if assoc == "cell":
                v = v[kept]
            fields.append({"name": a.GetName(), "association": assoc,
                           "components": a.GetNumberOfComponents(), "values": f32list(v)})
    return {"pointCount": int(grid.GetNumberOfPoints()), "points": f32list(pts),
            "cellTypes": types, "cellOffsets": offsets, "cellIndices": indices, "fields": fields}


def read_back(path):
    reader = (vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu")
              else vtk.vtkXMLUnstructuredGridReader())
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    grid = make_grid()
    manifest = []

    def record(path, kind):
        with open(path + ".json", "w") as f:
            json.dump(expected_from(read_back(path)), f)
        manifest.append({"file": path, "kind": kind})

    modes = {"ascii": "SetDataModeToAscii", "binary": "SetDataModeToBinary",
             "appended": "SetDataModeToAppended"}
    for mode, encode, comp, header, order in itertools.product(
            modes, (True, False), ("none", "zlib"), ("UInt32", "UInt64"), ("le", "be")):
        name = "vtk_%s_%s_%s_%s_%s.vtu" % (mode, "b64" if encode else "raw", comp, header, order)
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetInputData(grid)
        w.SetFileName(os.path.join(out, name))
        getattr(w, modes[mode])()
        w.SetEncodeAppendedData(encode)
        w.SetCompressorTypeToZLib() if comp == "zlib" else w.SetCompressorTypeToNone()
        w.SetBlockSize(256)  # several compressed blocks per array
        w.SetHeaderTypeToUInt32() if header == "UInt32" else w.SetHeaderTypeToUInt64()
        w.SetByteOrderToBigEndian() if order == "be" else w.SetByteOrderToLittleEndian()
        if not w.Write():
            raise SystemExit("VTK failed to write " + name)
        record(os.path.join(out, name), "vtk")

    # Three pieces through the parallel writer, each extracted from the whole grid.
    piece = vtk.vtkExtractUnstructuredGridPiece()
    piece.SetInputData(grid)
    pw = vtk.vtkXMLPUnstructuredGridWriter()
    pw.SetInputConnection(piece.GetOutputPort())
    pw.SetFileName(os.path.join(out, "three.pvtu"))
    pw.SetNumberOfPieces(3)
    pw.SetStartPiece(0)
    pw.SetEndPiece(2)
    pw.SetDataModeToAppended()
    pw.SetCompressorTypeToZLib()
    if not pw.Write():
        raise SystemExit("VTK failed to write three.pvtu")
    record(os.path.join(out, "three.pvtu"), "pvtu")

    # meshio writes its own flavour (header and data base64 runs, its own attributes).
    import meshio
    mgrid = read_back(os.path.join(out, "vtk_ascii_raw_none_UInt32_le.vtu"))
    pts = numpy_support.vtk_to_numpy(mgrid.GetPoints().GetData())
    conn = numpy_support.vtk_to_numpy(mgrid.GetCells().GetConnectivityArray())
    offs = numpy_support.vtk_to_numpy(mgrid.GetCells().GetOffsetsArray())
    names = {10: "tetra", 12: "hexahedron", 13: "wedge", 14: "pyramid", 24: "tetra10",
             5: "triangle", 11: "hexahedron"}
    blocks, cell_data = [], {}
    for c in range(mgrid.GetNumberOfCells()):  # one block per cell keeps the file's cell order
        t = mgrid.GetCellType(c)
        ids = conn[offs[c]:offs[c + 1]]
        if t == 11:
            ids = ids[[0, 1, 3, 2, 4, 5, 7, 6]]
        blocks.append((names[t], ids.reshape(1, -1)))
    for i in range(mgrid.GetCellData().GetNumberOfArrays()):
        a = mgrid.GetCellData().GetArray(i)
        v = numpy_support.vtk_to_numpy(a)
        cell_data[a.GetName()] = [v[c:c + 1] for c in range(mgrid.GetNumberOfCells())]
    point_data = {}
    for i in range(mgrid.GetPointData().GetNumberOfArrays()):
        a = mgrid.GetPointData().GetAbstractArray(i)
        if a.IsNumeric():
            point_data[a.GetName()] = numpy_support.vtk_to_numpy(a)
    m = meshio.Mesh(pts, blocks, point_data=point_data, cell_data=cell_data)
    for binary, comp in ((False, None), (True, None), (True, "zlib")):
        name = "meshio_%s_%s.vtu" % ("binary" if binary else "ascii", comp or "none")
        path = os.path.join(out, name)
        meshio.write(path, m, file_format="vtu", binary=binary, compression=comp)
        record(path, "meshio")

    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump(manifest, f)


if __name__ == "__main__":
    main()
