# SPDX-License-Identifier: MIT
"""Rendering: the CLI's pixels, time steps without rebuilding, the GIL, bad arguments."""

import json
import threading
import time

import numpy as np
import pytest

import uvr

VIEW = ["--size", "64x48", "--azimuth", "30", "--elevation", "20", "--device", "cpu", "-q"]


def python_frame(renderer, **kw):
    return renderer.render(size=(64, 48), azimuth=30, elevation=20, **kw)


@pytest.mark.parametrize("case", [
    ("spx.vtk", [], {}),
    ("post_tets.vtk", ["--tf", "viridis", "--opacity", "0:0,1:0.4"],
     dict(tf="viridis", opacity="0:0,1:0.4")),
    ("bluntfin_tets.vtk", ["--field", "momentum:magnitude", "--range", "0,3", "--method",
                           "reference"],
     dict(field="momentum:magnitude", range=(0, 3), method="reference")),
    ("cylinder_quadratic_as_tets.vtk", ["--field", "pressure:cell", "--method", "exact",
                                        "--tf", "Turbo"],
     dict(field="pressure:cell", method="exact", tf="Turbo")),
    ("fire_ug.vtu", ["--opacity", "step:0.5:0.8", "--background", "1,1,1", "--quality", "0.999"],
     dict(opacity="step:0.5:0.8", background=(1, 1, 1), quality=0.999)),
    ("tetraMesh.vtk", ["--opacity-law", "transmittance"], dict(opacity_law="transmittance")),
    ("bluntfin_tets.vtk", ["--clip-plane", "3,0,0,-1,0,0", "--clip-plane", "0,4,0,0,-1,0",
                           "--clip-box", "-8,0,0,14,8,3", "--method", "exact"],
     dict(clip_planes=[((3, 0, 0), (-1, 0, 0)), (0, 4, 0, 0, -1, 0)],
          clip_box=((-8, 0, 0), (14, 8, 3)), method="exact")),
    ("bluntfin_tets.vtk", ["--clip-plane", "3,0,0,1,0,0", "--clip-surface", "--ambient", "0.3",
                           "--method", "adaptive"],
     dict(clip_planes=[((3, 0, 0), (1, 0, 0))], clip_surface=True, ambient=0.3,
          method="adaptive")),
    ("post_tets.vtk", ["--shade", "--ambient", "0.2", "--specular", "0.3", "--specular-power", "12"],
     dict(shade=True, ambient=0.2, specular=0.3, specular_power=12)),
    ("bluntfin_tets.vtk", ["--iso", "0.9", "--iso", "1.2,0.5,#ff8000", "--specular", "0.2",
                           "--method", "adaptive"],
     dict(iso=[0.9, (1.2, 0.5, "#ff8000")], specular=0.2, method="adaptive")),
    ("bluntfin_tets.vtk", ["--gradient-opacity", "0:0.2,0.5:1", "--shade", "--normals", "cell",
                           "--method", "adaptive"],
     dict(gradient_opacity=[(0, 0.2), (0.5, 1)], shade=True, normals="cell",
          method="adaptive")),
], ids=lambda c: c[0])
def test_the_same_settings_give_the_clis_pixels(data_dir, cli, tmp_path, case):
    name, flags, kwargs = case
    out = tmp_path / "cli.png"
    cli("render", data_dir / name, "-o", out, *VIEW, *flags)
    r = uvr.Renderer(data_dir / name, field=kwargs.pop("field", None), device="cpu")
    img = python_frame(r, **kwargs)
    assert img.png_bytes() == out.read_bytes()
    from matplotlib.image import imread

    assert np.array_equal(img.to_uint8(), np.round(imread(out) * 255).astype(np.uint8))
    assert img.stats["samples"] > 0


