# SPDX-License-Identifier: MIT
"""The renderer: prepare a mesh once, render any number of frames."""

import numpy as np

from . import _uvr
from ._image import Image, _background
from ._mesh import Series, as_mesh


def transfer_function(tf=None, opacity=None):
    """A TransferFunction from a preset name, a ParaView JSON path ("FILE.json[:NAME]") or a
    TransferFunction (copied), with ``opacity`` (an ``--opacity`` spec such as "ramp",
    "step:0.5", "0:0,1:0.3", or (x, alpha) pairs) applied."""
    if tf is None:
        t = _uvr.TransferFunction("Cool to Warm")
    elif isinstance(tf, _uvr.TransferFunction):
        t = tf.__copy__()
    elif isinstance(tf, str):
        t = _uvr.TransferFunction.load(tf)
    else:
        raise TypeError(f"tf: expected a preset name, a .json path or a uvr.TransferFunction, "
                        f"got {type(tf).__name__}")
    if opacity is not None:
        if isinstance(opacity, str):
            t.set_opacity(opacity)
        else:
            a = np.asarray(opacity, dtype=np.float32)
            if a.ndim != 2 or a.shape[1] != 2:
                raise _uvr.ArgumentError(f"opacity: expected (x, alpha) pairs of shape (k, 2), "
                                         f"got shape {a.shape}")
            t.opacities = np.ascontiguousarray(a)
    return t


