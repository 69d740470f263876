# SPDX-License-Identifier: MIT
"""Meshes for uvr: from files, numpy arrays (VTK's and pyvista's layouts), meshio and VTK."""

import os

import numpy as np

from . import _uvr

# VTK cell types uvr takes as they are (the corner counts of tetra, hexahedron, wedge, pyramid).
_DIRECT = {10: 4, 12: 8, 13: 6, 14: 5}
# Cell type of a homogeneous (m, k) cell array, from k.
_BY_CORNERS = {4: 10, 8: 12, 6: 13, 5: 14}
# Node counts of the VTK cell types whose count is fixed (for pyvista's padded layout).
_FIXED_NODES = {1: 1, 3: 2, 5: 3, 8: 4, 9: 4, 10: 4, 11: 8, 12: 8, 13: 6, 14: 5, 21: 3, 22: 6,
                23: 8, 24: 10, 25: 20, 26: 15, 27: 13, 28: 9, 29: 27, 32: 18, 33: 24, 34: 6}
# meshio's cell type names and VTK's codes (meshio lists corners first, in VTK's order).
_MESHIO_TYPES = {"vertex": 1, "line": 3, "triangle": 5, "polygon": 7, "quad": 9, "tetra": 10,
                 "hexahedron": 12, "wedge": 13, "pyramid": 14, "line3": 21, "triangle6": 22,
                 "quad8": 23, "tetra10": 24, "hexahedron20": 25, "wedge15": 26, "pyramid13": 27,
                 "quad9": 28, "hexahedron27": 29, "wedge18": 32, "hexahedron24": 33,
                 "triangle7": 34}
# VTK codes of the 3D cells uvr renders (through their corners); others are dropped.
_VOLUMETRIC = {10, 11, 12, 13, 14, 24, 25, 26, 27, 29, 32, 33, 71, 72, 73, 74, 79, 80, 81, 82}


def _argument_error(message):
    return _uvr.ArgumentError(message)


def _real_array(value, name):
    """value as a numpy array of a real number type; TypeError naming `name` otherwise."""
    a = np.asarray(value)
    if a.dtype.kind not in "fiub":
        raise TypeError(f"{name}: expected an array of real numbers, got dtype {a.dtype}")
    return a


def _int_array(value, name):
    a = np.asarray(value)
    if a.dtype.kind not in "iub":
        raise TypeError(f"{name}: expected an array of integers, got dtype {a.dtype}")
    return a


def _shape(a):
    return "(" + ", ".join(str(s) for s in a.shape) + ("," if a.ndim == 1 else "") + ")"