def test_auto_is_the_default_and_says_what_it_rendered_with(data_dir):
    # The library's one list of methods, the default first.
    assert uvr._uvr.METHODS == ["auto", "adaptive", "reference", "exact"]
    spx = data_dir / "spx.vtk"
    img = uvr.render(spx, size=(32, 32), device="cpu")
    assert img.stats["method"] == "exact"  # few cells per ray: exact is the faster there
    assert "about 13.2 cells per ray, at most 32 on the CPU" in img.stats["method_reason"]
    # An argument tuning sampling makes auto the adaptive method it tunes.
    tuned = uvr.render(spx, size=(32, 32), device="cpu", quality=0.995)
    assert tuned.stats["method"] == "adaptive"
    assert "tune its sampling" in tuned.stats["method_reason"]
    # A renderer prepared for adaptive alone renders auto with what it has, and says so.
    r = uvr.Renderer(spx, device="cpu", methods=("adaptive",))
    only = r.render(size=(32, 32))
    assert only.stats["method"] == "adaptive"
    assert "the mesh BVH exact needs was not prepared" in only.stats["method_reason"]
    assert "method_reason" not in r.render(size=(32, 32), method="adaptive").stats
    expected = "method='fast': expected 'auto', 'adaptive', 'reference' or 'exact'"
    with pytest.raises(uvr.ArgumentError, match=expected):
        uvr.render(spx, size=(32, 32), device="cpu", method="fast")
    with pytest.raises(uvr.ArgumentError, match=expected):
        r.render(size=(32, 32), method="fast")


def test_hexahedra_render_natively_unless_split_as_the_cli_does(data_dir, cli, tmp_path):
    native = uvr.Renderer(data_dir / "hexa.vtk", device="cpu")
    split = uvr.Renderer(data_dir / "hexa.vtk", device="cpu", split_cells=True)
    assert (native.info["hexahedra"], native.info["tetrahedra"]) == (10648, 0)
    assert (split.info["hexahedra"], split.info["tetrahedra"]) == (0, 6 * 10648)
    for renderer, flags in ((native, []), (split, ["--split-cells"])):
        out = tmp_path / "cli.png"
        cli("render", data_dir / "hexa.vtk", "-o", out, *VIEW, *flags)
        assert python_frame(renderer).png_bytes() == out.read_bytes()


def test_a_pvcc_camera_and_a_paraview_json_give_the_clis_pixels(data_dir, cli, tmp_path):
    import pathlib
    oracle = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "oracle"
    out = tmp_path / "cli.png"
    cli("render", data_dir / "post_tets.vtk", "-o", out, "--size", "64x48", "--device", "cpu",
        "-q", "--camera", oracle / "post_oblique.pvcc", "--tf", oracle / "bands_lab.json")
    r = uvr.Renderer(data_dir / "post_tets.vtk", device="cpu")
    img = r.render(size=(64, 48), camera=uvr.Camera.load(oracle / "post_oblique.pvcc"),
                   tf=str(oracle / "bands_lab.json"))
    assert img.png_bytes() == out.read_bytes()


def test_new_field_values_rebuild_nothing_and_match_a_fresh_renderer(data_dir):
    mesh = uvr.read(data_dir / "spx.vtk")
    x = np.asarray(mesh.points)[:, 0]
    r = uvr.Renderer(mesh, device="cpu")
    before = r.info
    for t in (0.0, 0.5):
        values = np.sin(2 * x + t).astype(np.float32)
        a = r.render(field=values, size=(48, 40), range=(-1, 1), azimuth=10)
        b = uvr.Renderer(mesh, field=values, device="cpu").render(size=(48, 40), range=(-1, 1),
                                                                  azimuth=10)
        assert np.array_equal(a, b)
    after = r.info
    assert after["value_updates"] == 2
    assert after["partition_build_seconds"] == before["partition_build_seconds"]
    assert after["prepare_seconds"] == before["prepare_seconds"]
    # Back to the file's field by name, and a cell field of the same mesh.
    r.render(field="scalars", size=(8, 8))
    r.set_field(np.arange(mesh.n_cells, dtype=np.float64), association="cell")
    assert r.info["field_association"] == "cell" and r.info["value_updates"] == 4


