# SPDX-License-Identifier: MIT
"""Writes the hostile fuzzing seeds of issue 10 into OUTDIR/<target>/: inputs that only reach
nesting, amplification and extreme values when the fuzzers are allowed long inputs (scripts/fuzz.sh
sets -max_len per target). The render target's seeds are small and kept in fuzz/seeds/render/
(written by `write_hostile_seeds.py fuzz/seeds render`), so that the test suite replays them.
Usage: write_hostile_seeds.py OUTDIR [TARGET...]   (default: every target but render)
"""
import lzma
import os
import struct
import sys
import zlib


def write(folder, name, data):
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def le32(v):
    return struct.pack("<I", v)


def appended_zlib_vtu(pieces, data):
    """A zlib-compressed .vtu whose Pieces read raw appended data."""
    head = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
            'byte_order="LittleEndian" header_type="UInt32" '
            'compressor="vtkZLibDataCompressor">\n<UnstructuredGrid>\n' + pieces +
            '</UnstructuredGrid>\n<AppendedData encoding="raw">\n_').encode()
    return head + data + b"\n</AppendedData>\n</VTKFile>\n"


def points_piece(points):
    return ('<Piece NumberOfPoints="%d" NumberOfCells="0"><Points><DataArray type="Float32" '
            'NumberOfComponents="3" format="appended" offset="0"/></Points></Piece>\n' % points)


def zlib_zeros_payload(n):
    stream = zlib.compress(bytes(n), 9)
    return le32(1) + le32(n) + le32(n) + le32(len(stream)) + stream


def colormap_seeds(out):
    # 100,000 levels of nesting (200 KB), bare and where the reader expects RGBPoints.
    deep = 100000
    write(out, "nested_array.json", "[" * deep + "]" * deep)
    write(out, "nested_rgbpoints.json",
          '[{"Name": "deep", "RGBPoints": ' + "[" * deep + "0" + "]" * deep + "}]")
    write(out, "nested_object.json", '{"a":' * 5000 + "1" + "}" * 5000)
    # Invalid UTF-8 and control characters in a name, a huge number, UTF-16 text.
    write(out, "bad_utf8_name.json",
          b'[{"Name": "\xff\xfe\x80bad\x01", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]}]')
    write(out, "huge_numbers.json",
          '[{"RGBPoints": [-3e38, 0, 0, 0, 3e38, 1, 1, 1], "Points": [-3e38, 0, 0.5, 0, '
          '3e38, 1, 0.5, 0]}]')
    write(out, "utf16.json",
          '[{"RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]}]'.encode("utf-16"))