class Mesh:
    """An unstructured volume mesh: points, cells and fields.

    ``Mesh(points, cells=..., offsets=..., types=..., point_data={...}, cell_data={...})`` takes
    numpy arrays (or anything ``numpy.asarray`` takes) in VTK's layouts:

    * connectivity + offsets + types (``vtkUnstructuredGrid``, VTKHDF): ``cells`` is the flat
      connectivity, ``offsets`` has one entry more than there are cells (starting at 0) or one
      per cell (the end of each cell, as in ``.vtu`` files);
    * pyvista's padded ``cells`` (``[n0, ids..., n1, ids...]``) with ``types`` (``celltypes``);
    * a homogeneous ``(m, k)`` cell array (k = 4, 5, 6, 8: tetrahedra, pyramids, wedges,
      hexahedra) without ``types``.

    The arrays are used without a copy when they already have uvr's layout: float32 points of
    shape (n, 3), uint32 (or non-negative int32) connectivity, int64/uint64 offsets of length
    cells + 1, uint8 types of only 10, 12, 13, 14, all C-contiguous; the mesh then keeps
    references to them. Anything else is converted once; ``mesh.copied`` names the arguments
    that were. Fields are float32 arrays of shape (n,) or (n, components) (converted when not).

    Borrowed arrays may be changed afterwards: a Renderer made later (and ``bounds``) checks
    them again and prepares from a copy (an invalid change raises ValidationError or
    ArgumentError); a Renderer made earlier never reads them again (docs/PYTHON.md).
    """

    def __init__(self, points, cells=None, offsets=None, types=None, point_data=None,
                 cell_data=None, *, _data=None, _fields=None, _keep=None):
        self.copied = []
        self._keep = _keep  # an object whose memory the arrays view (a VTK grid)
        if _data is not None:
            self._data = _data
            self._fields = list(_fields or [])
            return
        if cells is None:
            raise _argument_error("cells: required (connectivity with offsets and types, "
                                  "pyvista's padded cells with types, or an (m, k) array)")
        p = _real_array(points, "points")
        if p.ndim != 2 or p.shape[1] != 3:
            raise _argument_error(f"points: expected shape (n, 3), got {_shape(p)}")
        p32 = np.ascontiguousarray(p, dtype=np.float32)
        if p32 is not p and not np.shares_memory(p32, p):
            self.copied.append("points")
        conn, offs, typ = self._cells(cells, offsets, types)
        kept = None
        direct = typ.size == 0 or bool(np.isin(typ, list(_DIRECT)).all())
        if direct:
            self._data = self._borrow(p32, conn, offs, typ)
        else:
            kept = np.isin(typ, list(_VOLUMETRIC))
            self.copied += ["cells", "offsets", "types"]
            self._data = _uvr.MeshData.convert(
                p32, np.ascontiguousarray(typ, dtype=np.int32),
                np.ascontiguousarray(offs, dtype=np.int64),
                np.ascontiguousarray(conn, dtype=np.int64))
        self._fields = []
        for name, values in (point_data or {}).items():
            self._add_field(name, "point", values, self._data.point_count)
        for name, values in (cell_data or {}).items():
            a = _real_array(values, f"cell_data['{name}']")
            if kept is not None and a.ndim >= 1 and a.shape[0] == kept.size:
                a = a[kept]  # the cells uvr dropped (0D-2D) leave their values too
            self._add_field(name, "cell", a, self._data.cell_count)

    # ---- construction helpers ----

    def _cells(self, cells, offsets, types):
        """(connectivity, offsets with cells + 1 entries, types) of any accepted layout."""
        c = _int_array(cells, "cells")
        if c.ndim == 2:
            m, k = c.shape
            if types is None:
                if k not in _BY_CORNERS:
                    raise _argument_error(
                        f"cells: an (m, k) array needs k = 4, 5, 6 or 8 corners, got k = {k} "
                        "(give types for other cells)")
                types = _BY_CORNERS[k]
            t = _int_array(types, "types")
            if t.ndim == 0:
                t = np.full(m, int(t), dtype=np.uint8)
            if offsets is not None:
                raise _argument_error("offsets: not used with an (m, k) cell array")
            if t.shape != (m,):
                raise _argument_error(f"types: expected shape ({m},), got {_shape(t)}")
            return c.reshape(-1), np.arange(0, m * k + 1, k, dtype=np.int64), t
        if c.ndim != 1:
            raise _argument_error(f"cells: expected a 1-D or 2-D array, got shape {_shape(c)}")
        if types is None:
            raise _argument_error("types: required with 1-D cells (one VTK type code per cell)")
        t = _int_array(types, "types")
        if t.ndim != 1:
            raise _argument_error(f"types: expected shape (m,), got {_shape(t)}")
        m = t.shape[0]
        if offsets is None:
            return self._padded(c, t) + (t,)
        o = _int_array(offsets, "offsets")
        if o.ndim != 1 or o.shape[0] not in (m, m + 1):
            raise _argument_error(f"offsets: expected {m + 1} entries (cells + 1, from 0) or {m} "
                                  f"(the end of each cell), got shape {_shape(o)}")
        if o.shape[0] == m and m > 0:
            o = np.concatenate([[0], o]).astype(np.int64)
            self.copied.append("offsets")
        elif o.shape[0] == m and m == 0:
            o = np.zeros(1, dtype=np.int64)
        return c, o, t

    def _padded(self, c, t):
        """pyvista's padded layout [n0, ids..., n1, ids...] as (connectivity, offsets)."""
        m = t.shape[0]
        self.copied += ["cells", "offsets"]
        table = np.full(256, -1, dtype=np.int64)
        table[list(_FIXED_NODES)] = list(_FIXED_NODES.values())
        if m and t.min() >= 0 and t.max() < 256 and (table[t] >= 0).all():
            sizes = table[t]
            starts = np.concatenate([[0], np.cumsum(sizes + 1)[:-1]])
            if starts[-1] + sizes[-1] + 1 == c.size and (c[starts] == sizes).all():
                keep = np.ones(c.size, dtype=bool)
                keep[starts] = False
                offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
                return c[keep], offsets
        # Variable sizes (Lagrange cells): one pass in order.
        offsets = np.zeros(m + 1, dtype=np.int64)
        conn = []
        pos = 0
        for i in range(m):
            if pos >= c.size:
                raise _argument_error(f"cells: the padded array ends before cell {i} of {m}")
            n = int(c[pos])
            if n < 0 or pos + 1 + n > c.size:
                raise _argument_error(f"cells: cell {i} lists {n} nodes past the array's end")
            conn.append(c[pos + 1:pos + 1 + n])
            offsets[i + 1] = offsets[i] + n
            pos += 1 + n
        if pos != c.size:
            raise _argument_error(f"cells: {c.size - pos} entries left after the {m} cells")
        return (np.concatenate(conn) if conn else np.zeros(0, np.int64)), offsets

    def _borrow(self, p32, conn, offs, typ):
        """The zero-copy path: uvr's dtypes as views, converting only what differs."""
        if typ.dtype == np.uint8 and typ.flags.c_contiguous:
            t8 = typ
        else:
            t8 = np.ascontiguousarray(typ, dtype=np.uint8)
            self.copied.append("types")
        if offs.dtype in (np.int64, np.uint64) and offs.flags.c_contiguous:
            if offs.dtype == np.int64 and offs.size and offs.min() < 0:
                raise _uvr.ValidationError(f"offsets: negative entry {int(offs.min())}")
            o64 = offs.view(np.uint64)
        else:
            if offs.size and offs.min() < 0:
                raise _uvr.ValidationError(f"offsets: negative entry {int(offs.min())}")
            o64 = np.ascontiguousarray(offs, dtype=np.uint64)
            if "offsets" not in self.copied:
                self.copied.append("offsets")
        if conn.size and conn.dtype.kind == "i" and conn.min() < 0:
            i = int(np.argmax(conn < 0))
            cell = int(np.searchsorted(o64, i, side="right")) - 1
            raise _uvr.ValidationError(f"cell {cell}: corner {i - int(o64[cell])} is point "
                                       f"{int(conn[i])}, expected 0 or more")
        if conn.dtype == np.uint32 and conn.flags.c_contiguous:
            c32 = conn
        elif conn.dtype == np.int32 and conn.flags.c_contiguous:
            c32 = conn.view(np.uint32)
        else:
            if conn.size and conn.max() > 0xFFFFFFFF:
                raise _uvr.ValidationError(f"cells: point index {int(conn.max())} beyond 2^32 - 1")
            c32 = np.ascontiguousarray(conn, dtype=np.uint32)
            if "cells" not in self.copied:
                self.copied.append("cells")
        return _uvr.MeshData.borrow(p32, t8, o64, c32)

    def _add_field(self, name, association, values, tuples):
        what = f"{association}_data['{name}']"
        a = _real_array(values, what)
        if a.ndim not in (1, 2) or a.shape[0] != tuples:
            raise _argument_error(f"{what}: expected {tuples} tuples (one per {association}), "
                                  f"got shape {_shape(a)}")
        a32 = np.ascontiguousarray(a, dtype=np.float32)
        if a32 is not a and not np.shares_memory(a32, a):
            self.copied.append(what)
        self._fields.append((str(name), association, a32))

    # ---- the mesh ----

    @property
    def points(self):
        """Points, float32 (n, 3) (a read-only view of uvr's memory for a file's mesh)."""
        return self._data.points

    @property
    def connectivity(self):
        """Corner indices of all cells, uint32."""
        return self._data.connectivity

    @property
    def offsets(self):
        """Start of each cell in connectivity and the end of the last, uint64 (cells + 1)."""
        return self._data.offsets

    @property
    def types(self):
        """VTK cell type of each cell, uint8 (10 tetra, 12 hexahedron, 13 wedge, 14 pyramid)."""
        return self._data.types

    @property
    def n_points(self):
        return self._data.point_count

    @property
    def n_cells(self):
        return self._data.cell_count

    @property
    def point_data(self):
        """Point fields by name (float32 arrays (n,) or (n, components))."""
        return {n: a for n, assoc, a in self._fields if assoc == "point"}

    @property
    def cell_data(self):
        """Cell fields by name (float32 arrays (m,) or (m, components))."""
        return {n: a for n, assoc, a in self._fields if assoc == "cell"}

    @property
    def fields(self):
        """Every field as (name, association, array), in the file's order."""
        return list(self._fields)

    @property
    def notes(self):
        """What reading or converting changed (dropped 2D cells, voxels reordered, ...)."""
        return list(self._data.notes) + list(getattr(self, "_notes_extra", []))

    @property
    def bounds(self):
        """((xmin, ymin, zmin), (xmax, ymax, zmax)) of the points cells use."""
        return self._data.bounds()

    def __repr__(self):
        fields = ", ".join(f"{n} ({a}{'' if v.ndim == 1 else f', {v.shape[1]} components'})"
                           for n, a, v in self._fields)
        return (f"uvr.Mesh({self.n_points} points, {self.n_cells} cells"
                + (f"; fields: {fields}" if fields else "") + ")")


