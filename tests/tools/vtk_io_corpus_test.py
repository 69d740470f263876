#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Reads what real writers write, as VTK reads it: a corpus of files written at test time by VTK's
writers (XML in ascii, inline binary and appended modes with every compressor and header type,
the parallel writer, the legacy writer in ASCII and BINARY, 4.2 and 5.1), by meshio, and by hand
in the style of a lattice-Boltzmann code ('+11047' counts, signed and exponent numbers), plus the
real meshes of the shared data. Each file is converted by `uvr convert` to a zlib .vtu, an LZ4
.vtu and a legacy .vtk; VTK's own readers read the original and every conversion, and the points,
cells (corner nodes of the volumetric cells uvr keeps) and fields (as float32) must be identical.

Usage: vtk_io_corpus_test.py --uvr BIN --out DIR [--data SHARED_DATA]
Exit status 0: all identical; 1: a file misread (each named); 77: no vtk/numpy/meshio here.
"""
import argparse
import os
import re
import subprocess
import sys

try:
    import numpy as np
    import vtk
    import meshio
except ImportError as e:  # the test is skipped, not failed
    print("skipped:", e)
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from write_vtu_variants import expected_from, make_grid  # noqa: E402

vtk.vtkObject.GlobalWarningDisplayOff()


def read_vtk(path):
    """VTK's own reader of the file: the legacy reader for .vtk, the generic XML one otherwise."""
    if path.endswith(".vtk"):
        r = vtk.vtkUnstructuredGridReader()
        for kind in ("Scalars", "Vectors", "Normals", "Tensors", "ColorScalars", "TCoords",
                     "Fields"):
            getattr(r, "ReadAll%sOn" % kind)()
    else:
        r = vtk.vtkXMLGenericDataObjectReader()
    r.SetFileName(path)
    r.Update()
    out = r.GetOutput()
    if out is None or out.GetPoints() is None or r.GetErrorCode() != 0:
        raise RuntimeError("VTK could not read " + path)
    return out


def same(expected, got):
    """The first difference between two expected_from() dicts, or None."""
    for key in ("pointCount", "cellTypes", "cellOffsets", "cellIndices"):
        if expected[key] != got[key]:
            return "%s differ" % key
    if not np.array_equal(np.float32(expected["points"]), np.float32(got["points"]),
                          equal_nan=True):
        return "points differ"
    want = {(f["association"], f["name"]): f for f in expected["fields"]}
    have = {(f["association"], f["name"]): f for f in got["fields"]}
    if set(want) != set(have):
        return "fields differ: expected %s, got %s" % (sorted(want), sorted(have))
    for k, f in want.items():
        g = have[k]
        if f["components"] != g["components"]:
            return "%s field %s: %d components, expected %d" % (k[0], k[1], g["components"],
                                                                 f["components"])
        if not np.array_equal(np.float32(f["values"]), np.float32(g["values"]), equal_nan=True):
            return "%s field %s: values differ" % k
    return None


# ---- the corpus ----

def vtk_xml_files(out, grid):
    files = []
    modes = {"ascii": "SetDataModeToAscii", "binary": "SetDataModeToBinary",
             "appended": "SetDataModeToAppended"}
    compressors = {"none": "SetCompressorTypeToNone", "zlib": "SetCompressorTypeToZLib",
                   "lz4": "SetCompressorTypeToLZ4", "lzma": "SetCompressorTypeToLZMA"}
    for mode in modes:
        for comp in (["none"] if mode == "ascii" else compressors):
            for header in ("UInt32", "UInt64"):
                name = os.path.join(out, "vtk_%s_%s_%s.vtu" % (mode, comp, header))
                w = vtk.vtkXMLUnstructuredGridWriter()
                w.SetInputData(grid)
                w.SetFileName(name)
                getattr(w, modes[mode])()
                getattr(w, compressors[comp])()
                w.SetBlockSize(256)  # several blocks per array
                w.SetHeaderTypeToUInt32() if header == "UInt32" else w.SetHeaderTypeToUInt64()
                if not w.Write():
                    raise SystemExit("VTK failed to write " + name)
                files.append(name)
    for comp in ("lz4", "lzma"):
        piece = vtk.vtkExtractUnstructuredGridPiece()
        piece.SetInputData(grid)
        pw = vtk.vtkXMLPUnstructuredGridWriter()
        pw.SetInputConnection(piece.GetOutputPort())
        name = os.path.join(out, "vtk_four_%s.pvtu" % comp)
        pw.SetFileName(name)
        pw.SetNumberOfPieces(4)
        pw.SetStartPiece(0)
        pw.SetEndPiece(3)
        pw.SetDataModeToAppended()
        getattr(pw, compressors[comp])()
        if not pw.Write():
            raise SystemExit("VTK failed to write " + name)
        files.append(name)
    return files


