// SPDX-License-Identifier: MIT
#pragma once

// What the binding's parts share (python/src): the exceptions, the arrays in the library's exact
// layout, the mesh and series holders, the settings in Python's spelling, the renderer holder;
// and one bind_* function per concept, each adding its classes and functions to the module.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uvr/core/setting_error.h"
#include "uvr/mesh/io/vtk_cells.h"
#include "uvr/uvr.h"

namespace py = pybind11;

namespace uvr::python {

// ---- Exceptions: one Python class per ErrorKind, all below uvr.Error ----

/// The Python exception classes, indexed by ErrorKind.
struct ExceptionClasses {
    PyObject* base = nullptr;
    PyObject* byKind[7] = {};
};

extern ExceptionClasses gExceptions;

/// Creates uvr._uvr.NAME deriving from uvr.Error and `builtin` (so `except ValueError` works).
PyObject* addException(py::module_& m, const char* name, PyObject* builtin, const char* doc);

/// Raises the Python error of an Error's kind with its message (used by the translator and by
/// argument checks that happen in the binding).
[[noreturn]] void raise(ErrorKind kind, const std::string& message);

// ---- Arrays ----

/// The array `obj` as a C-contiguous array of T; anything else (another dtype, a strided view,
/// not an array) is refused naming `what`. The pure-Python layer converts before calling.
template <class T>
py::array_t<T, py::array::c_style> exactArray(const py::handle& obj, const std::string& what) {
    if (!py::array_t<T, py::array::c_style>::check_(obj))
        raise(ErrorKind::Argument,
              what + ": expected a C-contiguous numpy array of " +
                  std::string(py::str(py::dtype::of<T>())) + ", got " +
                  std::string(py::str(py::type::handle_of(obj).attr("__name__"))) +
                  (py::isinstance<py::array>(obj)
                       ? " of " + std::string(py::str(obj.attr("dtype"))) +
                             (py::array(py::reinterpret_borrow<py::array>(obj)).flags() &
                                      py::array::c_style
                                  ? ""
                                  : " (not C-contiguous)")
                       : std::string()));
    return py::reinterpret_borrow<py::array_t<T, py::array::c_style>>(obj);
}

/// Refuses an array whose shape is not `shape` (-1: any extent), naming `what`.
void checkShape(const py::array& a, std::initializer_list<py::ssize_t> shape,
                const std::string& what);

/// A numpy array that takes over a vector's memory (no copy): the vector lives in a capsule
/// that frees it with the array.
template <class T, class Elem = T>
py::array vectorArray(std::vector<Elem>&& v, std::vector<py::ssize_t> shape) {
    auto* owned = new std::vector<Elem>(std::move(v));
    py::capsule free(owned, [](void* p) { delete static_cast<std::vector<Elem>*>(p); });
    return py::array_t<T>(shape, reinterpret_cast<T*>(owned->data()), free);
}

/// A numpy view of memory owned by `base` (kept alive by the array).
template <class T>
py::array viewArray(const T* data, std::vector<py::ssize_t> shape, py::handle base) {
    py::array_t<T> a(shape, data, base);
    a.attr("setflags")(py::arg("write") = false);
    return a;
}

/// A float RGBA array (h, w, 4) as an Image (a copy).
Image imageOf(const py::handle& pixels);

Vec3f vec3(const std::array<float, 3>& a);

std::array<float, 3> arr3(Vec3f v);

// ---- Meshes ----

/// A mesh for the renderer: read from a file (owned by uvr, its arrays shown to Python as
/// read-only views without copies) or the caller's numpy arrays in uvr's layout (borrowed: kept
/// alive here, never copied by the mesh). The caller may change borrowed arrays at any time, so
/// nothing reads them but cellsNow and shapesNow, which check them again.
struct MeshData {
    std::shared_ptr<Mesh> owned;  ///< a file's mesh or a converted one; null when borrowed
    py::object arrays[4];         ///< borrowed points, types, offsets, connectivity
};

/// A view of the borrowed arrays as they are now: dtype, layout and shapes checked again (an
/// array may have been retyped, reshaped or resized in place since); the indices unchecked.
/// Valid only while the GIL is held (no other thread can then free or resize an array).
MeshView borrowedView(const py::object (&arrays)[4]);

/// Runs `fn` and adds to the message of an Error it throws that the borrowed arrays changed
/// (they passed the same checks when the mesh was made).
template <class Fn>
auto changedSinceMesh(Fn&& fn) {
    try {
        return fn();
    } catch (const Error& e) {
        raise(e.kind(), std::string("the mesh's arrays changed after uvr.Mesh(): ") + e.what());
    }
}

/// The points and cells of `d` as they are now, safe to read without the GIL for as long as the
/// pointer is held: a file's mesh itself; of borrowed arrays a copy made now (with the GIL, so
/// no array is freed meanwhile) and checked by validateCells. Nothing reads the borrowed memory
/// afterwards, so a later change, or one made from another thread while this copies (a torn
/// copy), reaches only a copy that validateCells has checked.
std::shared_ptr<const Mesh> cellsNow(const MeshData& d);

/// The mesh's arrays as they are now, for their counts (a borrowed array's shape may have
/// changed): borrowed ones checked again by borrowedView, their indices not; valid only while
/// the GIL is held.
MeshView shapesNow(const MeshData& d);

/// Borrows the four arrays after checking dtype, layout, shape and every index (validateCells,
/// which checks each offset before indexing with it: it reads in bounds even while another
/// thread writes).
std::unique_ptr<MeshData> borrowMesh(const py::handle& points, const py::handle& types,
                                     const py::handle& offsets, const py::handle& connectivity);

/// Converts VTK cells of any type (copied): appendVtkCells' rules (voxels reordered, quadratic
/// cells through their corners, 0D-2D cells dropped with a note).
std::unique_ptr<MeshData> convertMesh(const py::handle& points, const py::handle& types,
                                      const py::handle& offsets, const py::handle& connectivity);

/// The owned mesh's fields as (name, association, read-only view (n,) or (n, components)).
py::list ownedFields(const py::object& self, const MeshData& m);

/// A time step's fields read for a mesh held elsewhere (its geometry is that mesh's).
struct FieldSet {
    std::vector<Field> fields;
};

/// The fields of a FieldSet as (name, association, read-only array) tuples viewing its memory.
py::list fieldSetTuples(const py::object& self);

/// A mesh file or series opened for its time steps (see uvr.Series).
struct PySeries {
    std::unique_ptr<MeshSeries> series;
};

Association parseAssociation(const std::string& s, const std::string& what);

/// A scalar field from a 1-D float32 array (a copy into the library's field).
ScalarField scalarField(const std::string& name, const std::string& association,
                        const py::handle& values);

/// Chooses a field as `uvr render --field SPEC` does among (name, association, array) tuples
/// and extracts its scalar (component or magnitude); returns (name, association, values,
/// choice).
py::tuple selectField(const MeshData& mesh, const py::list& fields, const std::string& spec);

// ---- Rendering ----

/// A Python value as the settings vocabulary reads it: None, bool, int, float or str (numpy
/// scalars too); anything else as its repr, which the vocabulary refuses naming it.
nlohmann::json settingValue(const py::handle& v);

/// A JSON value of the library (a frame report, the settings vocabulary) as Python objects.
/// The keyword a library setting has in this module, where it differs from the setting's name.
std::string pythonName(const std::string& setting);

/// A library message in Python's spelling: each setting it mentions as its keyword (`log_scale`).
std::string pythonSpelling(const std::string& message);

py::object fromJson(const nlohmann::json& j);

/// RenderSettings from a dict of the settings vocabulary (settings_vocabulary.h): each key a
/// setting's name, each value checked there; the library's SettingError says what is wrong.
/// depthShape, when given, receives depth_in's (rows, columns) (renderFrame checks them against
/// the frame's size).
RenderSettings settingsOf(const py::dict& settings,
                          std::pair<py::ssize_t, py::ssize_t>* depthShape = nullptr);

/// The renderer object of the library with the GIL released around its long calls.
struct PyRenderer {
    std::unique_ptr<Renderer> renderer;
};

/// One frame: (pixels (h, w, 4) float32 premultiplied, sample counts (h, w) uint32, stats).
/// roomForLegend: the camera (none: the reset one) is moved to keep the volume off the legend
/// the caller draws (cameraBesideLegend).
py::tuple renderFrame(PyRenderer& self, const TransferFunction& tf,
                      std::optional<std::pair<float, float>> range, std::optional<Camera> camera,
                      int width, int height, const py::dict& settings, bool roomForLegend);

/// The prepared mesh's bounds in the file's coordinates ((lo, hi), each a 3-tuple).
py::tuple fileBounds(const PreparedMesh& p);
/// The same bounds as a box (float).
Bounds3f fileBox(const PreparedMesh& p);

Bounds3f boundsOf(const std::array<std::array<float, 3>, 2>& b);

/// Writes text to a file atomically (OutputFile: temporary, then rename).
void writeText(const std::string& path, const std::string& text);

// ---- The module's parts (one per concept; uvr_module.cpp calls them in this order) ----

/// The settings vocabulary, the methods and their checks.
void bindSettings(py::module_& m);
/// One Python exception class per ErrorKind, below uvr.Error, and the translator.
void bindErrors(py::module_& m);
/// MeshData, FieldSet, Series and field selection.
void bindMeshes(py::module_& m);
/// TransferFunction and the presets.
void bindTransferFunctions(py::module_& m);
/// Camera.
void bindCameras(py::module_& m);
/// Renderer.
void bindRenderer(py::module_& m);
/// Images: PNG, comparison, legends, annotations, and the device queries.
void bindImages(py::module_& m);

}  // namespace uvr::python