def read(path, max_memory=None, *, step=None, time=None):
    """Reads a mesh file of any format ``uvr render`` reads (.vtk, .vtu, .pvtu, .pvd, .uvrm, a
    quoted numbered series such as "run_*.vtu"); of a file or series with time steps, the step
    `step` (an index) or the one shown at `time` (the last at or before it), else the first.

    The arrays are uvr's own; ``mesh.points`` and the fields are read-only numpy views of them
    (no copies). ``max_memory`` (bytes) refuses loads that would hold more.
    """
    if step is None and time is None:
        data = _uvr.MeshData.read(os.fspath(path), int(max_memory or 0))
        return Mesh(None, _data=data, _fields=data.fields)
    series = Series(path, max_memory)
    return series.read(series._index(step, time))


class Series:
    """A mesh file or series opened for its time steps: a ParaView ``.pvd``, a numbered file
    series named by a pattern with one ``*`` ("run_*.vtu"), or a file with time steps; any
    other file is one step at time 0.

    ``series.times`` lists the steps' times, ``len(series)`` counts them, ``series[i]`` (or
    ``read(i)``) reads step i whole. ``uvr.Renderer(series, field)`` prepares the first step and
    ``renderer.set_time(t)`` / ``set_step(i)`` shows another: when its points and cells are the
    same only the values are read and refreshed, nothing geometric is rebuilt.
    """

    def __init__(self, path, max_memory=None):
        self._core = _uvr.Series(os.fspath(path), int(max_memory or 0))

    @property
    def path(self):
        """The path or pattern it was opened with."""
        return self._core.path

    @property
    def times(self):
        """The steps' times (0, 1, 2, ... for a numbered series)."""
        return list(self._core.times)

    def __len__(self):
        return len(self._core.times)

    def source(self, step):
        """The file step `step` comes from."""
        return self._core.source(self._index(step, None))

    def step_at(self, time):
        """The step shown at `time`: the last at or before it (the first for earlier times)."""
        return int(self._core.step_at(float(time)))

    def _index(self, step, time):
        if step is not None and time is not None:
            raise _argument_error("step and time: give one of them")
        if time is not None:
            return self.step_at(time)
        i = int(step or 0)
        n = len(self)
        if not 0 <= i < n:
            raise _argument_error(f"step {i}: {self.path} has {n} time step"
                                  f"{'' if n == 1 else 's'} (0 to {n - 1})")
        return i

    def read(self, step=0):
        """Step `step`, whole (points, cells and that step's fields) as a uvr.Mesh."""
        data = self._core.read(self._index(step, None))
        return Mesh(None, _data=data, _fields=data.fields)

    def __getitem__(self, step):
        return self.read(step)

    def _same_geometry(self, step, mesh):
        """Step `step`'s fields on `mesh`'s geometry as a new uvr.Mesh sharing its arrays, or
        None when the step's points or cells differ."""
        fields = self._core.read_fields(self._index(step, None), mesh._data)
        if fields is None:
            return None
        return Mesh(None, _data=mesh._data, _fields=fields.fields, _keep=mesh._keep)

    def __repr__(self):
        t = self.times
        return f"uvr.Series({self.path!r}, {len(t)} steps, time {t[0]:g} to {t[-1]:g})"