class Renderer:
    """A mesh prepared once for rendering (tetrahedra, BVHs, k-d partitions; resident on the GPU
    when it renders there), rendering any number of frames.

    ``Renderer(mesh, field=None, device="auto")``: `mesh` is anything ``uvr.as_mesh`` takes;
    `field` a field spec as ``uvr render --field`` takes ("pressure", "velocity:magnitude",
    "T:cell"; None: the default field) or an array of values (one per point or cell). `device`:
    "auto" (CUDA when built with it and a GPU is present), "cpu" or "cuda".
    ``methods`` names the integrators to prepare for ("reference" and "exact" need the mesh
    BVH). Pyramids, wedges and hexahedra are rendered natively (trilinear hexahedra);
    ``split_cells=True`` splits them into tetrahedra instead, as ``uvr render --split-cells``. Changing the transfer function, camera, range, method or quality rebuilds nothing;
    new field values of the same mesh (``set_field``; ``render(field=...)``) rebuild nothing
    geometric either. Made from a ``uvr.Series``, it shows the first step and ``set_time`` /
    ``set_step`` show others (values only while the points and cells stay). The GIL is released
    while preparing and rendering.

    ``comm``: under ``mpirun``, mpi4py's ``MPI.COMM_WORLD`` renders data-parallel as
    ``mpirun -n N uvr render`` does: every rank makes the Renderer and calls ``render`` with the
    same arguments, each rank holds and renders its piece of the mesh, and rank 0's ``render``
    returns the whole picture (the other ranks' return None). ``largest_sample_distance``: the
    largest ``sample_distance`` its frames will ask for (the pieces' ghost cells reach it; a
    larger one is refused); None: twice the default.
    """

    def __init__(self, mesh, field=None, device="auto", *, build_device="auto", leaf_cells=0,
                 methods=tuple(_uvr.METHODS), seed_grids=True, split_cells=False,
                 association=None, comm=None, largest_sample_distance=None):
        self.series = mesh if isinstance(mesh, Series) else None
        self._step = 0
        self._ranks, self._rank = _ranks_of(comm)
        self._options = dict(device=device, build_device=build_device, leaf_cells=leaf_cells,
                             methods=methods, seed_grids=seed_grids, split_cells=split_cells,
                             largest_sample_distance=float(largest_sample_distance or 0.0))
        self._prepare(as_mesh(mesh), field, association)

    def _prepare(self, mesh, field, association=None):
        """Prepares `field` of `mesh` with the options given to the constructor."""
        device, build_device = self._options["device"], self._options["build_device"]
        leaf_cells, seed_grids = self._options["leaf_cells"], self._options["seed_grids"]
        methods = self._options["methods"]
        previous = getattr(self, "mesh", None)
        self.mesh = mesh
        try:
            name, assoc, values = self._field(field, association)
            unknown = set(methods) - set(_uvr.METHODS)
            if unknown:
                raise _uvr.ArgumentError(f"methods: unknown {sorted(unknown)}; expected some of "
                                         f"{_uvr.METHODS}")
            self._core = _uvr.Renderer(self.mesh._data, name, assoc, values, device,
                                       build_device, int(leaf_cells),
                                       mesh_bvh="reference" in methods or "exact" in methods,
                                       seed_grids=bool(seed_grids),
                                       split_cells=bool(self._options["split_cells"]),
                                       partitions="adaptive" in methods,
                                       for_auto="auto" in methods, ranks=self._ranks,
                                       largest_sample_distance=self._options[
                                           "largest_sample_distance"])
        except BaseException:
            self.mesh = previous  # a failed new step leaves the renderer as it was
            raise
        self._methods = tuple(methods)
        self._field_key = field if isinstance(field, str) or field is None else None
        self._by_values = self._field_key is None and field is not None

    @property
    def step(self):
        """The time step shown (0 for a mesh that is no series)."""
        return self._step

    @property
    def time(self):
        """The time of the step shown (0 for a mesh that is no series)."""
        return self.series.times[self._step] if self.series is not None else 0.0

    def set_step(self, step):
        """Shows time step `step` of the series the renderer was made from: when its points and
        cells equal the current ones only its values are read and refreshed (nothing geometric
        rebuilt, as set_field); otherwise the step is prepared anew. Returns True when only
        the values changed."""
        if self.series is None:
            raise _uvr.ArgumentError("set_step/set_time: the renderer was made from a mesh, not "
                                     "a uvr.Series (uvr.Series(path) opens one)")
        if self._by_values:
            raise _uvr.ArgumentError("set_step/set_time: the field was given as values; name "
                                     "it (field='pressure') to follow it through the steps")
        same = self.series._same_geometry(step, self.mesh)
        if same is not None:
            name, assoc, values = _uvr.select_field(same._data, same.fields,
                                                    self._field_key or "")[:3]
            self._core.set_field_values(name, assoc, values)
            self.mesh = same
        else:
            self._prepare(self.series.read(step), self._field_key)
        self._step = self.series._index(step, None)
        return same is not None

    def set_time(self, time):
        """Shows the step at `time` (the last step at or before it), as set_step. Returns True
        when only the values changed."""
        if self.series is None:
            return self.set_step(0)  # refused with the message above
        return self.set_step(self.series.step_at(time))

    def _field(self, field, association=None):
        """(name, association, float32 values) of a field spec or an array of values."""
        if field is None or isinstance(field, str):
            if not self.mesh.fields:
                raise _uvr.ArgumentError("the mesh has no fields: pass field=values (one per "
                                         "point or cell)")
            name, assoc, values, _ = _uvr.select_field(self.mesh._data, self.mesh.fields,
                                                       field or "")
            return name, assoc, values
        a = np.asarray(field)
        if a.dtype.kind not in "fiub":
            raise TypeError(f"field: expected real values, got dtype {a.dtype}")
        n_points, n_cells = self.mesh.n_points, self.mesh.n_cells
        if association is None:
            if a.ndim == 1 and a.shape[0] == n_points:
                association = "point"
            elif a.ndim == 1 and a.shape[0] == n_cells:
                association = "cell"
        if a.ndim != 1 or association not in ("point", "cell") or \
                a.shape[0] != (n_points if association == "point" else n_cells):
            raise _uvr.ArgumentError(f"field: expected {n_points} point values or {n_cells} cell "
                                     f"values (shape (n,)), got shape {a.shape}")
        return "values", association, np.ascontiguousarray(a, dtype=np.float32)

    def set_field(self, field, association=None):
        """New values of the same mesh (a time step; one per point or cell), or another field
        by its spec: the values, value ranges and macrocells are refreshed, nothing geometric is
        rebuilt (on the GPU only the value arrays are uploaded)."""
        name, assoc, values = self._field(field, association)
        self._core.set_field_values(name, assoc, values)
        self._field_key = field if isinstance(field, str) else None

    @property
    def bounds(self):
        """Bounds of the rendered tetrahedra, ((xmin, ymin, zmin), (xmax, ymax, zmax))."""
        return self._core.bounds

    @property
    def device(self):
        """"cpu" or "cuda"."""
        return self._core.device

    @property
    def info(self):
        """The preparation: tetrahedra, partitions, times, value updates, the field."""
        return self._core.info

    def camera(self, size=None, azimuth=0.0, elevation=0.0, zoom=1.0):
        """ParaView's reset camera for the mesh and the image size (default: the CLI's,
        uvr._uvr.DEFAULT_SIZE), orbited and zoomed."""
        w, h = _uvr.DEFAULT_SIZE if size is None else size
        cam = _uvr.Camera.reset(self.bounds, float(w) / float(h))
        if azimuth or elevation:
            cam = cam.orbit(azimuth, elevation)
        return cam.zoom(zoom) if zoom != 1.0 else cam

    def render(self, field=None, tf=None, opacity=None, range=None, camera=None,
               size=None, method=None, quality=None, *, azimuth=0.0,
               elevation=0.0, zoom=1.0, background=None, log_scale=None, nan_color=None,
               clip_planes=None, clip_box=None, iso=None, gradient_opacity=None, depth=None,
               depth_in=None, legend=False, **settings):
        """Renders a frame; returns a uvr.Image (float32 (h, w, 4), premultiplied RGBA) with
        ``.stats`` and ``.sample_counts``.

        The arguments are ``uvr render``'s flags: `tf` a preset, ParaView JSON or
        TransferFunction; `opacity` an opacity spec or (x, alpha) pairs; `range` (lo, hi) the
        values the transfer function spans (default: the field's); `camera` a uvr.Camera
        (default: ParaView's reset camera), then `azimuth`/`elevation`/`zoom`; `size` (w, h)
        (default: the CLI's, uvr._uvr.DEFAULT_SIZE);
        `field` switches to another field or new values first (set_field); `clip_planes` a list
        of up to six planes, each (origin, normal), keeping the side the normal points to, and
        `clip_box` (lo, hi) keeping its inside, in the file's coordinates (``--clip-plane``,
        ``--clip-box``); `iso` a list of up to eight isosurfaces, each a value, (value, opacity)
        or (value, opacity, colour) with colour "#RRGGBB" or (r, g, b) (``--iso``; default
        opaque, coloured by the colour map); `gradient_opacity` up to eight (magnitude, scale)
        pairs scaling the opacity by the field gradient's magnitude (VTK's gradient opacity; the
        field's units per file unit, scales in [0, 1]; ``--gradient-opacity``); `depth` an opacity in (0, 1]: the image's ``.depth``
        then holds per pixel the distance along the view direction (file units) where the
        opacity first reaches it, inf where it never does (``--depth``, ``--depth-opacity``);
        `depth_in` a (height, width) array of such distances of opaque geometry rendered
        elsewhere: every ray ends there (``--depth-in``); `legend` True draws ``--legend``'s
        colour legend (the field, point or cell, the range's ends) onto the image, the reset
        camera (no `camera` given) moved to keep the volume off it. The same settings give the
        CLI's pixels.

        `method`, `quality` and the other keywords are the library's settings (uvr.SETTINGS,
        each named, defaulted and checked there once; None means the default), listed below.
        Under method "auto" ``image.stats["method"]`` says which method rendered and
        ``["method_reason"]`` why.
        """
        if field is not None and (not isinstance(field, str) or field != self._field_key):
            self.set_field(field)
        t = transfer_function(tf, opacity)
        if log_scale is not None:
            t.log_scale = bool(log_scale)
        if nan_color is not None:
            c = [float(x) for x in nan_color]
            if len(c) not in (3, 4):
                raise _uvr.ArgumentError("nan_color: expected (r, g, b) or (r, g, b, a)")
            t.nan_color = c[:3]
            t.nan_opacity = c[3] if len(c) == 4 else 1.0
        if size is None:
            size = _uvr.DEFAULT_SIZE
        try:
            w, h = (int(size[0]), int(size[1]))
        except (TypeError, ValueError, IndexError):
            raise _uvr.ArgumentError(f"size: expected (width, height), got {size!r}") from None
        if range is not None:
            try:
                lo, hi = (float(range[0]), float(range[1]))
            except (TypeError, ValueError, IndexError):
                raise _uvr.ArgumentError(f"range: expected (lo, hi), got {range!r}") from None
            range = (lo, hi)
        # A camera of the reset one (turned, zoomed) keeps the volume off the legend.
        room_for_legend = bool(legend) and camera is None
        if camera is None and (azimuth or elevation or zoom != 1.0):
            camera = self.camera((w, h), azimuth, elevation, zoom)
        elif camera is not None:
            if not isinstance(camera, _uvr.Camera):
                raise TypeError(f"camera: expected a uvr.Camera, got {type(camera).__name__}")
            if azimuth or elevation:
                camera = camera.orbit(azimuth, elevation)
            if zoom != 1.0:
                camera = camera.zoom(zoom)
        # "auto" renders with whatever was prepared (its pick, else the other of exact and
        # adaptive; the stats say which).
        settings = _settings(method=method, quality=quality, clip_planes=clip_planes,
                             clip_box=clip_box, iso=iso, gradient_opacity=gradient_opacity,
                             depth=depth, depth_in=depth_in,
                             **settings)
        method = settings.get("method", "auto")
        if method != "auto" and method in _uvr.METHODS and method not in self._methods:
            raise _uvr.ArgumentError(f"method '{method}' was not prepared (methods="
                                     f"{self._methods!r} when the Renderer was made)")
        pixels, counts, stats, depth = self._core.render(t, range, camera, w, h, settings,
                                                         room_for_legend)
        if self._rank != 0:
            return None  # data-parallel: rank 0 holds the picture
        if legend:
            lo, hi = stats["range"]
            pixels = _uvr.draw_legend(pixels, t, lo, hi, stats["field"],
                                      stats["field_association"], bool(t.log_scale),
                                      _background(background))
        return Image(pixels, stats=stats, sample_counts=counts,
                     background=_background(background), depth=depth)

    def __repr__(self):
        i = self.info
        return (f"uvr.Renderer({i['tetrahedra']} tetrahedra, {i['partitions']} partitions, "
                f"field {i['field']} ({i['field_association']}), on {self.device})")


