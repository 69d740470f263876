# SPDX-License-Identifier: MIT
"""uvr: unstructured volume rendering from Python.

Meshes from files (``uvr.read``), numpy arrays (``uvr.Mesh``), meshio (``uvr.from_meshio``) and
VTK/pyvista (``uvr.from_vtk``); ``uvr.Renderer`` prepares a mesh once and renders frames on the
CPU or a CUDA GPU; ``uvr.TransferFunction`` and ``uvr.Camera`` follow ParaView's conventions and
files. docs/PYTHON.md is the guide.
"""

import os as _os

from . import _uvr
from ._image import Image, compare, compare_report, contact_sheet, read_png
from ._mesh import Mesh, Series, as_mesh, from_meshio, from_vtk, read
from ._render import Renderer, render, transfer_function
from ._uvr import __version__
from ._uvr import (SETTINGS, ArgumentError, Camera, Error, FileError, InternalError, ParseError,
                   ResourceError, TransferFunction, UnsupportedError, ValidationError)

__all__ = ["SETTINGS", "ArgumentError", "Camera", "Error", "FileError", "Image", "InternalError", "Mesh",
           "ParseError", "Renderer", "ResourceError", "Series", "TransferFunction",
           "UnsupportedError", "ValidationError", "as_mesh", "compare", "compare_report",
           "contact_sheet", "cuda_available", "from_meshio", "from_vtk", "presets", "read",
           "read_png", "render", "transfer_function"]


def presets():
    """Names of the built-in colour maps (ParaView's presets)."""
    return list(_uvr.preset_names())


def cuda_available():
    """True when uvr was built with CUDA and a CUDA device can be used."""
    return bool(_uvr.cuda_available())


# ---- TransferFunction: Python conveniences over the library's class ----

def _tf_save(self, path, range=(0.0, 1.0)):
    """Writes the transfer function as a ParaView colour-map JSON over the data range
    (lo, hi) (atomically); ``TransferFunction.load_paraview`` and ParaView read it back."""
    _uvr.write_text(_os.fspath(path), self.to_json(float(range[0]), float(range[1])))


def _tf_repr(self):
    return (f"uvr.TransferFunction({self.name!r}, {len(self.colors)} colour points, "
            f"{len(self.opacities)} opacity points{', log scale' if self.log_scale else ''})")


def _tf_repr_png(self):
    """A colour bar: the colour map over [0, 1] (top) and its opacity as a grey ramp (bottom)."""
    import numpy as np
    t = self.bake(256)
    bar = np.empty((24, 256, 4), dtype=np.float32)
    bar[:16, :, :3] = t[None, :, :3]
    bar[16:, :, :3] = t[None, :, 3:4] / max(float(t[:, 3].max()), 1e-9)
    bar[..., 3] = 1.0
    return _uvr.png_bytes(bar, None)


def _with_path(load):
    """A loader taking any path-like (the compiled one takes str)."""
    def wrapped(path, *args, **kwargs):
        return load(_os.fspath(path), *args, **kwargs)
    wrapped.__doc__ = load.__doc__
    return staticmethod(wrapped)


TransferFunction.load = _with_path(TransferFunction.load)
TransferFunction.load_paraview = _with_path(TransferFunction.load_paraview)
TransferFunction.save = _tf_save
TransferFunction.__repr__ = _tf_repr
TransferFunction._repr_png_ = _tf_repr_png
TransferFunction.presets = staticmethod(presets)

# ---- Camera: ParaView's operations ----

_camera_reset = Camera.reset


def _camera_reset_any(bounds, aspect=1.0):
    """ParaView's reset camera for bounds ((lo), (hi)), or for anything with ``.bounds`` (a
    Mesh, a Renderer), at an aspect ratio (width / height)."""
    b = getattr(bounds, "bounds", bounds)
    return _camera_reset(tuple(tuple(float(x) for x in c) for c in b), float(aspect))


def _camera_azimuth(self, degrees):
    """A copy rotated about the view up through the focal point (ParaView's Azimuth)."""
    return self.orbit(float(degrees), 0.0)


def _camera_elevation(self, degrees):
    """A copy rotated about the right axis through the focal point (ParaView's Elevation)."""
    return self.orbit(0.0, float(degrees))


def _camera_zoom(self, factor):
    """A copy zoomed by `factor` (ParaView's Zoom): the view angle (perspective) or the parallel
    scale divided by it."""
    factor = float(factor)
    if not factor > 0.0:
        raise ArgumentError(f"zoom: expected a positive factor, got {factor}")
    c = self.__copy__()
    if c.parallel_projection:
        c.parallel_scale = c.parallel_scale / factor
    else:
        c.view_angle = c.view_angle / factor
    c.validate()
    return c


def _camera_save(self, path):
    """Writes the camera as a ParaView camera file (.pvcc), atomically."""
    _uvr.write_text(_os.fspath(path), self.to_pvcc())


def _camera_repr(self):
    p = "parallel scale %g" % self.parallel_scale if self.parallel_projection else \
        "view angle %g" % self.view_angle
    return (f"uvr.Camera(position={tuple(self.position)}, focal_point={tuple(self.focal_point)}, "
            f"view_up={tuple(self.view_up)}, {p})")


Camera.reset = staticmethod(_camera_reset_any)
Camera.load = _with_path(Camera.load)
Camera.azimuth = _camera_azimuth
Camera.elevation = _camera_elevation
Camera.zoom = _camera_zoom
Camera.save = _camera_save
Camera.__repr__ = _camera_repr