def from_meshio(m):
    """A uvr.Mesh from a meshio.Mesh: 3D cell blocks kept (quadratic ones through their corners),
    0D-2D blocks dropped with their cell data; point and cell data become fields (the cell data
    of the kept blocks, concatenated). Connectivity is copied (meshio holds int64 blocks)."""
    points = np.asarray(m.points)
    if points.ndim == 2 and points.shape[1] == 2:
        raise _argument_error("points: a 2D meshio mesh has no volume to render")
    conn, sizes, types, keep_blocks = [], [], [], []
    for block in m.cells:
        code = _MESHIO_TYPES.get(block.type)
        if code is None:
            raise _uvr.UnsupportedError(f"meshio cell type '{block.type}' is not supported")
        keep = code in _VOLUMETRIC
        keep_blocks.append(keep)
        if not keep:
            continue
        data = np.asarray(block.data)
        conn.append(data.reshape(-1))
        sizes.append(np.full(data.shape[0], data.shape[1], dtype=np.int64))
        types.append(np.full(data.shape[0], code, dtype=np.uint8))
    if not conn:
        raise _uvr.ValidationError("the meshio mesh has no 3D cells")
    sizes = np.concatenate(sizes)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cell_data = {}
    for name, blocks in m.cell_data.items():
        kept = [np.asarray(b) for b, k in zip(blocks, keep_blocks) if k]
        if kept and all(b.ndim in (1, 2) for b in kept):
            cell_data[name] = np.concatenate(kept)
    mesh = Mesh(points, cells=np.concatenate(conn), offsets=offsets,
                types=np.concatenate(types), point_data=dict(m.point_data), cell_data=cell_data)
    dropped = [b.type for b, k in zip(m.cells, keep_blocks) if not k]
    if dropped:
        mesh._notes_extra = [f"dropped non-volumetric meshio blocks: {', '.join(dropped)}"]
    return mesh


