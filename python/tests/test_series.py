# SPDX-License-Identifier: MIT
"""Time series from Python: uvr.Series, uvr.read(step=, time=), Renderer.set_step/set_time
(values refreshed without rebuilding while the geometry stays; frames equal fresh renderers)."""

import numpy as np
import pytest

import uvr


def _blob_mesh(points, k):
    d = points - np.array([0.2 + 0.3 * k, 0.5, 0.5], dtype=np.float32)
    return np.exp(-(d * d).sum(axis=1) / 0.03).astype(np.float32)


@pytest.fixture
def series_dir(tmp_path, cli):
    """run.pvd: three steps of a generated box (times 0, 0.5, 1) with a moving point field
    'blob', and a fourth at time 2 on another geometry."""
    cli("-q", "generate", "box", "--cells", "3000", "--fields", "linear", "-o",
        tmp_path / "a.vtu")
    cli("-q", "generate", "box", "--cells", "1500", "--fields", "linear", "-o",
        tmp_path / "b.vtu")
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    entries = []
    for k, base in enumerate(["a", "a", "a", "b"]):
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(str(tmp_path / f"{base}.vtu"))
        r.Update()
        g = r.GetOutput()
        pts = vtk_to_numpy(g.GetPoints().GetData())
        a = numpy_to_vtk(_blob_mesh(pts, k), deep=1)
        a.SetName("blob")
        g.GetPointData().AddArray(a)
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(str(tmp_path / f"s{k}.vtu"))
        w.SetInputData(g)
        w.Write()
        entries.append(f'<DataSet timestep="{[0, 0.5, 1, 2][k]}" file="s{k}.vtu"/>')
    (tmp_path / "run.pvd").write_text('<VTKFile type="Collection"><Collection>'
                                      + "".join(entries) + "</Collection></VTKFile>")
    return tmp_path


LOOK = dict(tf="viridis", opacity="0:0,1:0.8", range=(0, 1), size=(48, 40), azimuth=30)


def test_series_lists_and_reads_steps(series_dir):
    s = uvr.Series(series_dir / "run.pvd")
    assert len(s) == 4 and s.times == [0, 0.5, 1, 2]
    assert s.step_at(0.7) == 1 and s.step_at(-3) == 0
    assert s.source(2).endswith("s2.vtu")
    m = s[2]
    blob = dict((n, a) for n, _, a in m.fields)["blob"]
    assert np.allclose(blob, _blob_mesh(m.points, 2))
    assert uvr.read(series_dir / "run.pvd", time=1.2).n_points == m.n_points
    assert np.array_equal(uvr.read(series_dir / "s*.vtu", step=1).points, m.points)
    with pytest.raises(uvr.ArgumentError, match="step 9"):
        s.read(9)
    with pytest.raises(uvr.ArgumentError, match="one of them"):
        uvr.read(series_dir / "run.pvd", step=1, time=0)
    with pytest.raises(uvr.FileError, match="no file matches"):
        uvr.Series(series_dir / "none_*.vtu")


def test_renderer_follows_the_steps_without_rebuilding(series_dir):
    s = uvr.Series(series_dir / "run.pvd")
    r = uvr.Renderer(s, "blob", device="cpu")
    assert (r.step, r.time) == (0, 0)
    first = r.render(**LOOK)
    for k, t in [(1, 0.6), (2, 1.0)]:
        assert r.set_time(t) is True  # values only
        assert (r.step, r.time) == (k, [0, 0.5, 1][k])
        assert r.info["value_updates"] == k
        frame = r.render(**LOOK)
        fresh = uvr.Renderer(s[k], "blob", device="cpu").render(**LOOK)
        assert np.array_equal(frame, fresh)
        assert not np.array_equal(frame, first)
    # Another geometry: prepared anew, still right.
    assert r.set_step(3) is False
    assert r.mesh.n_points == s[3].n_points
    assert np.array_equal(r.render(**LOOK), uvr.Renderer(s[3], "blob", device="cpu").render(**LOOK))


def test_set_step_is_refused_clearly(series_dir):
    m = uvr.read(series_dir / "s0.vtu")
    r = uvr.Renderer(m, "blob", device="cpu")
    with pytest.raises(uvr.ArgumentError, match="uvr.Series"):
        r.set_time(1.0)
    s = uvr.Series(series_dir / "run.pvd")
    by_values = uvr.Renderer(s, np.zeros(s[0].n_points), device="cpu")
    with pytest.raises(uvr.ArgumentError, match="given as values"):
        by_values.set_step(1)
    r = uvr.Renderer(s, "blob", device="cpu")
    with pytest.raises(uvr.ArgumentError, match="step 7"):
        r.set_step(7)
    assert r.step == 0


def test_animate_writes_a_movie_pillow_plays(cli, tmp_path):
    # Issue 35: uvr animate --movie, an animated PNG beside the frames, checked by Pillow.
    from PIL import Image as PilImage

    cli("-q", "generate", "box", "--cells", "2000", "--fields", "jet", "--steps", "3",
        "-o", tmp_path / "t.uvrm")
    movie = tmp_path / "m.png"
    cli("-q", "animate", tmp_path / "t.pvd", "-o", tmp_path / "frames", "--movie", movie,
        "--fps", "4", "--size", "64x48", "--device", "cpu", "--background", "0,0,0")
    with PilImage.open(movie) as m:
        assert m.format == "PNG" and m.is_animated and m.n_frames == 3
        frames = []
        for k in range(3):
            m.seek(k)
            assert m.info.get("duration") == 250  # ms at 4 frames per second
            frames.append(np.asarray(m.convert("RGB")))
    # Each movie frame is the frame PNG of its step.
    for k in range(3):
        with PilImage.open(tmp_path / "frames" / f"frame_{k:04d}.png") as f:
            assert np.array_equal(frames[k], np.asarray(f.convert("RGB")))
    assert not np.array_equal(frames[0], frames[2])
    # A movie not named .png is refused before rendering.
    r = cli("animate", tmp_path / "t.pvd", "-o", tmp_path / "f2", "--movie", tmp_path / "m.gif",
            check=False)
    assert r.returncode == 2 and "animated PNG" in r.stderr
