#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""VTK's oracle for `uvr generate mixed`: VTK's own .vtu reader reads the mesh, vtkCellValidator
finds every cell valid (faces oriented outwards, not inverted; jittered cells other than
tetrahedra have non-planar faces, which VTK calls "nonconvex" and nothing else), without jitter
vtkCellSizeFilter's volumes sum to 8 (the cube [-1, 1]^3; with non-planar faces VTK's own split
of each cell does not conform), and all four cell types are there. Exit status 77 (skipped)
without the vtk module."""
import argparse
import os
import subprocess
import sys
import tempfile

try:
    import vtk
except ImportError:
    print("skipped: no vtk module in /usr/bin/python3 (install python3-vtk9)")
    sys.exit(77)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--uvr", required=True)
    args = ap.parse_args()
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for cells, jitter, seed in [(270, "0", 1), (270, "0.1", 2), (900, "0.15", 7)]:
            path = os.path.join(tmp, f"m{seed}.vtu")
            subprocess.run([args.uvr, "-q", "generate", "mixed", "--cells", str(cells),
                            "--jitter", jitter, "--seed", str(seed), "-o", path], check=True)
            reader = vtk.vtkXMLUnstructuredGridReader()
            reader.SetFileName(path)
            reader.Update()
            grid = reader.GetOutput()
            validator = vtk.vtkCellValidator()
            validator.SetInputData(grid)
            sys.stdout.flush()
            saved = os.dup(1)  # the validator prints every invalid cell to stdout
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                validator.Update()
            os.dup2(saved, 1)
            os.close(saved)
            states = validator.GetOutput().GetCellData().GetArray("ValidityState")
            nonconvex = 16  # vtkCellStatus::Nonconvex: non-planar faces
            allowed = 0 if jitter == "0" else nonconvex
            invalid = [c for c in range(grid.GetNumberOfCells())
                       if states.GetValue(c) & ~allowed
                       or (states.GetValue(c) and grid.GetCellType(c) == 10)]
            sizes = vtk.vtkCellSizeFilter()
            sizes.SetInputData(grid)
            sizes.Update()
            volumes = sizes.GetOutput().GetCellData().GetArray("Volume")
            total = sum(volumes.GetValue(c) for c in range(grid.GetNumberOfCells()))
            types = {grid.GetCellType(c) for c in range(grid.GetNumberOfCells())}
            name = f"--cells {cells} --jitter {jitter} --seed {seed}"
            print(f"{name}: {grid.GetNumberOfCells()} cells, types {sorted(types)}, "
                  f"{len(invalid)} invalid, volume {total:.6f}")
            if invalid:
                failures.append(f"{name}: VTK finds {len(invalid)} invalid cells, first "
                                f"{invalid[0]} (state {states.GetValue(invalid[0])})")
            if abs(total - 8.0) > (1e-4 if jitter == "0" else 0.02):
                failures.append(f"{name}: volume {total}, expected 8")
            if types != {10, 12, 13, 14}:
                failures.append(f"{name}: cell types {sorted(types)}, expected 10, 12, 13, 14")
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
