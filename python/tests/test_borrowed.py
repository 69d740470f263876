# SPDX-License-Identifier: MIT
"""Arrays a uvr.Mesh borrows without a copy, changed afterwards (issue 28): a Renderer made later
checks them again (a Python exception, never a crash); one made earlier never reads them again.

The hostile cases run in a child interpreter, so that a regression shows as a failed test naming
the signal instead of killing pytest."""

import os
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

import uvr

# Two tetrahedra sharing the face (1, 2, 3): point 0 is used by cell 0 only, point 4 by cell 1.
P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float32)
C = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], dtype=np.uint32)
VALUES = np.arange(5, dtype=np.float32)

PRELUDE = """
import numpy as np, uvr
P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float32)
C = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], dtype=np.uint32)
def outcome(fn):
    try:
        r = fn()
    except uvr.Error as e:
        print(type(e).__name__ + ": " + str(e))
    else:
        print("ok", r)
"""


def tet_grid(n):
    """An n^3 grid of unit cubes over [0, 1]^3, each split into 6 tetrahedra: (points, (m, 4))."""
    ax = np.linspace(0.0, 1.0, n + 1, dtype=np.float32)
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    i, j, k = (a.ravel() for a in np.meshgrid(*(np.arange(n),) * 3, indexing="ij"))

    def v(a, b, c):
        return ((k + c) * (n + 1) + j + b) * (n + 1) + i + a

    c = [v(0, 0, 0), v(1, 0, 0), v(1, 1, 0), v(0, 1, 0),
         v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)]
    tets = [(0, 1, 3, 7), (0, 1, 7, 4), (1, 2, 3, 7), (1, 5, 4, 7), (1, 2, 7, 6), (1, 6, 7, 5)]
    cells = np.stack([np.stack([c[a] for a in t], axis=1) for t in tets], axis=1)
    return points, np.ascontiguousarray(cells.reshape(-1, 4).astype(np.uint32))


def run_child(code):
    """stdout of `code` (after PRELUDE) run by this interpreter in a child; fails on a crash."""
    r = subprocess.run([sys.executable, "-c", PRELUDE + textwrap.dedent(code)],
                       capture_output=True, text=True, env=dict(os.environ), timeout=300)
    assert r.returncode == 0, (f"the child died with {r.returncode} (a negative code is a "
                               f"signal: {-r.returncode})\n{r.stderr}")
    return r.stdout.strip().splitlines()


def test_connectivity_changed_after_mesh_is_refused_by_renderer_and_bounds():
    # The reproducer: before the fix, SIGSEGV in Renderer().
    out = run_child("""
        c = C.copy()
        m = uvr.Mesh(P, c)
        c[1, 3] = 4000000000
        outcome(lambda: uvr.Renderer(m, np.arange(5, dtype=np.float32)).render(size=(16, 16)))
        outcome(lambda: m.bounds)
        c[1, 3] = 4  # changed back: renders again
        outcome(lambda: uvr.Renderer(m, np.arange(5, dtype=np.float32)).info["tetrahedra"])
    """)
    assert out[0] == out[1]
    assert out[0].startswith("ValidationError: the mesh's arrays changed after uvr.Mesh(): "
                             "cell 1 (tetra): corner 3 is point 4000000000, expected below "
                             "pointCount 5"), out
    assert out[2] == "ok 2"


@pytest.mark.parametrize("change, message", [
    ("o[1] = 1 << 40", "cell 0: offsets 0..1099511627776 do not span the 4 corners"),
    ("o[2] = 7", "cell 1: offsets 4..7 do not span the 4 corners"),
    ("o[0] = 2", "cell 0: offset 2, expected 0"),
    ("t[1] = 12", "cell 1: offsets 4..8 do not span the 8 corners of a hexahedron"),
    ("t[0] = 99", "cell 0: type 99, expected 10"),
])
def test_offsets_and_types_changed_after_mesh_are_refused(change, message):
    out = run_child(f"""
        c = C.ravel().copy()
        o = np.array([0, 4, 8], dtype=np.int64)
        t = np.array([10, 10], dtype=np.uint8)
        m = uvr.Mesh(P, cells=c, offsets=o, types=t)
        assert m.copied == []
        {change}
        outcome(lambda: uvr.Renderer(m, np.arange(5, dtype=np.float32)).render(size=(16, 16)))
        outcome(lambda: m.bounds)
    """)
    for line in out:
        assert line.startswith("ValidationError: the mesh's arrays changed after uvr.Mesh(): "
                               + message), out


def test_arrays_reshaped_retyped_or_resized_in_place_are_refused():
    # A borrowed array changed in place as numpy allows: its shape, its dtype (same item size),
    # its memory (resize without the reference check: the old buffer is freed).
    out = run_child("""
        def fresh():
            c = C.ravel().copy()
            return c, uvr.Mesh(P, cells=c, offsets=np.array([0, 4, 8]),
                               types=np.array([10, 10], np.uint8))
        values = np.arange(5, dtype=np.float32)
        c, m = fresh()
        c.shape = (2, 4)
        outcome(lambda: uvr.Renderer(m, values).info["tetrahedra"])
        c, m = fresh()
        c.dtype = np.float32
        outcome(lambda: uvr.Renderer(m, values).info["tetrahedra"])
        c, m = fresh()
        c.resize(1 << 22, refcheck=False)
        c[:] = 4000000000
        outcome(lambda: uvr.Renderer(m, values).info["tetrahedra"])
    """)
    assert out[0] == ("ArgumentError: the mesh's arrays changed after uvr.Mesh(): connectivity: "
                      "expected shape (n,), got (2, 4)"), out
    assert out[1].startswith("ArgumentError: the mesh's arrays changed after uvr.Mesh(): "
                             "connectivity: expected a C-contiguous numpy array of uint32, got "
                             "ndarray of float32"), out
    assert out[2].startswith("ValidationError: the mesh's arrays changed after uvr.Mesh(): "
                             "cell 0 (tetra): corner 0 is point 4000000000"), out