def _ranks_of(comm):
    """(ranks, rank) of a Renderer's `comm`: (1, 0) for None or one rank; else mpi4py's
    COMM_WORLD (or a communicator congruent with it), the only one uvr renders over."""
    if comm is None:
        return 1, 0
    if not all(hasattr(comm, a) for a in ("Get_size", "Get_rank", "Compare")):
        raise TypeError(f"comm: expected mpi4py's MPI.COMM_WORLD, got {type(comm).__name__}")
    from mpi4py import MPI  # the caller's communicator is mpi4py's: it is imported
    if MPI.Comm.Compare(comm, MPI.COMM_WORLD) not in (MPI.IDENT, MPI.CONGRUENT):
        raise _uvr.ArgumentError("comm: uvr renders over MPI.COMM_WORLD (or a duplicate of it), "
                                 "not a part of it")
    return comm.Get_size(), comm.Get_rank()


def _settings(**kwargs):
    """The settings of the vocabulary among keyword arguments, None (the default) left out;
    checked by the library, whose message names the first bad one (quality=1.5: ...)."""
    settings = {k: v for k, v in kwargs.items() if v is not None}
    _uvr.check_settings(settings)
    return settings


def _settings_doc():
    """Renderer.render's docstring lines for the settings vocabulary."""
    lines = []
    for d in _uvr.SETTINGS:
        what = (" | ".join(repr(c) for c in d["choices"]) if d["type"] == "choice"
                else d["type"])
        default = "per mesh" if d["default"] is None else repr(d["default"])
        lines.append(f"        {d['name']} ({what}, default {default}): {d['doc']}")
    return "\n".join(lines)


Renderer.render.__doc__ += "\n" + _settings_doc() + "\n"


def render(mesh, **kwargs):
    """One frame of a mesh: Renderer(mesh, field, device).render(**kwargs) (prepares only what
    the method needs: under "auto", what it picks, or the adaptive method's partitions when an
    argument tunes sampling)."""
    field = kwargs.pop("field", None)
    device = kwargs.pop("device", "auto")
    names = {d["name"] for d in _uvr.SETTINGS}
    settings = _settings(**{k: v for k, v in kwargs.items() if k in names})
    method = settings.get("method", "auto")
    # Under "auto", what a frame of these settings renders with (the library's tunesAdaptive).
    prepare = "adaptive" if method == "auto" and _uvr.tunes_adaptive(settings) else method
    return Renderer(mesh, field, device, methods=(method, prepare)).render(**kwargs)