def vtk_legacy_files(out, grid):
    """VTK's legacy writer, without the string array (uvr's legacy reader refuses those)."""
    copy = vtk.vtkUnstructuredGrid()
    copy.DeepCopy(grid)
    copy.GetPointData().RemoveArray("labels")
    grid = copy
    files = []
    for binary in (False, True):
        for version in (42, 51):
            name = os.path.join(out, "vtk_legacy_%s_%d.vtk" % ("binary" if binary else "ascii",
                                                               version))
            w = vtk.vtkUnstructuredGridWriter()
            w.SetInputData(grid)
            w.SetFileName(name)
            w.SetFileVersion(version)
            w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
            if not w.Write():
                raise SystemExit("VTK failed to write " + name)
            files.append(name)
    return files


def meshio_files(out):
    """meshio's flavours of .vtu and legacy .vtk, of a mesh of volumetric cells only."""
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.0, 1.0, size=(20, 3))
    cells = [("tetra", np.array([[0, 1, 2, 3], [4, 5, 6, 7]])),
             ("hexahedron", np.array([list(range(8, 16))])),
             ("wedge", np.array([[14, 15, 16, 17, 18, 19]]))]
    m = meshio.Mesh(pts, cells,
                    point_data={"temperature": rng.normal(size=20).astype(np.float32),
                                "velocity": rng.normal(size=(20, 3)),
                                "id": np.arange(20, dtype=np.int32)},
                    cell_data={"pressure": [np.array([1.5, -2.0]), np.array([3e10]),
                                            np.array([np.nan])]})
    files = []
    for binary, comp in ((False, None), (True, None), (True, "zlib"), (True, "lzma")):
        name = os.path.join(out, "meshio_%s_%s.vtu" % ("binary" if binary else "ascii",
                                                        comp or "none"))
        meshio.write(name, m, file_format="vtu", binary=binary, compression=comp)
        files.append(name)
    # VTK 9.1's legacy reader knows no 'vtktypeint32' (meshio's name for int32) and no ASCII
    # nan: the legacy files hold what VTK can read, to be compared with it.
    m.point_data["id"] = m.point_data["id"].astype(np.int64)
    m.cell_data["pressure"][2] = np.array([7.0])
    for binary in (False, True):
        name = os.path.join(out, "meshio_legacy_%s.vtk" % ("binary" if binary else "ascii"))
        meshio.write(name, m, file_format="vtk", binary=binary)
        files.append(name)
    return files


NUMBER = r"(?<![\w.+-])-?[0-9]+(?:\.[0-9]*)?(?:e[+-]?[0-9]+)?(?![\w.])"


def signed(text, real):
    """'+'-signs the numbers of text that have none, pads some with spaces and, in real arrays,
    writes some integers with an exponent (VTK reads "+3e0" as 3.0 in a real array only)."""
    count = [0]

    def one(match):
        t = match.group(0)
        count[0] += 1
        if real and "." in t and "e" not in t and count[0] % 2:
            t += "E+00" if count[0] % 4 == 1 else "e0"  # the same decimal value
        if t.startswith("-"):
            return t
        if re.fullmatch(r"[0-9]+", t) and len(t) < 6 and int(t) % 3 == 0 and t != "0":
            return "+%se0" % t if real and int(t) % 2 else "  +%s" % t
        return "+" + t
    return re.sub(NUMBER, one, text)


