# SPDX-License-Identifier: MIT
"""Transfer functions and cameras: presets, ParaView files round trips, ParaView's operations."""

import pathlib

import numpy as np
import pytest

import uvr

ORACLE = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "oracle"


def test_presets_and_opacity():
    names = uvr.presets()
    assert "Cool to Warm" in names and "Viridis (matplotlib)" in names
    tf = uvr.TransferFunction("viridis")
    assert tf.name == "Viridis (matplotlib)" and tf.colors.shape[1] == 4
    tf.set_opacity("step:0.5:0.8")
    assert tf.opacities.tolist()[-1][1] == pytest.approx(0.8)
    tf.opacities = np.array([[0, 0], [1, 0.25]], dtype=np.float32)
    assert tf.bake(3)[:, 3].tolist() == pytest.approx([0, 0.125, 0.25])
    assert tf._repr_png_()[:4] == b"\x89PNG"
    with pytest.raises(uvr.ArgumentError, match="opacities: row 1 has a value outside"):
        tf.opacities = np.array([[0, 0], [2, 0.5]], dtype=np.float32)
    with pytest.raises(uvr.ArgumentError, match=r"colors \(rows x, r, g, b\): expected shape \(n, 4\)"):
        tf.colors = np.zeros((3, 3), dtype=np.float32)
    with pytest.raises(uvr.ArgumentError, match="Cool to Warm|unknown"):
        uvr.TransferFunction("cool to warmm")


def test_paraview_json_round_trip(tmp_path):
    tf = uvr.TransferFunction.load_paraview(ORACLE / "bands_lab.json")
    path = tmp_path / "map.json"
    tf.save(path, range=(0.5, 2.0))
    back = uvr.TransferFunction.load_paraview(path)
    assert back.color_space == tf.color_space
    assert np.allclose(back.opacities, tf.opacities, atol=1e-6)
    assert np.allclose(back.bake(64), tf.bake(64), atol=1e-6)
    assert back.to_json(0.5, 2.0) == tf.to_json(0.5, 2.0)
    again = uvr.TransferFunction.from_json(path.read_text())
    assert np.array_equal(again.bake(16), back.bake(16))
    bad = tmp_path / "bad.json"
    bad.write_text("[{\"RGBPoints\": [0, 1]}]")
    with pytest.raises(uvr.ParseError, match="bad.json"):
        uvr.TransferFunction.load_paraview(bad)
    with pytest.raises(uvr.FileError):
        uvr.TransferFunction.load_paraview(tmp_path / "missing.json")


def test_pvcc_round_trip_and_paraview_operations(tmp_path):
    cam = uvr.Camera.load(ORACLE / "post_oblique.pvcc")
    path = tmp_path / "view.pvcc"
    cam.save(path)
    back = uvr.Camera.load(path)
    for attr in ("position", "focal_point", "view_up", "view_angle", "parallel_projection",
                 "parallel_scale"):
        assert getattr(back, attr) == getattr(cam, attr)
    assert uvr.Camera.from_pvcc(cam.to_pvcc()).to_pvcc() == cam.to_pvcc()
    reset = uvr.Camera.reset(((-1, -1, -1), (1, 1, 1)))
    assert reset.view_angle == 30 and reset.view_up == [0, 1, 0]
    assert reset.position[2] > 0 and reset.focal_point == [0, 0, 0]
    turned = reset.azimuth(90)
    assert turned.position[0] == pytest.approx(reset.position[2], rel=1e-5)
    assert turned.position[2] == pytest.approx(0, abs=1e-5)
    assert reset.zoom(2).view_angle == 15
    assert reset.elevation(90).view_up != reset.view_up
    with pytest.raises(uvr.ArgumentError, match="zoom"):
        reset.zoom(0)
    (tmp_path / "bad.pvcc").write_text("<PVCameraConfiguration/>")
    with pytest.raises(uvr.ParseError, match="bad.pvcc"):
        uvr.Camera.load(tmp_path / "bad.pvcc")