def test_the_gil_is_released_while_rendering(data_dir):
    r = uvr.Renderer(data_dir / "bluntfin_tets.vtk", device="cpu", methods=("reference",))
    done = threading.Event()
    ticks = 0

    def work():
        r.render(size=(256, 256), method="reference", sample_distance=0.02)
        done.set()

    thread = threading.Thread(target=work)
    start = time.perf_counter()
    thread.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    thread.join()
    elapsed = time.perf_counter() - start
    assert elapsed > 0.05, "the frame was too quick to tell"
    assert ticks >= 10, f"the main thread ran {ticks} times in {elapsed:.2f} s"


def test_images_are_arrays_that_display_themselves(data_dir):
    img = uvr.render(data_dir / "tetraMesh.vtk", size=(20, 10))
    assert isinstance(img, np.ndarray) and img.shape == (10, 20, 4) and img.dtype == np.float32
    assert img._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"
    assert img.to_uint8().shape == (10, 20, 4) and img.to_uint8((0, 0, 0)).shape == (10, 20, 3)
    assert img.sample_counts.shape == (10, 20)
    assert {"render_seconds", "samples", "mean_samples_per_pixel", "rays", "method"} <= set(img.stats)
    crop = img[2:5]
    assert crop.stats is img.stats


def test_compare_report_gives_the_worst_pixels_under_the_clis_keys(cli, tmp_path):
    # A grey ramp, and the same with one pixel 40/255 brighter and a 3x3 block 10/255 darker:
    # the maximum is 40, 10 pixels are off by more than 4/255, the odd pixel is speckle.
    h, w = 48, 64
    a = np.zeros((h, w, 4), np.float32)
    a[..., :3] = (np.arange(w, dtype=np.float32) / (w - 1) * 0.5 + 0.2)[None, :, None]
    a[..., 3] = 1.0
    b = a.copy()
    b[20, 30, :3] += 40 / 255
    b[5:8, 5:8, :3] -= 10 / 255
    a, b = uvr.Image(a), uvr.Image(b)
    r = uvr.compare_report(a, b)
    assert r["max_abs_difference"] == 40
    assert r["fraction_off"] == pytest.approx(10 / (h * w))
    assert r["speckle_fraction"] > 0 and r["seam_count"] == 0
    assert isinstance(r["seam_count"], int) and 0.9 < r["ssim"] < 1
    assert uvr.compare(a, b) == (r["ssim"], r["psnr"])
    same = uvr.compare_report(a, a)
    assert same["psnr"] is None and same["max_abs_difference"] == 0
    assert uvr.compare(a, a) == (1.0, float("inf"))
    # The CLI's JSON of the same PNGs: the same keys and values.
    a.save(tmp_path / "a.png")
    b.save(tmp_path / "b.png")
    j = json.loads(cli("compare", "--json", tmp_path / "a.png", tmp_path / "b.png").stdout)
    for key, value in r.items():
        assert j[key] == pytest.approx(value), key
    with pytest.raises(uvr.ArgumentError):
        uvr.compare_report(a, uvr.Image(np.zeros((h, w + 1, 4), np.float32)))