def vtu_seeds(out):
    # zlib block headers declaring 4 GiB in 65536 blocks of 1 compressed byte each (330 KB).
    blocks, block = 65536, 65532
    data = le32(blocks) + le32(block) + le32(0) + le32(1) * blocks + b"x" * blocks
    write(out, "header_bomb.vtu", appended_zlib_vtu(points_piece(blocks * block // 12), data))
    # 3000 Pieces reading one compressed block of 1.2 MB of zeros (300M points declared).
    write(out, "reused_block.vtu",
          appended_zlib_vtu(points_piece(100000) * 3000, zlib_zeros_payload(1200000)))
    # Many point fields in two Pieces (a quadratic merge took minutes).
    piece = ('<Piece NumberOfPoints="1" NumberOfCells="0"><Points><DataArray type="Float32" '
             'NumberOfComponents="3" format="ascii">0 0 0</DataArray></Points><PointData>')
    piece += "".join('<DataArray type="Float32" Name="f%d" format="ascii">%d</DataArray>' % (f, f)
                     for f in range(5000))
    piece += "</PointData></Piece>\n"
    write(out, "many_fields.vtu",
          '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1">\n'
          "<UnstructuredGrid>\n" + piece + piece + "</UnstructuredGrid>\n</VTKFile>\n")
    # LZ4 and LZMA blocks: a valid LZ4 block of 4 points written as literals only (token 0xf0,
    # literal length 15 + 33), one whose header declares 4 GiB from 1-byte blocks, and an LZMA
    # (xz) block of 100 points of zeros.
    lz4 = b"\xf0\x21" + bytes(48)
    write(out, "lz4_literals.vtu",
          appended_zlib_vtu(points_piece(4), le32(1) + le32(48) + le32(48) + le32(len(lz4)) + lz4)
          .replace(b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor"))
    write(out, "lz4_header_bomb.vtu",
          appended_zlib_vtu(points_piece(blocks * block // 12), data)
          .replace(b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor"))
    xz = lzma.compress(bytes(1200), format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC64)
    write(out, "lzma_zeros.vtu",
          appended_zlib_vtu(points_piece(100), le32(1) + le32(1200) + le32(1200) + le32(len(xz)) + xz)
          .replace(b"vtkZLibDataCompressor", b"vtkLZMADataCompressor"))
    # Round three: an LZMA block table declaring 6.3 GB from 200 KB of garbage blocks (within
    # LZMA's 32768:1 per block), and 3,000 Pieces reading one LZMA block of 1.2 MB of zeros.
    lblocks, lblock, lsize = 200, 33554424, 1024
    data = le32(lblocks) + le32(lblock) + le32(0) + le32(lsize) * lblocks + b"x" * (lblocks * lsize)
    write(out, "lzma_lying_block_table.vtu",
          appended_zlib_vtu(points_piece(lblocks * lblock // 12), data)
          .replace(b"vtkZLibDataCompressor", b"vtkLZMADataCompressor"))
    xz = lzma.compress(bytes(1200000), format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC64)
    write(out, "lzma_reused_block.vtu",
          appended_zlib_vtu(points_piece(100000) * 3000,
                            le32(1) + le32(1200000) + le32(1200000) + le32(len(xz)) + xz)
          .replace(b"vtkZLibDataCompressor", b"vtkLZMADataCompressor"))


def pvd_seeds(out):
    # The fuzz target's input.pvd naming itself through './' and a missing folder's '..'.
    for name, self_name in (("self_dot.pvd", "./input.pvd"),
                            ("self_parent.pvd", "nowhere/../input.pvd")):
        write(out, name, '<VTKFile type="Collection"><Collection>\n<DataSet timestep="0" '
              'file="step0.vtu"/>\n<DataSet timestep="1" file="%s"/>\n</Collection></VTKFile>\n'
              % self_name)


def pvtu_seeds(out):
    # One piece (the fuzz target's piece0.vtu) listed 60 times.
    text = ('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="0.1">\n'
            '<PUnstructuredGrid GhostLevel="0">\n<PPoints><PDataArray type="Float32" '
            'NumberOfComponents="3"/></PPoints>\n')
    text += '<Piece Source="piece0.vtu"/>\n' * 60
    write(out, "same_piece_60_times.pvtu", text + "</PUnstructuredGrid>\n</VTKFile>\n")


def vtk_legacy_seeds(out):
    # A tetrahedron with a field spanning the float range, a name with invalid UTF-8 and a
    # newline-like control character, an unused NaN point and 2000 more point fields.
    head = ("# vtk DataFile Version 3.0\nhostile\nASCII\nDATASET UNSTRUCTURED_GRID\n"
            "POINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 nan nan nan\nCELLS 1 5\n4 0 1 2 3\n"
            "CELL_TYPES 1\n10\nPOINT_DATA 5\n")
    body = "SCALARS wide float 1\nLOOKUP_TABLE default\n-3e38 3e38 -1e38 1e38 0\n"
    body += "SCALARS bad\xff\x01name float 1\nLOOKUP_TABLE default\n0 1 2 3 4\n"
    body += "".join("SCALARS f%d float 1\nLOOKUP_TABLE default\n0 1 2 3 %d\n" % (f, f)
                    for f in range(2000))
    write(out, "hostile_fields.vtk", (head + body).encode("latin-1"))
    # Counts no file of this size can hold.
    write(out, "huge_counts.vtk",
          "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
          "POINTS 4000000000 float\n")


def render_seed(points, cells, values, flags, view=0, extra=(), exact=False):
    """An input of the render target (fuzzRender in fuzz/fuzz_targets.h); exact picks the exact
    integrator where the method bits say reference."""
    types = {4: 0, 5: 1, 6: 2, 8: 3}
    data = bytes([(len(points) - 4) | (0x10 if exact else 0), len(cells) - 1, flags, view])
    for p in points:
        data += struct.pack("<3f", *p)
    for c in cells:
        data += bytes([types[len(c)]] + list(c))
    data += struct.pack("<%df" % len(values), *values)
    data += struct.pack("<%df" % len(extra), *extra)
    return data


def render_seeds(out):
    tet = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    cube = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    hexa = [(0, 1, 3, 2, 4, 5, 7, 6)]
    flags_for = lambda method, opacity, cell=0: cell | (opacity << 1) | (method << 3)
    for method in range(4):
        write(out, "tet_m%d.bin" % method,
              render_seed(tet, [(0, 1, 2, 3)], [0, 1, 2, 3], flags_for(method, 2)))
        write(out, "hex_m%d.bin" % method,
              render_seed(cube, hexa, [float(i) for i in range(8)], flags_for(method, 0)))
    write(out, "tet_exact.bin",
          render_seed(tet, [(0, 1, 2, 3)], [0, 1, 2, 3], flags_for(0, 2), exact=True))
    write(out, "hex_exact.bin",
          render_seed(cube, hexa, [float(i) for i in range(8)], flags_for(0, 0), exact=True))
    # Values spanning the float range; a cell field at the float's ends.
    write(out, "wide_field.bin", render_seed(tet, [(0, 1, 2, 3)], [-3e38, 3e38, -1e38, 1e38],
                                             flags_for(1, 0)))
    write(out, "wide_cell_field.bin",
          render_seed(tet, [(0, 1, 2, 3)], [3.4e38], flags_for(0, 3, 1)))
    # Coordinates near 1e38, a mesh 1e-30 across, far from the origin.
    for name, scale, shift in (("huge", 1e37, 0.0), ("tiny", 1e-30, 0.0), ("far", 1.0, 1e7)):
        pts = [tuple(c * scale + shift for c in p) for p in tet]
        write(out, "coords_%s.bin" % name,
              render_seed(pts, [(0, 1, 2, 3)], [0, 1, 2, 3], flags_for(1, 0)))
    # A sliver 1e-7 thick and an unused NaN point.
    write(out, "sliver.bin", render_seed([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0.3, 0.3, 1e-7)],
                                         [(0, 1, 2, 3)], [0, 1, 2, 3], flags_for(0, 0)))
    nan = float("nan")
    write(out, "unused_nan.bin", render_seed(tet + [(nan, nan, nan)], [(0, 1, 2, 3)],
                                             [0, 1, 2, 3, nan], flags_for(1, 1)))
    # A given camera (position, focal point, view up), a range and a step.
    camera = (0.5, 0.5, 3, 0.3, 0.3, 0.3, 0, 1, 0)
    write(out, "camera_range_step.bin",
          render_seed(tet, [(0, 1, 2, 3)], [0, 1, 2, 3], flags_for(1, 1) | 0xE0, 29,
                      (0.5, 2.5, 0.05) + camera))


WRITERS = {"colormap_json": colormap_seeds, "vtu": vtu_seeds, "pvtu": pvtu_seeds, "pvd": pvd_seeds,
           "vtk_legacy": vtk_legacy_seeds, "render": render_seeds}


def main():
    out = sys.argv[1]
    targets = sys.argv[2:] or [t for t in WRITERS if t != "render"]
    for t in targets:
        if t not in WRITERS:
            sys.exit("write_hostile_seeds.py: unknown target '%s' (known: %s)" %
                     (t, ", ".join(WRITERS)))
        WRITERS[t](os.path.join(out, t))


if __name__ == "__main__":
    main()