def test_points_changed_to_nan_after_mesh_drop_their_cells():
    p = P.copy()
    m = uvr.Mesh(p, C)
    p[4] = np.nan  # only cell 1 uses point 4
    r = uvr.Renderer(m, VALUES, methods=("adaptive",))
    assert r.info["tetrahedra"] == 1
    alone = uvr.Renderer(uvr.Mesh(P, C[:1]), VALUES, methods=("adaptive",))
    # The opacity unit given: its default depends on the cell count, which differs.
    kw = dict(size=(24, 24), azimuth=30, elevation=20, range=(0, 4), opacity_unit=0.5)
    assert np.array_equal(r.render(**kw), alone.render(**kw))
    p[:] = np.nan
    empty = uvr.Renderer(m, VALUES, methods=("adaptive",))
    assert empty.info["tetrahedra"] == 0
    with pytest.raises(uvr.ArgumentError, match="empty or non-finite bounds"):
        empty.render(**kw)
    assert m.bounds[0][0] > m.bounds[1][0]  # empty: no cell with finite corners


def test_fields_are_read_when_a_renderer_uses_them_and_not_afterwards():
    v = VALUES.copy()
    m = uvr.Mesh(P, C, point_data={"v": v})
    assert m.copied == []
    r = uvr.Renderer(m, "v", methods=("adaptive",))
    kw = dict(size=(24, 24), azimuth=30, elevation=20, range=(0, 4))
    before = r.render(**kw)
    v[:] = np.inf  # the renderer holds its own values
    assert np.array_equal(r.render(**kw), before)
    v[0], v[1] = np.nan, -np.inf
    later = uvr.Renderer(m, "v", methods=("adaptive",))  # today's values, NaN and infinities
    assert later.info["value_range"][0] == later.info["value_range"][0]  # not NaN
    later.render(**kw)
    r.set_field("v")  # the same for new values of a renderer
    r.render(**kw)
    v[:] = VALUES
    r.set_field("v")
    assert np.array_equal(r.render(**kw), before)


def test_a_renderer_never_reads_the_borrowed_arrays_again():
    p, c = P.copy(), C.copy()
    m = uvr.Mesh(p, c)
    r = uvr.Renderer(m, VALUES, methods=("adaptive",))
    kw = dict(size=(24, 24), azimuth=30, elevation=20, range=(0, 4))
    before = r.render(**kw)
    c[1, 3] = 4000000000
    p[:] = np.nan
    assert np.array_equal(r.render(**kw), before)
    r.set_field(VALUES[::-1].copy())
    r.set_field(VALUES)
    assert np.array_equal(r.render(**kw), before)


def test_a_thread_changing_the_arrays_while_renderers_prepare():
    # Another thread writes bad and good indices while Renderer() prepares (the GIL released):
    # each renderer sees a copy checked whole, so it renders or raises, never reads wild memory.
    points, conn = tet_grid(8)
    good = conn.copy()
    m = uvr.Mesh(points, conn)
    stop = threading.Event()

    def writer():
        rng = np.random.default_rng(5)
        while not stop.is_set():
            i = int(rng.integers(conn.size))
            conn.reshape(-1)[i] = 4000000000
            conn.reshape(-1)[i] = good.reshape(-1)[i]

    t = threading.Thread(target=writer)
    t.start()
    try:  # any other exception, or a crash, fails the test
        for _ in range(40):
            try:
                uvr.Renderer(m, points[:, 0].copy(), methods=("adaptive",))
            except uvr.ValidationError as e:
                assert "point 4000000000" in str(e)
    finally:
        stop.set()
        t.join()


def test_transfer_function_and_camera_arrays_are_copied():
    tf = uvr.TransferFunction("Cool to Warm")
    colors = np.array([[0, 0, 0, 1], [1, 1, 0, 0]], dtype=np.float32)
    tf.colors = colors
    colors[:] = np.nan
    assert np.array_equal(tf.colors, [[0, 0, 0, 1], [1, 1, 0, 0]])
    opacities = np.array([[0, 0], [1, 1]], dtype=np.float32)
    tf.opacities = opacities
    opacities[:] = 7
    assert np.array_equal(tf.opacities, [[0, 0], [1, 1]])
    position = np.array([0.5, 0.5, 4.0], dtype=np.float32)
    cam = uvr.Camera(position=position, focal_point=(0.5, 0.5, 0.5))
    position[:] = np.nan
    assert tuple(cam.position) == (0.5, 0.5, 4.0)


def test_a_series_compares_a_borrowed_geometry_as_it_is_now(data_dir):
    path = data_dir / "spx.vtk"
    read = uvr.read(path)
    conn = np.array(read.connectivity)
    borrowed = uvr.Mesh(np.array(read.points), cells=conn, offsets=np.array(read.offsets),
                        types=np.array(read.types))
    assert borrowed.copied == []
    series = uvr.Series(path)
    assert series._same_geometry(0, borrowed) is not None  # only the fields are read
    conn[-1] = 4000000000
    with pytest.raises(uvr.ValidationError, match="changed after uvr.Mesh.*point 4000000000"):
        series._same_geometry(0, borrowed)