def handmade_files(out, grid):
    """A 4-piece .pvtu whose ASCII pieces write NumberOfPoints="+11047"-style counts, signed and
    exponent numbers and padded attributes (as a lattice-Boltzmann code does), and legacy ASCII
    files with signed counts and values."""
    piece = vtk.vtkExtractUnstructuredGridPiece()
    piece.SetInputData(grid)
    pw = vtk.vtkXMLPUnstructuredGridWriter()
    pw.SetInputConnection(piece.GetOutputPort())
    name = os.path.join(out, "lbm.pvtu")
    pw.SetFileName(name)
    pw.SetNumberOfPieces(4)
    pw.SetStartPiece(0)
    pw.SetEndPiece(3)
    pw.SetDataModeToAscii()
    if not pw.Write():
        raise SystemExit("VTK failed to write " + name)
    for k in range(4):
        path = os.path.join(out, "lbm_%d.vtu" % k)
        text = open(path).read()
        # Counts and attributes: '+', spaces around them.
        text = re.sub(r'(NumberOf(?:Points|Cells|Components))="(\d+)"',
                      lambda m: '%s=" +%s "' % (m.group(1), m.group(2)), text)
        # Values of the integer and real arrays: signs and exponents, never inside names.
        def sign_array(m):
            real = 'type="Float' in m.group(1)
            return m.group(1) + signed(m.group(2), real) + m.group(3)
        text = re.sub(r'(<DataArray (?:(?!type="String")[^>])*format="ascii"[^>]*>)([^<]*)(<)',
                      sign_array, text)
        open(path, "w").write(text)
    files = [name]
    for version in (42, 51):
        src = os.path.join(out, "vtk_legacy_ascii_%d.vtk" % version)
        lines = open(src).read().split("\n")
        signed_lines = []
        real = False  # the array being written holds float or double values
        for line in lines:
            if re.fullmatch(r"[-+0-9.eE ]+", line.strip() or "x"):
                line = signed(line, real)
            elif not line.startswith(("LOOKUP_TABLE", "METADATA", "INFORMATION", "NAME", "DATA")):
                real = "float" in line.split() or "double" in line.split()
            if re.match(r"(POINTS|CELLS|CELL_TYPES|POINT_DATA|CELL_DATA|OFFSETS) ", line):
                line = re.sub(r" (\d+)", r" +\1", line)
            signed_lines.append(line)
        path = os.path.join(out, "signed_legacy_%d.vtk" % version)
        open(path, "w").write("\n".join(signed_lines))
        files.append(path)
    return files


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--uvr", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--data", default="")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    grid = make_grid()
    corpus = (vtk_xml_files(args.out, grid) + vtk_legacy_files(args.out, grid) +
              meshio_files(args.out) + handmade_files(args.out, grid))
    if args.data and os.path.isdir(args.data):
        corpus += [os.path.join(args.data, f) for f in sorted(os.listdir(args.data))
                   if f.endswith((".vtk", ".vtu"))]
    else:
        print("note: no shared data; the real meshes are left out")
    failures = []
    for path in corpus:
        base = os.path.basename(path)
        try:
            expected = expected_from(read_vtk(path))
        except RuntimeError as e:
            failures.append("%s: %s" % (base, e))
            continue
        for suffix, flags in (("zlib.vtu", []), ("lz4.vtu", ["--compress", "lz4"]),
                              ("legacy.vtk", [])):
            converted = os.path.join(args.out, "converted", base + "." + suffix)
            os.makedirs(os.path.dirname(converted), exist_ok=True)
            run = subprocess.run([args.uvr, "-q", "convert", path, converted] + flags,
                                 capture_output=True, text=True)
            if run.returncode != 0:
                failures.append("%s: uvr convert to %s failed (%d): %s" % (
                    base, suffix, run.returncode, run.stderr.strip()))
                continue
            try:
                problem = same(expected, expected_from(read_vtk(converted)))
            except RuntimeError as e:
                problem = str(e)
            status = "ok" if problem is None else "MISREAD: " + problem
            print("%-40s -> %-10s %s" % (base, suffix, status))
            if problem:
                failures.append("%s -> %s: %s" % (base, suffix, problem))
    print("%d files, %d failures" % (len(corpus), len(failures)))
    for f in failures:
        print("FAIL", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
