#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""VTK's side of the Exodus II reader tests (src/uvr/mesh/io/exodus_test.cpp).

  exodus_oracle.py write OUT.e
      Writes an Exodus II file with VTK's vtkExodusIIWriter: one cell per cube, cubes spread along
      x and jittered, blocks (ElementBlockIds) of tetrahedra, hexahedra, wedges, pyramids and
      triangles, the nodal variables temp and vel (a vector), the element variable pres, and
      three time steps (0, 0.5, 1.5) whose values change.
  exodus_oracle.py series MESH.vtk OUT.e
      Writes a VTK legacy mesh as an Exodus II series of three time steps (0, 1, 2) of one
      geometry, its point field "wave" moving with the time (uvr animate under mpirun reads its
      steps by parts: tests/tools/mpi_render_test.py).
  exodus_oracle.py dump FILE.e OUT.json STEP [STEP...]
      Reads FILE with VTK's vtkExodusIIReader (every nodal and element result array, points not
      squeezed, so point ids are the file's node numbers minus one) and writes, per step, what
      uvr's reader must give: points, the volume cells (types reduced to linear, corner ids),
      point fields and cell fields (NaN for a block that lacks a variable), plus the times.

Exit status 77 when python3-vtk9 is missing.
"""
import json
import math
import sys

try:
    import numpy as np
    import vtk
    from vtkmodules.util import numpy_support as ns
    from vtkmodules.util.vtkAlgorithm import VTKPythonAlgorithmBase
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e}", file=sys.stderr)
    sys.exit(77)

# VTK cell type -> the linear volume type whose corners come first (as uvr reads them).
LINEAR = {10: 10, 24: 10, 71: 10, 12: 12, 25: 12, 29: 12, 72: 12, 13: 13, 26: 13, 32: 13, 73: 13,
          14: 14, 27: 14, 37: 14, 74: 14}
CORNERS = {10: 4, 12: 8, 13: 6, 14: 5}
# VTK's generated arrays, not the file's variables.
GENERATED = {"ObjectId", "GlobalElementId", "GlobalNodeId", "PedigreeElementId",
             "PedigreeNodeId", "ImplicitElementId", "ImplicitNodeId", "FileId"}


class Source(VTKPythonAlgorithmBase):
    """An unstructured grid of one cell per cube with time-dependent fields."""

    TIMES = [0.0, 0.5, 1.5]
    # (VTK type, corner indices into the cube's points 0..7 = (x, y, z) bits, in VTK order)
    CELLS = [(vtk.VTK_TETRA, [0, 1, 2, 4]),
             (vtk.VTK_HEXAHEDRON, [0, 1, 3, 2, 4, 5, 7, 6]),
             (vtk.VTK_WEDGE, [0, 2, 1, 4, 6, 5]),  # (0, 1, 2)'s normal away from (3, 4, 5)
             (vtk.VTK_PYRAMID, [0, 1, 3, 2, 4]),
             (vtk.VTK_TRIANGLE, [0, 1, 2])]

    def __init__(self):
        super().__init__(nInputPorts=0, nOutputPorts=1, outputType="vtkUnstructuredGrid")

    def RequestInformation(self, request, inInfo, outInfo):
        info = outInfo.GetInformationObject(0)
        sddp = vtk.vtkStreamingDemandDrivenPipeline
        info.Set(sddp.TIME_STEPS(), self.TIMES, len(self.TIMES))
        info.Set(sddp.TIME_RANGE(), [self.TIMES[0], self.TIMES[-1]], 2)
        return 1

    def RequestData(self, request, inInfo, outInfo):
        info = outInfo.GetInformationObject(0)
        sddp = vtk.vtkStreamingDemandDrivenPipeline
        t = info.Get(sddp.UPDATE_TIME_STEP()) if info.Has(sddp.UPDATE_TIME_STEP()) else 0.0
        g = vtk.vtkUnstructuredGrid.GetData(outInfo, 0)
        g.Allocate(64)
        rng = np.random.default_rng(7)
        pts, types, blocks = [], [], []
        for k in range(20):
            block, (vtype, corners) = k % len(self.CELLS), self.CELLS[k % len(self.CELLS)]
            base = len(pts)
            for b in range(8):
                pts.append([2.0 * k + (b & 1), (b >> 1) & 1, (b >> 2) & 1])
            g.InsertNextCell(vtype, len(corners), [base + c for c in corners])
            blocks.append(10 + block)
        pts = np.array(pts) + rng.uniform(-0.1, 0.1, (len(pts), 3))
        p = vtk.vtkPoints()
        p.SetData(ns.numpy_to_vtk(pts, deep=1))
        g.SetPoints(p)
        n = g.GetNumberOfCells()

        def add(data, name, values):
            a = ns.numpy_to_vtk(np.ascontiguousarray(values), deep=1)
            a.SetName(name)
            data.AddArray(a)

        add(g.GetPointData(), "temp", np.sin(pts[:, 0]) + t)
        add(g.GetPointData(), "vel", pts * (1.0 + t))
        add(g.GetCellData(), "pres", np.arange(n, dtype=float) * 0.25 + 10.0 * t)
        add(g.GetCellData(), "ElementBlockIds", np.array(blocks, dtype=np.int32))
        return 1


class MeshSeries(VTKPythonAlgorithmBase):
    """A VTK legacy mesh (one element block) whose point field "wave" moves over three steps."""

    TIMES = [0.0, 1.0, 2.0]

    def __init__(self, path):
        super().__init__(nInputPorts=0, nOutputPorts=1, outputType="vtkUnstructuredGrid")
        r = vtk.vtkUnstructuredGridReader()
        r.SetFileName(path)
        r.Update()
        self.grid = r.GetOutput()

    RequestInformation = Source.RequestInformation

    def RequestData(self, request, inInfo, outInfo):
        info = outInfo.GetInformationObject(0)
        sddp = vtk.vtkStreamingDemandDrivenPipeline
        t = info.Get(sddp.UPDATE_TIME_STEP()) if info.Has(sddp.UPDATE_TIME_STEP()) else 0.0
        g = vtk.vtkUnstructuredGrid.GetData(outInfo, 0)
        g.CopyStructure(self.grid)
        pts = ns.vtk_to_numpy(self.grid.GetPoints().GetData()).astype(float)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        u = (pts - lo) / np.maximum(hi - lo, 1e-30)
        wave = np.sin(2.0 * math.pi * u[:, 0] + t) + u[:, 2]
        a = ns.numpy_to_vtk(np.ascontiguousarray(wave), deep=1)
        a.SetName("wave")
        g.GetPointData().AddArray(a)
        b = ns.numpy_to_vtk(np.ones(g.GetNumberOfCells(), dtype=np.int32), deep=1)
        b.SetName("ElementBlockIds")
        g.GetCellData().AddArray(b)
        return 1


def write(out, source=None):
    w = vtk.vtkExodusIIWriter()
    source = source or Source()  # kept alive while the writer pulls its steps
    w.SetInputConnection(source.GetOutputPort())
    w.SetFileName(out)
    w.WriteAllTimeStepsOn()
    w.Write()


def dump(path, out, steps):
    r = vtk.vtkExodusIIReader()
    r.SetFileName(path)
    r.UpdateInformation()
    r.SetAllArrayStatus(vtk.vtkExodusIIReader.NODAL, 1)
    r.SetAllArrayStatus(vtk.vtkExodusIIReader.ELEM_BLOCK, 1)
    r.SetSqueezePoints(False)
    r.SetGenerateObjectIdCellArray(False)
    times = [r.GetTimeStepRange()[0] + i for i in range(r.GetNumberOfTimeSteps())]
    info_times = r.GetOutputInformation(0).Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    result = {"times": list(info_times) if info_times else [0.0], "steps": []}
    for step in steps:
        r.SetTimeStep(step)
        r.Update()
        mb = r.GetOutput()
        it = mb.NewIterator()
        it.InitTraversal()
        grids = []
        while not it.IsDoneWithTraversal():
            grids.append(it.GetCurrentDataObject())
            it.GoToNextItem()
        if not grids:
            print(f"VTK's reader read no element block from {path}", file=sys.stderr)
            sys.exit(1)
        rec = {"points": [], "types": [], "ids": [], "point": {}, "cell": {}}
        if grids:
            pts = ns.vtk_to_numpy(grids[0].GetPoints().GetData()).astype(float)
            rec["points"] = pts.ravel().tolist()
            pd = grids[0].GetPointData()
            for i in range(pd.GetNumberOfArrays()):
                a = pd.GetArray(i)
                if a.GetName() in GENERATED:
                    continue
                rec["point"][a.GetName()] = {"components": a.GetNumberOfComponents(),
                                             "values": ns.vtk_to_numpy(a).astype(float).ravel().tolist()}
        names = {}
        for g in grids:
            cd = g.GetCellData()
            for i in range(cd.GetNumberOfArrays()):
                a = cd.GetArray(i)
                if a.GetName() not in GENERATED:
                    names[a.GetName()] = a.GetNumberOfComponents()
        cell = {k: [] for k in names}
        for g in grids:
            kept = []
            for c in range(g.GetNumberOfCells()):
                t = g.GetCellType(c)
                if t not in LINEAR:
                    continue
                lin = LINEAR[t]
                ids = g.GetCell(c).GetPointIds()
                rec["types"].append(lin)
                rec["ids"] += [ids.GetId(k) for k in range(CORNERS[lin])]
                kept.append(c)
            cd = g.GetCellData()
            for name, comps in names.items():
                a = cd.GetArray(name)
                v = ns.vtk_to_numpy(a).astype(float).reshape(-1, comps) if a else None
                for c in kept:
                    cell[name] += v[c].tolist() if v is not None else [math.nan] * comps
        rec["cell"] = {k: {"components": names[k], "values": v} for k, v in cell.items()}
        result["steps"].append(rec)
    def no_nan(x):  # JSON has no NaN: null stands for it
        if isinstance(x, float) and math.isnan(x):
            return None
        if isinstance(x, list):
            return [no_nan(v) for v in x]
        if isinstance(x, dict):
            return {k: no_nan(v) for k, v in x.items()}
        return x

    with open(out, "w") as f:
        json.dump(no_nan(result), f, allow_nan=False)


def main():
    if len(sys.argv) >= 3 and sys.argv[1] == "write":
        write(sys.argv[2])
    elif len(sys.argv) >= 4 and sys.argv[1] == "series":
        write(sys.argv[3], MeshSeries(sys.argv[2]))
    elif len(sys.argv) >= 5 and sys.argv[1] == "dump":
        dump(sys.argv[2], sys.argv[3], [int(s) for s in sys.argv[4:]])
    else:
        print(__doc__, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
