#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Writes VTKHDF UnstructuredGrid test files with h5py, following Kitware's VTKHDF specification,
into OUTDIR; src/uvr/mesh/io/vtkhdf_test.cpp checks uvr's reader against the values they are
built from (the same construction is repeated there).

The mixed partition: 14 points, the 12 of a 3 x 2 x 2 grid (x + 3y + 6z) and apexes (0.5, 0.5, 2)
and (0.5, 0.5, -1); cells hexahedron, wedge, tetra, pyramid, triangle (dropped by uvr), tetra.
Fields: point 'temp' = x + 2y - z (float64), point 'vel' = (x, y, z) (float32), cell 'cellid' =
cell index (int32), cell 'pair' = (c, -c) (float32). A partition shifted by dx has its points
moved by dx and 'cellid' = base + c.

Files: mixed.vtkhdf (1.0, one partition, float64 points), parts.vtkhdf (1.0, two partitions:
dx 0 and 10, cellid bases 0 and 100), parts_flat.vtkhdf (a partition of one triangle at z = 5,
then the mixed one), typeless_1_0.vtkhdf (mixed.vtkhdf without the Type attribute), ghosts.vtkhdf (mixed.vtkhdf
with vtkGhostType arrays hiding the hexahedron and the last tetrahedron), temporal_shared.vtkhdf (2.0, three steps sharing one
geometry; temp + 10 s and cellid + 100 s per step), temporal_changing.vtkhdf (2.0, steps 0 and 1
share the mixed partition, step 2 holds two partitions at dx 10 and 20), and bad_*.vtkhdf /
bad_*.hdf: one defect each (the test names the message it expects).
Usage: write_vtkhdf_cases.py OUTDIR
"""
import os
import sys

import h5py
import numpy as np

GRID = [(i, j, k) for k in range(2) for j in range(2) for i in range(3)]
POINTS = np.array(GRID + [(0.5, 0.5, 2.0), (0.5, 0.5, -1.0)], dtype=np.float64)
CELLS = [
    (12, [0, 1, 4, 3, 6, 7, 10, 9]),  # hexahedron
    (13, [1, 2, 4, 7, 8, 10]),  # wedge
    (10, [2, 5, 4, 8]),  # tetra
    (14, [6, 7, 10, 9, 12]),  # pyramid
    (5, [0, 1, 3]),  # triangle
    (10, [0, 1, 3, 13]),  # tetra
]


def partition(dx, base):
    """Arrays of one mixed partition moved by dx."""
    pts = POINTS + np.array([dx, 0.0, 0.0])
    conn = np.concatenate([np.array(c, dtype=np.int64) for _, c in CELLS])
    offsets = np.concatenate([[0], np.cumsum([len(c) for _, c in CELLS])]).astype(np.int64)
    types = np.array([t for t, _ in CELLS], dtype=np.uint8)
    n = len(CELLS)
    return {
        "points": pts,
        "conn": conn,
        "offsets": offsets,
        "types": types,
        "temp": pts[:, 0] + 2 * pts[:, 1] - pts[:, 2],
        "vel": pts.astype(np.float32),
        "cellid": (base + np.arange(n)).astype(np.int32),
        "pair": np.stack([np.arange(n), -np.arange(n)], axis=1).astype(np.float32),
    }


def flat():
    """A partition of one triangle (3 points), which uvr drops whole."""
    pts = np.array([(0.0, 0.0, 5.0), (1.0, 0.0, 5.0), (0.0, 1.0, 5.0)])
    return {
        "points": pts,
        "conn": np.array([0, 1, 2], dtype=np.int64),
        "offsets": np.array([0, 3], dtype=np.int64),
        "types": np.array([5], dtype=np.uint8),
        "temp": pts[:, 0] + 2 * pts[:, 1] - pts[:, 2],
        "vel": pts.astype(np.float32),
        "cellid": np.array([7], dtype=np.int32),
        "pair": np.array([[7, -7]], dtype=np.float32),
    }


def header(f, version, kind="UnstructuredGrid"):
    root = f.create_group("VTKHDF")
    root.attrs.create("Version", np.array(version, dtype=np.int64))
    # A fixed-length ASCII string, as VTK writes it (VTK 9.1 reads no variable-length one).
    root.attrs.create("Type", np.bytes_(kind))
    return root


def write_static(path, parts, version=(1, 0), points_dtype=np.float64, edit=None):
    """A file of the given partitions (no Steps); edit(root) may then break it."""
    with h5py.File(path, "w") as f:
        root = header(f, version)
        cat = lambda key: np.concatenate([p[key] for p in parts])
        root["NumberOfPoints"] = np.array([len(p["points"]) for p in parts], dtype=np.int64)
        root["NumberOfCells"] = np.array([len(p["types"]) for p in parts], dtype=np.int64)
        root["NumberOfConnectivityIds"] = np.array([len(p["conn"]) for p in parts], dtype=np.int64)
        root["Points"] = cat("points").astype(points_dtype)
        root["Types"] = cat("types")
        root["Offsets"] = cat("offsets")
        root["Connectivity"] = cat("conn")
        pd, cd = root.create_group("PointData"), root.create_group("CellData")
        pd["temp"], pd["vel"] = cat("temp"), cat("vel")
        cd["cellid"], cd["pair"] = cat("cellid"), cat("pair")
        root.create_group("FieldData")["note"] = np.array([1.0, 2.0])
        if edit:
            edit(root)


def write_temporal(path, steps, shared_fields, times):
    """steps: per step a list of partitions, or an int naming an earlier step whose geometry it
    reuses. Fields 'temp' and 'cellid' are stored per step (offset datasets); 'vel' and 'pair'
    follow the geometry (no offset datasets)."""
    geo = []  # stored geometries: list of partition lists
    rows = []  # per step: (part offset, parts, point, cell, conn offsets)
    counters = [0, 0, 0, 0]  # parts, points, cells, conn ids stored so far
    for s, st in enumerate(steps):
        if isinstance(st, int):
            rows.append(rows[st])
            continue
        geo.append(st)
        rows.append((counters[0], len(st), counters[1], counters[2], counters[3]))
        counters[0] += len(st)
        counters[1] += sum(len(p["points"]) for p in st)
        counters[2] += sum(len(p["types"]) for p in st)
        counters[3] += sum(len(p["conn"]) for p in st)
    allparts = [p for g in geo for p in g]
    with h5py.File(path, "w") as f:
        root = header(f, (2, 0))
        cat = lambda parts, key: np.concatenate([p[key] for p in parts])
        root["NumberOfPoints"] = np.array([len(p["points"]) for p in allparts], dtype=np.int64)
        root["NumberOfCells"] = np.array([len(p["types"]) for p in allparts], dtype=np.int64)
        root["NumberOfConnectivityIds"] = np.array([len(p["conn"]) for p in allparts],
                                                   dtype=np.int64)
        root["Points"] = cat(allparts, "points")
        root["Types"] = cat(allparts, "types")
        root["Offsets"] = cat(allparts, "offsets")
        root["Connectivity"] = cat(allparts, "conn")
        pd, cd = root.create_group("PointData"), root.create_group("CellData")
        # Per-step fields: each step's values stored one after the other.
        per_step = [shared_fields(s, rows[s], steps, geo) for s in range(len(steps))]
        pd["temp"] = np.concatenate([t for t, _ in per_step])
        cd["cellid"] = np.concatenate([c for _, c in per_step])
        pd["vel"] = cat(allparts, "vel")
        cd["pair"] = cat(allparts, "pair")
        st = root.create_group("Steps")
        st.attrs.create("NSteps", np.int64(len(steps)))
        st["Values"] = np.array(times, dtype=np.float64)
        st["PartOffsets"] = np.array([r[0] for r in rows], dtype=np.int64)
        st["NumberOfParts"] = np.array([r[1] for r in rows], dtype=np.int64)
        st["PointOffsets"] = np.array([r[2] for r in rows], dtype=np.int64)
        st["CellOffsets"] = np.array([[r[3]] for r in rows], dtype=np.int64)  # (NSteps, 1)
        st["ConnectivityIdOffsets"] = np.array([[r[4]] for r in rows], dtype=np.int64)
        po, co = st.create_group("PointDataOffsets"), st.create_group("CellDataOffsets")
        tp, tc = 0, 0
        pof, cof = [], []
        for t, c in per_step:
            pof.append(tp)
            cof.append(tc)
            tp += len(t)
            tc += len(c)
        po["temp"] = np.array(pof, dtype=np.int64)
        co["cellid"] = np.array(cof, dtype=np.int64)


def step_parts(s, steps):
    while isinstance(steps[s], int):
        s = steps[s]
    return steps[s]


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    p = lambda name: os.path.join(out, name)
    mixed = partition(0.0, 0)
    shifted = partition(10.0, 100)
    write_static(p("mixed.vtkhdf"), [mixed])
    write_static(p("parts.vtkhdf"), [mixed, shifted], points_dtype=np.float32)
    write_static(p("parts_flat.vtkhdf"), [flat(), mixed])
    # Version 1.0 without Type, as VTK 9.1-era writers left it (VTK's can_0.hdf): VTK 9.1 reads
    # it as an UnstructuredGrid; with a WholeExtent it would be ImageData.
    write_static(p("typeless_1_0.vtkhdf"), [mixed], edit=lambda root: root.attrs.__delitem__("Type"))

    # VTK's ghost flags: the hexahedron HIDDENCELL (32), the apex (0.5, 0.5, -1) of the last
    # tetrahedron HIDDENPOINT (2), the wedge EXTERIORCELL (16, kept), point 0 DUPLICATEPOINT (1,
    # kept).
    def ghosts(root):
        cells = np.zeros(len(CELLS), dtype=np.uint8)
        cells[0], cells[1] = 32, 16
        points = np.zeros(len(POINTS), dtype=np.uint8)
        points[13], points[0] = 2, 1
        root["CellData"]["vtkGhostType"] = cells
        root["PointData"]["vtkGhostType"] = points

    write_static(p("ghosts.vtkhdf"), [mixed], edit=ghosts)

    def typeless_image(root):
        root.attrs.__delitem__("Type")
        root.attrs.create("WholeExtent", np.array([0, 2, 0, 2, 0, 2], dtype=np.int64))

    write_static(p("bad_typeless_image.vtkhdf"), [mixed], edit=typeless_image)

    # Three steps on one geometry: temp + 10 s, cellid + 100 s.
    def fields(s, row, steps, geo):
        parts = step_parts(s, steps)
        return (np.concatenate([q["temp"] for q in parts]) + 10 * s,
                np.concatenate([q["cellid"] for q in parts]) + 100 * s)

    write_temporal(p("temporal_shared.vtkhdf"), [[mixed], 0, 0], fields, [0.0, 0.5, 1.25])
    write_temporal(p("temporal_changing.vtkhdf"),
                   [[mixed], 0, [partition(10.0, 200), partition(20.0, 300)]], fields,
                   [0.0, 1.0, 2.0])

    # One defect per file.
    with open(p("bad_not_hdf5.vtkhdf"), "w") as f:
        f.write("# vtk DataFile Version 4.2\nnot really\n")
    with h5py.File(p("bad_no_vtkhdf.hdf"), "w") as f:
        f.create_group("Other")["x"] = np.arange(3)
    with h5py.File(p("bad_type.vtkhdf"), "w") as f:
        header(f, (2, 0), "PolyData")
    with h5py.File(p("bad_version.vtkhdf"), "w") as f:
        header(f, (3, 0))

    def replace(name, value):
        def edit(root):
            del root[name]
            if value is not None:
                root[name] = value
        return edit

    write_static(p("bad_missing_connectivity.vtkhdf"), [mixed],
                 edit=replace("Connectivity", None))
    bad_offsets = mixed["offsets"].copy()
    bad_offsets[3] = 2
    write_static(p("bad_offsets_decrease.vtkhdf"), [mixed], edit=replace("Offsets", bad_offsets))
    bad_conn = mixed["conn"].copy()
    bad_conn[5] = 99
    write_static(p("bad_connectivity_range.vtkhdf"), [mixed],
                 edit=replace("Connectivity", bad_conn))
    write_static(p("bad_field_rows.vtkhdf"), [mixed],
                 edit=replace("PointData/temp", mixed["temp"][:10]))
    write_static(p("bad_partition_count.vtkhdf"), [mixed, shifted],
                 edit=replace("NumberOfCells", np.array([12], dtype=np.int64)))
    write_static(p("bad_absurd_count.vtkhdf"), [mixed],
                 edit=replace("NumberOfPoints", np.array([10**15], dtype=np.int64)))
    def sparse_points(root):
        # A billion rows declared, one chunk stored: the rest would read as fill values.
        del root["Points"], root["NumberOfPoints"]
        d = root.create_dataset("Points", shape=(10**9, 3), dtype="f4", chunks=(1024, 3))
        d[0:14] = mixed["points"]
        root["NumberOfPoints"] = np.array([10**9], dtype=np.int64)

    write_static(p("bad_sparse_points.vtkhdf"), [mixed], edit=sparse_points)
    write_static(p("bad_cell_type.vtkhdf"), [mixed],
                 edit=replace("Types", np.array([12, 13, 10, 14, 5, 200], dtype=np.uint8)))
    write_static(p("bad_points_shape.vtkhdf"), [mixed],
                 edit=replace("Points", mixed["points"][:, :2].copy()))


if __name__ == "__main__":
    main()