def from_vtk(grid):
    """A uvr.Mesh from a VTK vtkUnstructuredGrid (python3-vtk9; a pyvista UnstructuredGrid is
    one). Points (float32), cell types and offsets are used without copies where VTK's arrays
    have uvr's dtypes (the mesh keeps the grid alive); VTK's 64-bit connectivity is copied to
    uint32. Point and cell data arrays become fields."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    if not hasattr(grid, "GetCellTypesArray"):
        raise TypeError(f"from_vtk: expected a vtkUnstructuredGrid, got {type(grid).__name__}")
    if grid.GetNumberOfPoints() == 0:
        raise _uvr.ValidationError("the VTK grid has no points")
    points = vtk_to_numpy(grid.GetPoints().GetData())
    cells = grid.GetCells()
    conn = vtk_to_numpy(cells.GetConnectivityArray())
    offsets = vtk_to_numpy(cells.GetOffsetsArray())
    types = vtk_to_numpy(grid.GetCellTypesArray())

    def data_of(attributes):
        out = {}
        for i in range(attributes.GetNumberOfArrays()):
            arr = attributes.GetArray(i)
            if arr is None or not arr.GetName():
                continue  # a string or unnamed array
            out[arr.GetName()] = vtk_to_numpy(arr)
        return out

    mesh = Mesh(points, cells=conn, offsets=offsets, types=types,
                point_data=data_of(grid.GetPointData()), cell_data=data_of(grid.GetCellData()))
    mesh._keep = grid
    return mesh


def as_mesh(obj):
    """uvr.Mesh of anything mesh-like: a uvr.Mesh, a path, a vtkUnstructuredGrid (pyvista too),
    a meshio.Mesh, or an object with ``points`` and either ``cells``/``celltypes`` (pyvista's
    padded layout) or ``connectivity``/``offsets``/``types``, and optional ``point_data`` and
    ``cell_data`` mappings."""
    if isinstance(obj, Mesh):
        return obj
    if isinstance(obj, Series):
        return obj.read(0)
    if isinstance(obj, (str, os.PathLike)):
        return read(obj)
    if hasattr(obj, "GetCellTypesArray"):
        return from_vtk(obj)
    cells = getattr(obj, "cells", None)
    if isinstance(cells, (list, tuple)) and cells and hasattr(cells[0], "type") and \
            hasattr(cells[0], "data"):
        return from_meshio(obj)
    point_data = dict(getattr(obj, "point_data", {}) or {})
    cell_data = dict(getattr(obj, "cell_data", {}) or {})
    if hasattr(obj, "points") and hasattr(obj, "celltypes") and cells is not None:
        return Mesh(obj.points, cells=cells, types=obj.celltypes, point_data=point_data,
                    cell_data=cell_data)
    if hasattr(obj, "points") and hasattr(obj, "connectivity") and hasattr(obj, "offsets"):
        return Mesh(obj.points, cells=obj.connectivity, offsets=obj.offsets,
                    types=getattr(obj, "types", None), point_data=point_data,
                    cell_data=cell_data)
    raise TypeError(f"expected a mesh (uvr.Mesh, a path, a vtkUnstructuredGrid, a meshio.Mesh, "
                    f"or an object with points and cells), got {type(obj).__name__}")