def test_bad_render_arguments_are_refused_with_the_librarys_messages(data_dir):
    r = uvr.Renderer(data_dir / "tetraMesh.vtk", device="cpu")
    with pytest.raises(uvr.ArgumentError, match=r"^size=0x10: each side must be between 1 and"):
        r.render(size=(0, 10))
    with pytest.raises(uvr.ArgumentError, match="size: expected"):
        r.render(size=5)
    with pytest.raises(uvr.ArgumentError, match="methods: unknown"):
        uvr.Renderer(data_dir / "tetraMesh.vtk", methods=("fast",))
    # The library's messages in Python's spelling: the keyword, not a CLI flag.
    with pytest.raises(uvr.ArgumentError, match=r"^quality=2\.0: expected a number in \[0\.5, 0\.9999\]$"):
        r.render(quality=2.0)
    with pytest.raises(uvr.ArgumentError, match=r"^supersample=9: expected an integer in \[1, 8\]$"):
        r.render(supersample=9)
    with pytest.raises(uvr.ArgumentError, match=r"^sample_distance=-1\.0: expected a positive finite number$"):
        r.render(sample_distance=-1.0)
    with pytest.raises(uvr.ArgumentError, match=r"^skip='no': expected true or false$"):
        r.render(skip="no")
    with pytest.raises(uvr.ArgumentError, match="'qualty': not a setting; the settings are 'method'"):
        r.render(qualty=0.9)
    with pytest.raises(uvr.ArgumentError, match="^field='nope': not found; available: scalars"):
        r.render(field="nope")
    with pytest.raises(uvr.ArgumentError, match="field: expected 55 point values or 160 cell"):
        r.render(field=np.zeros(7))
    with pytest.raises(uvr.ArgumentError, match=r"^range=2,1: expected finite lo <= hi$"):
        r.render(range=(2, 1))
    with pytest.raises(uvr.ArgumentError, match=r"^`log_scale` needs positive values: `range`"):
        r.render(range=(-2, -1), log_scale=True)
    with pytest.raises(uvr.ArgumentError, match="unknown"):
        r.render(tf="no such map")
    with pytest.raises(uvr.FileError):
        r.render(tf="/nonexistent/map.json")
    with pytest.raises(TypeError, match="camera: expected a uvr.Camera"):
        r.render(camera="front")
    with pytest.raises(uvr.ArgumentError, match="^opacity=\"wobbly\": "):
        r.render(opacity="wobbly")
    with pytest.raises(uvr.ArgumentError, match="opacity_law='linear': expected 'attenuation' or"):
        r.render(opacity_law="linear")
    with pytest.raises(uvr.ArgumentError, match="position equal|focal"):
        r.render(camera=uvr.Camera(position=(0, 0, 0), focal_point=(0, 0, 0)))
    with pytest.raises(uvr.ArgumentError, match="device: expected auto, cpu or cuda"):
        uvr.Renderer(data_dir / "tetraMesh.vtk", device="tpu")
    if not uvr.cuda_available():
        with pytest.raises(uvr.UnsupportedError, match="no CUDA device"):
            uvr.Renderer(data_dir / "tetraMesh.vtk", device="cuda")
    # Clipping (issue 32): planes as (origin, normal), a box as (lo, hi).
    with pytest.raises(uvr.ArgumentError, match=r"^clip_planes=\(1, 2, 3\): expected \(origin"):
        r.render(clip_planes=[(1, 2, 3)])
    with pytest.raises(uvr.ArgumentError, match=r"^clip_planes='x': expected a list of planes"):
        r.render(clip_planes="x")
    with pytest.raises(uvr.ArgumentError, match=r"^clip_planes=0,0,0,0,0,0: expected a finite"):
        r.render(clip_planes=[((0, 0, 0), (0, 0, 0))])
    with pytest.raises(uvr.ArgumentError, match=r"^clip_planes=7 planes: expected at most 6"):
        r.render(clip_planes=[(0, 0, 0, 1, 0, 0)] * 7)
    with pytest.raises(uvr.ArgumentError, match=r"^clip_box=1,0,0,0,1,1: expected finite"):
        r.render(clip_box=((1, 0, 0), (0, 1, 1)))
    with pytest.raises(uvr.ArgumentError, match=r"^clip_box=.*: expected \(lo, hi\)"):
        r.render(clip_box=(0, 0, 0))
    # Gradient shading (issue 32): a coefficient needs shade=True.
    with pytest.raises(uvr.ArgumentError, match=r"^ambient=0.3: read only with `shade` on"):
        r.render(ambient=0.3)
    with pytest.raises(uvr.ArgumentError, match=r"^diffuse=2: expected a number in \[0, 1\]"):
        r.render(shade=True, diffuse=2)
    # Isosurfaces (issue 32): values, (value, opacity[, colour]) or the CLI's text.
    with pytest.raises(uvr.ArgumentError, match=r"^iso=0.5: expected a list of isosurfaces"):
        r.render(iso=0.5)
    with pytest.raises(uvr.ArgumentError, match=r"^iso=1,2: expected VALUE\[,OPACITY"):
        r.render(iso=[(1, 2)])
    with pytest.raises(uvr.ArgumentError, match=r"^iso=\(1, 1, 'red'\): expected a list"):
        r.render(iso=[(1, 1, "red")])
    with pytest.raises(uvr.ArgumentError, match=r"^iso=1,1,#ff: expected VALUE"):
        r.render(iso=["1,1,#ff"])
    with pytest.raises(uvr.ArgumentError, match=r"^iso=9 isosurfaces: expected at most 8"):
        r.render(iso=list(range(9)))
    assert r.render(size=(8, 8), iso=[(2, 0.5, (1, 0, 0)), "2.5,1,#00ff00"]).stats["iso"] == [
        "2,0.5,#ff0000", "2.5,1,#00ff00"]
    # Gradient opacity (issue 32): (magnitude, scale) pairs or the CLI's text.
    expected = r"expected up to 8 \(magnitude, scale\) pairs"
    with pytest.raises(uvr.ArgumentError, match=r"^gradient_opacity=0.5: " + expected):
        r.render(gradient_opacity=0.5)
    with pytest.raises(uvr.ArgumentError, match=r"^gradient_opacity=\[\(1, 2\)\]: " + expected):
        r.render(gradient_opacity=[(1, 2)])
    with pytest.raises(uvr.ArgumentError, match=r"^gradient_opacity=\[\(2, 1\), \(1, 0\)\]"):
        r.render(gradient_opacity=[(2, 1), (1, 0)])
    with pytest.raises(uvr.ArgumentError, match=r"^gradient_opacity=\[\(True, 1\)\]"):
        r.render(gradient_opacity=[(True, 1)])
    with pytest.raises(uvr.ArgumentError, match=r"^gradient_opacity=1:2: expected MAGNITUDE"):
        r.render(gradient_opacity="1:2")
    pairs = r.render(size=(8, 8), gradient_opacity=[(0, 0), (1.5, 1)])
    assert pairs.stats["gradient_opacity"] == "0:0,1.5:1"
    assert np.array_equal(pairs, r.render(size=(8, 8), gradient_opacity="0:0,1.5:1"))
    # Still usable after every refusal.
    assert r.render(size=(8, 8)).stats["samples"] > 0


def test_depth_out_and_in(data_dir):
    # Issue 32: depth= gives the view depths of an opaque isosurface; depth_in= ends the rays
    # there, so nothing behind it is added; a depth image of another shape is refused.
    r = uvr.Renderer(data_dir / "bluntfin_tets.vtk", device="cpu")
    kw = dict(size=(48, 32), method="exact", azimuth=30, elevation=20)
    img = r.render(iso=[0.9], depth=0.5, **kw)
    assert img.depth.shape == (32, 48) and img.depth.dtype == np.float32
    hit = np.isfinite(img.depth)
    assert hit.sum() > 100 and (img.depth[hit] > 0).all()
    assert img.stats["depth_alpha"] == 0.5
    assert r.render(**kw).depth is None
    whole = r.render(**kw)
    front = r.render(depth_in=img.depth, **kw)
    assert front.stats["depth_in"] is True
    assert (np.asarray(front)[..., 3] <= np.asarray(whole)[..., 3] + 1e-5).all()
    assert np.array_equal(np.asarray(front)[~hit], np.asarray(whole)[~hit])
    with pytest.raises(uvr.ArgumentError, match=r"^depth_in=shape \(48, 32\): expected the frame's"):
        r.render(depth_in=img.depth.T, **kw)
    with pytest.raises(uvr.ArgumentError, match=r"^depth=2: expected the opacity"):
        r.render(depth=2, **kw)
    with pytest.raises(uvr.ArgumentError, match=r"^depth=True: expected the opacity"):
        r.render(depth=True, **kw)
    with pytest.raises(uvr.ArgumentError, match=r"^depth_in=a str: expected a 2-D array"):
        r.render(depth_in="x", **kw)


def test_the_settings_vocabulary_is_the_librarys(data_dir):
    names = [d["name"] for d in uvr.SETTINGS]
    assert names[:3] == ["method", "sampling", "step_rule"] and len(set(names)) == len(names)
    quality = next(d for d in uvr.SETTINGS if d["name"] == "quality")
    assert quality["default"] == pytest.approx(0.99) and quality["min"] == 0.5
    assert quality["tunes_adaptive"]
    # Every setting is a keyword of render, documented in its docstring.
    for name in names:
        assert f"        {name} (" in uvr.Renderer.render.__doc__, name
    # numpy scalars are numbers; a value of another type is refused by name.
    r = uvr.Renderer(data_dir / "tetraMesh.vtk", device="cpu", methods=("adaptive",))
    img = r.render(size=(16, 16), method="adaptive", quality=np.float32(0.995),
                   supersample=np.int64(2), sample_distance=None)
    assert img.stats["quality"] == pytest.approx(0.995) and img.stats["supersample"] == 2
    with pytest.raises(uvr.ArgumentError, match=r"^power='\[2\]': expected a number in \[1, 64\]$"):
        r.render(power=[2])
    assert r.render(size=(8, 8), method="adaptive", skip=np.bool_(False)).stats["skip"] is False
    assert uvr._uvr.tunes_adaptive({"quality": 0.995})
    assert not uvr._uvr.tunes_adaptive({"quality": 0.99, "supersample": 4})


def test_the_version_is_the_clis(cli):
    assert uvr.__version__
    assert cli("--version").stdout.strip() == f"uvr {uvr.__version__}"


def test_a_legend_is_the_clis(data_dir, cli, tmp_path):
    # Issue 35: --legend in Python too; the title says point or cell data, the ends are labelled.
    out = tmp_path / "cli.png"
    cli("render", data_dir / "bluntfin_tets.vtk", "-o", out, "--size", "256x192", "--legend",
        "--background", "0,0,0", "--device", "cpu", "-q")
    img = uvr.render(data_dir / "bluntfin_tets.vtk", size=(256, 192), legend=True,
                     background=(0, 0, 0), device="cpu")
    assert img.png_bytes() == out.read_bytes()
    plain = uvr.render(data_dir / "bluntfin_tets.vtk", size=(256, 192), background=(0, 0, 0),
                       device="cpu")
    assert not np.array_equal(img, plain)
    # The reset camera, turned, moves the volume off the legend as the CLI's does; a camera
    # given stays, and the legend then changes only its own columns.
    cli("render", data_dir / "bluntfin_tets.vtk", "-o", out, "--size", "256x192", "--legend",
        "--azimuth", "30", "--elevation", "15", "--device", "cpu", "-q")
    turned = uvr.render(data_dir / "bluntfin_tets.vtk", size=(256, 192), legend=True,
                        azimuth=30, elevation=15, device="cpu")
    assert turned.png_bytes() == out.read_bytes()
    r = uvr.Renderer(data_dir / "bluntfin_tets.vtk", device="cpu")
    cam = r.camera((256, 192), azimuth=30, elevation=15)
    placed = r.render(size=(256, 192), camera=cam, legend=True)
    bare = r.render(size=(256, 192), camera=cam)
    assert np.array_equal(np.asarray(placed)[:, :128], np.asarray(bare)[:, :128])
    assert not np.array_equal(np.asarray(turned)[:, :128], np.asarray(bare)[:, :128])
