// SPDX-License-Identifier: MIT
// uvr._uvr: the compiled half of the Python module, a thin pybind11 layer over the library's
// facade (uvr/uvr.h). It takes arrays only in the exact dtype and layout the library uses and
// refuses anything else naming the argument; conversions, defaults and the friendly API live in
// the pure-Python package beside it (python/uvr). docs/PYTHON.md describes both.
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

namespace {

// ---- Exceptions: one Python class per ErrorKind, all below uvr.Error ----

/// The Python exception classes, indexed by ErrorKind.
struct ExceptionClasses {
    PyObject* base = nullptr;
    PyObject* byKind[7] = {};
};
ExceptionClasses gExceptions;

/// Creates uvr._uvr.NAME deriving from uvr.Error and `builtin` (so `except ValueError` works).
PyObject* addException(py::module_& m, const char* name, PyObject* builtin, const char* doc) {
    py::tuple bases = builtin ? py::make_tuple(py::handle(gExceptions.base), py::handle(builtin))
                              : py::make_tuple(py::handle(PyExc_Exception));
    const std::string qualified = std::string("uvr._uvr.") + name;
    PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
    if (!cls) throw py::error_already_set();
    m.add_object(name, py::handle(cls));  // the module holds a reference; cls is never freed
    return cls;
}

/// Raises the Python error of an Error's kind with its message (used by the translator and by
/// argument checks that happen in the binding).
[[noreturn]] void raise(ErrorKind kind, const std::string& message) {
    throw Error(kind, message);
}

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
                const std::string& what) {
    bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
    std::string expected = "(";
    int i = 0;
    for (py::ssize_t s : shape) {
        if (i) expected += ", ";
        expected += s < 0 ? "n" : std::to_string(s);
        if (ok && s >= 0 && a.shape(i) != s) ok = false;
        ++i;
    }
    expected += shape.size() == 1 ? ",)" : ")";
    if (ok) return;
    std::string got = "(";
    for (py::ssize_t k = 0; k < a.ndim(); ++k) got += (k ? ", " : "") + std::to_string(a.shape(k));
    got += a.ndim() == 1 ? ",)" : ")";
    raise(ErrorKind::Argument, what + ": expected shape " + expected + ", got " + got);
}

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
Image imageOf(const py::handle& pixels) {
    auto a = exactArray<float>(pixels, "image");
    checkShape(a, {-1, -1, 4}, "image");
    Image image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
    std::memcpy(static_cast<void*>(image.pixels.data()), a.data(),
                image.pixels.size() * sizeof(Vec4f));
    return image;
}

Vec3f vec3(const std::array<float, 3>& a) {
    return {a[0], a[1], a[2]};
}
std::array<float, 3> arr3(Vec3f v) {
    return {v.x, v.y, v.z};
}

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
MeshView borrowedView(const py::object (&arrays)[4]) {
    auto p = exactArray<float>(arrays[0], "points");
    checkShape(p, {-1, 3}, "points");
    auto t = exactArray<std::uint8_t>(arrays[1], "types");
    checkShape(t, {-1}, "types");
    auto o = exactArray<std::uint64_t>(arrays[2], "offsets");
    checkShape(o, {t.shape(0) + 1}, "offsets (one more than the cells)");
    auto c = exactArray<std::uint32_t>(arrays[3], "connectivity");
    checkShape(c, {-1}, "connectivity");
    MeshView v;
    v.points = {reinterpret_cast<const Vec3f*>(p.data()), static_cast<std::size_t>(p.shape(0))};
    v.cellTypes = {reinterpret_cast<const CellType*>(t.data()),
                   static_cast<std::size_t>(t.shape(0))};
    v.cellOffsets = {o.data(), static_cast<std::size_t>(o.shape(0))};
    v.cellIndices = {c.data(), static_cast<std::size_t>(c.shape(0))};
    return v;
}

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
std::shared_ptr<const Mesh> cellsNow(const MeshData& d) {
    if (d.owned) return d.owned;
    return changedSinceMesh([&] {
        const MeshView v = borrowedView(d.arrays);
        auto copy = std::make_shared<Mesh>();
        copy->points.assign(v.points.begin(), v.points.end());
        copy->cellTypes.assign(v.cellTypes.begin(), v.cellTypes.end());
        copy->cellOffsets.assign(v.cellOffsets.begin(), v.cellOffsets.end());
        copy->cellIndices.assign(v.cellIndices.begin(), v.cellIndices.end());
        py::gil_scoped_release release;
        validateCells(*copy, "");
        return std::shared_ptr<const Mesh>(std::move(copy));
    });
}

/// The mesh's arrays as they are now, for their counts (a borrowed array's shape may have
/// changed): borrowed ones checked again by borrowedView, their indices not; valid only while
/// the GIL is held.
MeshView shapesNow(const MeshData& d) {
    if (d.owned) return *d.owned;
    return changedSinceMesh([&] { return borrowedView(d.arrays); });
}

/// Borrows the four arrays after checking dtype, layout, shape and every index (validateCells,
/// which checks each offset before indexing with it: it reads in bounds even while another
/// thread writes).
std::unique_ptr<MeshData> borrowMesh(const py::handle& points, const py::handle& types,
                                     const py::handle& offsets, const py::handle& connectivity) {
    auto out = std::make_unique<MeshData>();
    out->arrays[0] = py::reinterpret_borrow<py::object>(points);
    out->arrays[1] = py::reinterpret_borrow<py::object>(types);
    out->arrays[2] = py::reinterpret_borrow<py::object>(offsets);
    out->arrays[3] = py::reinterpret_borrow<py::object>(connectivity);
    validateCells(borrowedView(out->arrays), "");
    return out;
}

/// Converts VTK cells of any type (copied): appendVtkCells' rules (voxels reordered, quadratic
/// cells through their corners, 0D-2D cells dropped with a note).
std::unique_ptr<MeshData> convertMesh(const py::handle& points, const py::handle& types,
                                      const py::handle& offsets, const py::handle& connectivity) {
    auto p = exactArray<float>(points, "points");
    checkShape(p, {-1, 3}, "points");
    auto t = exactArray<std::int32_t>(types, "types");
    checkShape(t, {-1}, "types");
    auto o = exactArray<std::int64_t>(offsets, "offsets");
    checkShape(o, {t.shape(0) + 1}, "offsets (one more than the cells)");
    auto c = exactArray<std::int64_t>(connectivity, "connectivity");
    checkShape(c, {-1}, "connectivity");
    auto mesh = std::make_shared<Mesh>();
    mesh->points.assign(reinterpret_cast<const Vec3f*>(p.data()),
                        reinterpret_cast<const Vec3f*>(p.data()) + p.shape(0));
    VtkCellArrays cells;
    cells.types.assign(t.data(), t.data() + t.shape(0));
    cells.offsets.assign(o.data(), o.data() + o.shape(0));
    cells.connectivity.assign(c.data(), c.data() + c.shape(0));
    if (!cells.offsets.empty() && cells.offsets[0] != 0)
        raise(ErrorKind::Validation,
              "cell 0: offset " + std::to_string(cells.offsets[0]) + ", expected 0");
    appendVtkCells(cells, *mesh, "");
    auto out = std::make_unique<MeshData>();
    out->owned = std::move(mesh);
    return out;
}

/// The owned mesh's fields as (name, association, read-only view (n,) or (n, components)).
py::list ownedFields(const py::object& self, const MeshData& m) {
    py::list out;
    if (!m.owned) return out;
    for (const Field& f : m.owned->fields) {
        const auto n = static_cast<py::ssize_t>(f.tupleCount());
        py::array a = f.components == 1 ? viewArray(f.values.data(), {n}, self)
                                        : viewArray(f.values.data(), {n, f.components}, self);
        out.append(py::make_tuple(f.name, associationName(f.association), a));
    }
    return out;
}

/// A time step's fields read for a mesh held elsewhere (its geometry is that mesh's).
struct FieldSet {
    std::vector<Field> fields;
};

/// The fields of a FieldSet as (name, association, read-only array) tuples viewing its memory.
py::list fieldSetTuples(const py::object& self) {
    py::list out;
    for (const Field& f : self.cast<const FieldSet&>().fields) {
        const auto n = static_cast<py::ssize_t>(f.tupleCount());
        py::array a = f.components == 1 ? viewArray(f.values.data(), {n}, self)
                                        : viewArray(f.values.data(), {n, f.components}, self);
        out.append(py::make_tuple(f.name, associationName(f.association), a));
    }
    return out;
}

/// A mesh file or series opened for its time steps (see uvr.Series).
struct PySeries {
    std::unique_ptr<MeshSeries> series;
};

Association parseAssociation(const std::string& s, const std::string& what) {
    if (s == "point") return Association::Point;
    if (s == "cell") return Association::Cell;
    raise(ErrorKind::Argument, what + ": expected 'point' or 'cell', got '" + s + "'");
}

/// A scalar field from a 1-D float32 array (a copy into the library's field).
ScalarField scalarField(const std::string& name, const std::string& association,
                        const py::handle& values) {
    auto a = exactArray<float>(values, "values");
    checkShape(a, {-1}, "values");
    ScalarField f;
    f.name = name;
    f.association = parseAssociation(association, "association");
    f.values.assign(a.data(), a.data() + a.shape(0));
    return f;
}

/// Chooses a field as `uvr render --field SPEC` does among (name, association, array) tuples
/// and extracts its scalar (component or magnitude); returns (name, association, values,
/// choice).
py::tuple selectField(const MeshData& mesh, const py::list& fields, const std::string& spec) {
    const MeshView shapes = shapesNow(mesh);
    std::vector<FieldInfo> infos;
    std::vector<py::array_t<float, py::array::c_style>> arrays;
    for (const py::handle& item : fields) {
        const auto t = item.cast<py::tuple>();
        const std::string name = t[0].cast<std::string>();
        const Association assoc = parseAssociation(t[1].cast<std::string>(), "association");
        auto a = exactArray<float>(t[2], "field '" + name + "'");
        const std::uint64_t tuples =
            assoc == Association::Point ? shapes.pointCount() : shapes.cellCount();
        if (a.ndim() < 1 || a.ndim() > 2 || static_cast<std::uint64_t>(a.shape(0)) != tuples)
            raise(ErrorKind::Argument,
                  std::string(associationName(assoc)) + " field '" + name + "': expected " +
                      std::to_string(tuples) + " tuples (one per " + associationName(assoc) +
                      "), got an array of shape " + std::string(py::str(a.attr("shape"))));
        infos.push_back({name, assoc, a.ndim() == 2 ? static_cast<int>(a.shape(1)) : 1});
        arrays.push_back(a);
    }
    const FieldSpec parsed = parseFieldSpec(spec);
    const FieldChoice choice = resolveField(infos, parsed);
    const auto& a = arrays[choice.index];
    Field f{infos[choice.index].name, infos[choice.index].association,
            infos[choice.index].components, std::vector<float>(a.data(), a.data() + a.size())};
    ScalarField s = scalarFieldOf(shapes, f, parsed.component);  // reads only the counts
    const auto n = static_cast<py::ssize_t>(s.values.size());
    return py::make_tuple(s.name, associationName(s.association),
                          vectorArray<float>(std::move(s.values), {n}), choice.choice);
}

// ---- Rendering ----

/// A Python value as the settings vocabulary reads it: None, bool, int, float or str (numpy
/// scalars too); anything else as its repr, which the vocabulary refuses naming it.
nlohmann::json settingValue(const py::handle& v) {
    if (v.is_none()) return nullptr;
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>();
    // numpy booleans (their __index__ would read them as 0 and 1)
    if (py::hasattr(v, "dtype") && py::str(v.attr("dtype").attr("kind")).cast<std::string>() == "b")
        return py::reinterpret_borrow<py::object>(v).attr("__bool__")().cast<bool>();
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    if (py::hasattr(v, "__index__")) {  // int, numpy integers
        const py::object i = py::module_::import("operator").attr("index")(v);
        try {
            return i.cast<std::int64_t>();
        } catch (const py::cast_error&) {
            return py::str(i).cast<std::string>();  // beyond 64 bits: refused as written
        }
    }
    if (py::hasattr(v, "__float__")) return v.cast<double>();  // numpy floats
    return py::str(py::repr(v)).cast<std::string>();           // refused as what it is
}

/// A JSON value of the library (a frame report, the settings vocabulary) as Python objects.
/// The keyword a library setting has in this module, where it differs from the setting's name.
std::string pythonName(const std::string& setting) {
    if (setting == "log") return "log_scale";
    if (setting == "seed_grid") return "seed_grids";
    return setting;
}

/// A library message in Python's spelling: each setting it mentions as its keyword (`log_scale`).
std::string pythonSpelling(const std::string& message) {
    return respellMentions(message, [](std::string_view setting) {
        return "`" + pythonName(std::string(setting)) + "`";
    });
}

py::object fromJson(const nlohmann::json& j) {
    return py::module_::import("json").attr("loads")(
        j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

/// RenderSettings from a dict of the settings vocabulary (settings_vocabulary.h): each key a
/// setting's name, each value checked there; the library's SettingError says what is wrong.
RenderSettings settingsOf(const py::dict& settings) {
    RenderSettings s;
    for (const auto& [k, v] : settings)
        applySetting(s, py::str(k).cast<std::string>(), settingValue(v));
    return s;
}

/// The renderer object of the library with the GIL released around its long calls.
struct PyRenderer {
    std::unique_ptr<Renderer> renderer;
};

/// One frame: (pixels (h, w, 4) float32 premultiplied, sample counts (h, w) uint32, stats).
py::tuple renderFrame(PyRenderer& self, const TransferFunction& tf,
                      std::optional<std::pair<float, float>> range, std::optional<Camera> camera,
                      int width, int height, const py::dict& settings) {
    RenderSettings s = settingsOf(settings);
    s.width = width, s.height = height;
    s.tf = tf;
    s.range = range;
    s.camera = camera;
    RenderResult r;
    {
        py::gil_scoped_release release;
        r = self.renderer->render(s);
    }
    // The library's frame report (the CLI's --stats, the viewer's frame messages), as a dict.
    py::object stats = fromJson(frameReport(*self.renderer, s, r));
    const auto h = static_cast<py::ssize_t>(height), w = static_cast<py::ssize_t>(width);
    py::array pixels = vectorArray<float>(std::move(r.image.pixels), {h, w, 4});
    py::array counts = vectorArray<std::uint32_t>(std::move(r.sampleCounts), {h, w});
    return py::make_tuple(pixels, counts, stats);
}

/// The prepared mesh's bounds in the file's coordinates ((lo, hi), each a 3-tuple).
py::tuple fileBounds(const PreparedMesh& p) {
    double lo[3], hi[3];
    p.tets.frame.toFile(p.tets.bounds.lo, lo);
    p.tets.frame.toFile(p.tets.bounds.hi, hi);
    return py::make_tuple(py::make_tuple(lo[0], lo[1], lo[2]), py::make_tuple(hi[0], hi[1], hi[2]));
}

Bounds3f boundsOf(const std::array<std::array<float, 3>, 2>& b) {
    return {vec3(b[0]), vec3(b[1])};
}

/// Writes text to a file atomically (OutputFile: temporary, then rename).
void writeText(const std::string& path, const std::string& text) {
    OutputFile out(path);
    out.write(text);
    out.commit();
}

}  // namespace

}  // namespace uvr::python

PYBIND11_MODULE(_uvr, m) {
    using namespace uvr;
    using namespace uvr::python;
    m.doc() = "uvr's compiled core (a thin layer over the C++ library); use the uvr package.";
    // The integrators' names, the default first (the library's one list: kMethods).
    m.attr("METHODS") = methodNames();
    // The settings vocabulary (settings_vocabulary.h): name, type, doc, default, choices or range.
    m.attr("SETTINGS") = fromJson(settingsVocabularyJson());
    m.def(
        "check_settings", [](const py::dict& settings) { settingsOf(settings); },
        py::arg("settings"),
        "Raises ArgumentError naming the first setting of the dict that the vocabulary refuses.");
    m.def(
        "tunes_adaptive",
        [](const py::dict& settings) { return tunesAdaptive(settingsOf(settings)); },
        py::arg("settings"),
        "True when the settings tune the sampling methods: method 'auto' then renders adaptive.");

    // Exceptions.
    gExceptions.base = addException(m, "Error", nullptr, "Base of every error uvr raises.");
    auto& k = gExceptions.byKind;
    k[int(ErrorKind::Io)] =
        addException(m, "FileError", PyExc_OSError, "A file could not be opened, read or written.");
    k[int(ErrorKind::Parse)] = addException(m, "ParseError", PyExc_ValueError,
                                            "A file is malformed (names file and place).");
    k[int(ErrorKind::Validation)] = addException(m, "ValidationError", PyExc_ValueError,
                                                 "A mesh is invalid (names the cell or index).");
    k[int(ErrorKind::Argument)] = addException(m, "ArgumentError", PyExc_ValueError,
                                               "An argument is out of range or malformed.");
    k[int(ErrorKind::Unsupported)] = addException(m, "UnsupportedError", PyExc_NotImplementedError,
                                                  "Valid input uvr does not handle.");
    k[int(ErrorKind::Resource)] = addException(m, "ResourceError", PyExc_MemoryError,
                                               "Not enough memory (host or GPU) or over a limit.");
    k[int(ErrorKind::Internal)] = addException(m, "InternalError", PyExc_RuntimeError,
                                               "A broken invariant inside uvr (a bug).");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const SettingError& e) {
            // Python's spelling: the keyword and its value (quality=1.5: expected ...).
            const std::string text = pythonSpelling(e.spelledAs(pythonName(e.setting()), "="));
            PyErr_SetString(gExceptions.byKind[static_cast<int>(e.kind())], text.c_str());
        } catch (const Error& e) {
            PyErr_SetString(gExceptions.byKind[static_cast<int>(e.kind())],
                            pythonSpelling(e.what()).c_str());
        }
    });

    // Meshes.
    py::class_<MeshData>(m, "MeshData", "A mesh in uvr's layout (see uvr.Mesh).")
        .def_static(
            "read",
            [](const std::string& path, std::uint64_t maxMemory) {
                auto out = std::make_unique<MeshData>();
                {
                    py::gil_scoped_release release;
                    ReadOptions o;
                    o.maxMemoryBytes = maxMemory;
                    out->owned = std::make_shared<Mesh>(readMesh(path, o));
                }
                return out;
            },
            py::arg("path"), py::arg("max_memory") = 0)
        .def_static("borrow", &borrowMesh, py::arg("points"), py::arg("types"), py::arg("offsets"),
                    py::arg("connectivity"))
        .def_static("convert", &convertMesh, py::arg("points"), py::arg("types"),
                    py::arg("offsets"), py::arg("connectivity"))
        .def_property_readonly("borrowed", [](const MeshData& d) { return !d.owned; })
        .def_property_readonly("point_count",
                               [](const MeshData& d) { return shapesNow(d).pointCount(); })
        .def_property_readonly("cell_count",
                               [](const MeshData& d) { return shapesNow(d).cellCount(); })
        .def_property_readonly("points",
                               [](py::object self) -> py::object {
                                   const auto& d = self.cast<const MeshData&>();
                                   if (!d.owned) return d.arrays[0];
                                   return viewArray(
                                       reinterpret_cast<const float*>(d.owned->points.data()),
                                       {py::ssize_t(d.owned->pointCount()), 3}, self);
                               })
        .def_property_readonly(
            "types",
            [](py::object self) -> py::object {
                const auto& d = self.cast<const MeshData&>();
                if (!d.owned) return d.arrays[1];
                return viewArray(reinterpret_cast<const std::uint8_t*>(d.owned->cellTypes.data()),
                                 {py::ssize_t(d.owned->cellCount())}, self);
            })
        .def_property_readonly("offsets",
                               [](py::object self) -> py::object {
                                   const auto& d = self.cast<const MeshData&>();
                                   if (!d.owned) return d.arrays[2];
                                   return viewArray(d.owned->cellOffsets.data(),
                                                    {py::ssize_t(d.owned->cellOffsets.size())},
                                                    self);
                               })
        .def_property_readonly("connectivity",
                               [](py::object self) -> py::object {
                                   const auto& d = self.cast<const MeshData&>();
                                   if (!d.owned) return d.arrays[3];
                                   return viewArray(d.owned->cellIndices.data(),
                                                    {py::ssize_t(d.owned->cellIndices.size())},
                                                    self);
                               })
        .def_property_readonly(
            "fields",
            [](py::object self) { return ownedFields(self, self.cast<const MeshData&>()); })
        .def_property_readonly(
            "notes",
            [](const MeshData& d) { return d.owned ? d.owned->notes : std::vector<std::string>{}; })
        .def("bounds", [](const MeshData& d) {
            const std::shared_ptr<const Mesh> cells = cellsNow(d);
            Bounds3f b;
            {
                py::gil_scoped_release release;
                b = cells->bounds();
            }
            return py::make_tuple(arr3(b.lo), arr3(b.hi));
        });
    py::class_<FieldSet>(m, "FieldSet", "A time step's fields (see uvr.Series).")
        .def_property_readonly("fields", [](py::object self) { return fieldSetTuples(self); });
    py::class_<PySeries>(m, "Series", "A mesh file or series opened for its time steps.")
        .def(py::init([](const std::string& path, std::uint64_t maxMemory) {
                 ReadOptions o;
                 o.maxMemoryBytes = maxMemory;
                 auto s = std::make_unique<PySeries>();
                 py::gil_scoped_release release;
                 s->series = openMeshSeries(path, o);
                 return s;
             }),
             py::arg("path"), py::arg("max_memory") = 0)
        .def_property_readonly("path", [](const PySeries& s) { return s.series->path(); })
        .def_property_readonly("times", [](const PySeries& s) { return s.series->times(); })
        .def("source", [](const PySeries& s, std::size_t i) { return s.series->stepSource(i); })
        .def("step_at",
             [](const PySeries& s, double t) { return stepAtTime(s.series->times(), t); })
        .def(
            "read",
            [](PySeries& s, std::size_t i) {
                auto out = std::make_unique<MeshData>();
                {
                    py::gil_scoped_release release;
                    out->owned = std::make_shared<Mesh>(s.series->readStep(i));
                }
                return out;
            },
            py::arg("step"))
        .def(
            "read_fields",
            [](PySeries& s, std::size_t i, const MeshData& geometry) -> py::object {
                const std::shared_ptr<const Mesh> cells = cellsNow(geometry);
                std::optional<std::vector<Field>> fields;
                {
                    py::gil_scoped_release release;
                    fields = s.series->readFieldsIfSameGeometry(i, *cells);
                }
                if (!fields) return py::none();
                auto set = std::make_unique<FieldSet>();
                set->fields = std::move(*fields);
                return py::cast(std::move(set));
            },
            py::arg("step"), py::arg("geometry"));
    m.def("select_field", &selectField, py::arg("mesh"), py::arg("fields"), py::arg("spec"));
    m.def(
        "is_id_field_name", [](const std::string& n) { return isIdFieldName(n); }, py::arg("name"));

    // Transfer functions.
    py::class_<TransferFunction>(m, "TransferFunction",
                                 "Colour map plus opacity over a normalised [0, 1] domain "
                                 "(ParaView's conventions; see uvr.TransferFunction).")
        .def(py::init([](const std::string& preset) { return transferFunctionPreset(preset); }),
             py::arg("preset") = "Cool to Warm")
        .def_static("load", &loadTransferFunction, py::arg("preset_or_path"))
        .def_static(
            "load_paraview",
            [](const std::string& path, const std::string& name) {
                return loadParaViewColorMap(path, name);
            },
            py::arg("path"), py::arg("name") = "")
        .def_static(
            "from_json",
            [](const std::string& text, const std::string& name, const std::string& source) {
                return parseParaViewColorMap(std::vector<char>(text.begin(), text.end()), source,
                                             name);
            },
            py::arg("text"), py::arg("name") = "", py::arg("source") = "<json>")
        .def("to_json", &paraViewColorMapJson, py::arg("lo"), py::arg("hi"))
        .def(
            "set_opacity",
            [](TransferFunction& tf, const std::string& spec) { applyOpacitySpec(tf, spec); },
            py::arg("spec"))
        .def_readwrite("name", &TransferFunction::name)
        .def_readwrite("log_scale", &TransferFunction::logScale)
        .def_readwrite("nan_opacity", &TransferFunction::nanOpacity)
        .def_property(
            "nan_color", [](const TransferFunction& tf) { return arr3(tf.nanColor); },
            [](TransferFunction& tf, const std::array<float, 3>& c) { tf.nanColor = vec3(c); })
        .def_property(
            "color_space", [](const TransferFunction& tf) { return colorSpaceName(tf.colorSpace); },
            [](TransferFunction& tf, const std::string& s) {
                const auto space = colorSpaceFromName(s);
                if (!space)
                    raise(ErrorKind::Argument,
                          "color_space: expected 'RGB', 'Lab' or 'Diverging', got '" + s + "'");
                tf.colorSpace = *space;
            })
        .def_property(
            "colors",
            [](const TransferFunction& tf) {
                std::vector<float> v;
                for (const ColorPoint& p : tf.colors)
                    v.insert(v.end(), {p.x, p.rgb.x, p.rgb.y, p.rgb.z});
                const auto n = static_cast<py::ssize_t>(tf.colors.size());
                return vectorArray<float>(std::move(v), {n, 4});
            },
            [](TransferFunction& tf, const py::handle& obj) {
                auto a = exactArray<float>(obj, "colors");
                checkShape(a, {-1, 4}, "colors (rows x, r, g, b)");
                if (a.shape(0) < 1) raise(ErrorKind::Argument, "colors: at least one point");
                std::vector<ColorPoint> pts;
                for (py::ssize_t i = 0; i < a.shape(0); ++i) {
                    float r[4];  // read once: the checked values are the ones kept
                    std::memcpy(r, a.data(i, 0), sizeof(r));
                    for (int c = 0; c < 4; ++c)
                        if (!(r[c] >= 0.f && r[c] <= 1.f))
                            raise(ErrorKind::Argument, "colors: row " + std::to_string(i) +
                                                           " has a value outside [0, 1]");
                    if (i && r[0] < pts.back().x)
                        raise(ErrorKind::Argument,
                              "colors: x must not decrease (row " + std::to_string(i) + ")");
                    pts.push_back({r[0], {r[1], r[2], r[3]}});
                }
                tf.colors = std::move(pts);
            })
        .def_property(
            "opacities",
            [](const TransferFunction& tf) {
                std::vector<float> v;
                for (const OpacityPoint& p : tf.opacities) v.insert(v.end(), {p.x, p.alpha});
                const auto n = static_cast<py::ssize_t>(tf.opacities.size());
                return vectorArray<float>(std::move(v), {n, 2});
            },
            [](TransferFunction& tf, const py::handle& obj) {
                auto a = exactArray<float>(obj, "opacities");
                checkShape(a, {-1, 2}, "opacities (rows x, alpha)");
                if (a.shape(0) < 1) raise(ErrorKind::Argument, "opacities: at least one point");
                std::vector<OpacityPoint> pts;
                for (py::ssize_t i = 0; i < a.shape(0); ++i) {
                    const float x = *a.data(i, 0), alpha = *a.data(i, 1);
                    if (!(x >= 0.f && x <= 1.f && alpha >= 0.f && alpha <= 1.f))
                        raise(ErrorKind::Argument, "opacities: row " + std::to_string(i) +
                                                       " has a value outside [0, 1]");
                    if (i && x < pts.back().x)
                        raise(ErrorKind::Argument,
                              "opacities: x must not decrease (row " + std::to_string(i) + ")");
                    pts.push_back({x, alpha});
                }
                tf.opacities = std::move(pts);
            })
        .def(
            "bake",
            [](const TransferFunction& tf, int n) {
                if (n < 2 || n > (1 << 20))
                    raise(ErrorKind::Argument, "n: expected 2 to 2^20 entries");
                std::vector<Vec4f> t = tf.bake(n);
                return vectorArray<float>(std::move(t), {n, 4});
            },
            py::arg("n") = 256)
        .def("__copy__", [](const TransferFunction& tf) { return tf; })
        .def("__deepcopy__", [](const TransferFunction& tf, py::dict) { return tf; });
    m.def("preset_names", &transferFunctionPresetNames);

    // Cameras.
    py::class_<Camera>(m, "Camera",
                       "A camera as ParaView describes one (see uvr.Camera): position, focal "
                       "point, view up, view angle or parallel scale.")
        .def(py::init([](const std::array<float, 3>& position,
                         const std::array<float, 3>& focalPoint, const std::array<float, 3>& up,
                         float viewAngle, bool parallel, float parallelScale) {
                 Camera c;
                 c.position = vec3(position), c.focalPoint = vec3(focalPoint);
                 c.viewUp = vec3(up);
                 c.viewAngle = viewAngle;
                 c.parallelProjection = parallel;
                 c.parallelScale = parallelScale;
                 return c;
             }),
             py::arg("position") = std::array<float, 3>{0.f, 0.f, 1.f},
             py::arg("focal_point") = std::array<float, 3>{0.f, 0.f, 0.f},
             py::arg("view_up") = std::array<float, 3>{0.f, 1.f, 0.f}, py::arg("view_angle") = 30.f,
             py::arg("parallel_projection") = false, py::arg("parallel_scale") = 1.f)
        .def_property(
            "position", [](const Camera& c) { return arr3(c.position); },
            [](Camera& c, const std::array<float, 3>& v) { c.position = vec3(v); })
        .def_property(
            "focal_point", [](const Camera& c) { return arr3(c.focalPoint); },
            [](Camera& c, const std::array<float, 3>& v) { c.focalPoint = vec3(v); })
        .def_property(
            "view_up", [](const Camera& c) { return arr3(c.viewUp); },
            [](Camera& c, const std::array<float, 3>& v) { c.viewUp = vec3(v); })
        .def_readwrite("view_angle", &Camera::viewAngle)
        .def_readwrite("parallel_projection", &Camera::parallelProjection)
        .def_readwrite("parallel_scale", &Camera::parallelScale)
        .def_static(
            "reset",
            [](const std::array<std::array<float, 3>, 2>& bounds, float aspect) {
                return resetCamera(boundsOf(bounds), aspect);
            },
            py::arg("bounds"), py::arg("aspect") = 1.f)
        .def(
            "orbit",
            [](const Camera& c, float azimuth, float elevation) {
                validateCamera(c);
                return orbitCamera(c, azimuth, elevation);
            },
            py::arg("azimuth") = 0.f, py::arg("elevation") = 0.f)
        .def("validate", [](const Camera& c) { validateCamera(c); })
        .def_static(
            "load", [](const std::string& path) { return loadPvcc(path); }, py::arg("path"))
        .def_static(
            "from_pvcc",
            [](const std::string& text, const std::string& source) {
                return parsePvcc(std::vector<char>(text.begin(), text.end()), source);
            },
            py::arg("text"), py::arg("source") = "<pvcc>")
        .def("to_pvcc", &pvccText)
        .def("__copy__", [](const Camera& c) { return c; })
        .def("__deepcopy__", [](const Camera& c, py::dict) { return c; });

    // The renderer.
    py::class_<PyRenderer>(m, "Renderer", "The library's renderer (see uvr.Renderer).")
        .def(py::init([](const MeshData& mesh, const std::string& name,
                         const std::string& association, const py::handle& values,
                         const std::string& device, const std::string& buildDevice,
                         std::uint32_t leafCells, bool meshBvh, bool seedGrids, bool splitCells,
                         bool partitions, bool forAuto) {
                 ScalarField field = scalarField(name, association, values);
                 RendererOptions o;
                 o.device = parseDevice(device, "device");
                 o.buildDevice = parseDevice(buildDevice, "build_device");
                 o.leafCells = leafCells;
                 o.meshBvh = meshBvh;
                 o.partitions = partitions;
                 o.forAuto = forAuto;
                 o.seedGrids = seedGrids;
                 o.splitCells = splitCells;
                 // The mesh's points and cells as they are now (a borrowed mesh's copied and
                 // checked again), freed as soon as they are split.
                 std::shared_ptr<const Mesh> cells = cellsNow(mesh);
                 o.afterSplit = [&cells] { cells.reset(); };
                 const std::uint64_t expected = field.association == Association::Point
                                                    ? cells->pointCount()
                                                    : cells->cellCount();
                 if (field.values.size() != expected)
                     raise(ErrorKind::Argument, "values: " + std::to_string(field.values.size()) +
                                                    " " + associationName(field.association) +
                                                    " values, expected " +
                                                    std::to_string(expected));
                 auto r = std::make_unique<PyRenderer>();
                 py::gil_scoped_release release;
                 r->renderer = std::make_unique<Renderer>(MeshView(*cells), field, o);
                 return r;
             }),
             py::arg("mesh"), py::arg("name"), py::arg("association"), py::arg("values"),
             py::arg("device") = "auto", py::arg("build_device") = "auto",
             py::arg("leaf_cells") = 0, py::arg("mesh_bvh") = true, py::arg("seed_grids") = true,
             py::arg("split_cells") = false, py::arg("partitions") = true,
             py::arg("for_auto") = false)
        .def(
            "set_field_values",
            [](PyRenderer& self, const std::string& name, const std::string& association,
               const py::handle& values) {
                ScalarField f = scalarField(name, association, values);
                py::gil_scoped_release release;
                self.renderer->setFieldValues(f);
            },
            py::arg("name"), py::arg("association"), py::arg("values"))
        .def("render", &renderFrame, py::arg("tf"), py::arg("range"), py::arg("camera"),
             py::arg("width"), py::arg("height"), py::arg("settings") = py::dict())
        .def_property_readonly("device",
                               [](const PyRenderer& r) { return r.renderer->deviceName(); })
        .def_property_readonly("device_description",
                               [](const PyRenderer& r) { return r.renderer->deviceDescription(); })
        .def_property_readonly(
            "bounds", [](const PyRenderer& r) { return fileBounds(r.renderer->prepared()); })
        .def_property_readonly("info", [](const PyRenderer& r) {
            const PreparedMesh& p = r.renderer->prepared();
            py::dict d;
            d["tetrahedra"] = p.tets.tets.size();
            d["pyramids"] = p.tets.pyramidCount;
            d["wedges"] = p.tets.wedgeCount;
            d["hexahedra"] = p.tets.hexCount;
            d["source_cells"] = p.sourceCells;
            d["points"] = p.tets.points.size();
            d["field"] = p.tets.fieldName;
            d["field_association"] = associationName(p.tets.association);
            d["value_range"] = py::make_tuple(p.tets.valueMin, p.tets.valueMax);
            d["partitions"] = p.kd ? p.kd->partitions.size() : 0;
            d["partition_build_seconds"] = p.kd ? p.kd->buildSeconds : 0.0;
            d["mesh_bvh_nodes"] = p.bvh.nodes.size();
            d["prepare_seconds"] = r.renderer->prepareSeconds();
            d["split_seconds"] = p.splitSeconds;
            d["bvh_seconds"] = p.bvhSeconds;
            d["value_updates"] = p.valueUpdates;
            d["value_update_seconds"] = p.valueUpdateSeconds;
            if (const std::optional<GpuResidency> gpu = r.renderer->gpuResidency()) {
                d["gpu_geometry_bytes"] = gpu->geometryBytes;
                d["gpu_value_upload_seconds"] = gpu->valueUploadSeconds;
            }
            return d;
        });

    // Images.
    m.def(
        "png_bytes",
        [](const py::handle& pixels, std::optional<std::array<float, 3>> background) {
            const Image image = imageOf(pixels);
            std::optional<Vec3f> bg;
            if (background) bg = vec3(*background);
            std::vector<std::uint8_t> bytes;
            {
                py::gil_scoped_release release;
                bytes = encodePng(image, bg);
            }
            return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
        },
        py::arg("pixels"), py::arg("background") = py::none());
    m.def(
        "to_uint8",
        [](const py::handle& pixels, std::optional<std::array<float, 3>> background) {
            const Image image = imageOf(pixels);
            std::optional<Vec3f> bg;
            if (background) bg = vec3(*background);
            std::vector<std::uint8_t> bytes = toPngBytes(image, bg);
            return vectorArray<std::uint8_t>(std::move(bytes),
                                             {image.height, image.width, bg ? 3 : 4});
        },
        py::arg("pixels"), py::arg("background") = py::none());
    m.def(
        "write_png",
        [](const std::string& path, const py::handle& pixels,
           std::optional<std::array<float, 3>> background) {
            const Image image = imageOf(pixels);
            std::optional<Vec3f> bg;
            if (background) bg = vec3(*background);
            writePng(path, image, bg);
        },
        py::arg("path"), py::arg("pixels"), py::arg("background") = py::none());
    m.def(
        "read_png",
        [](const std::string& path) {
            Image image = readPng(path);
            return vectorArray<float>(std::move(image.pixels), {image.height, image.width, 4});
        },
        py::arg("path"));
    m.def(
        "compare_images",
        [](const py::handle& a, const py::handle& b, std::array<float, 3> background) {
            const ImageComparison c = compareImages(toRgb8(imageOf(a), vec3(background)),
                                                    toRgb8(imageOf(b), vec3(background)));
            // The keys of `uvr compare --json`: SSIM, PSNR (None when identical) and the
            // per-pixel measures under differenceFields' names.
            py::dict d;
            d["ssim"] = c.ssim;
            py::list channels;
            for (double v : c.ssimChannel) channels.append(v);
            d["ssim_channels"] = channels;
            d["psnr"] =
                std::isinf(c.psnr) ? py::object(py::none()) : py::object(py::float_(c.psnr));
            for (const ComparisonField& f : differenceFields(c))
                d[f.name] = f.integer ? py::object(py::int_(static_cast<long long>(f.value)))
                                      : py::object(py::float_(f.value));
            return d;
        },
        py::arg("a"), py::arg("b"), py::arg("background") = std::array<float, 3>{0.f, 0.f, 0.f});
    m.def("write_text", &writeText, py::arg("path"), py::arg("text"));
    m.def("cuda_available", &cudaDeviceAvailable);
    m.def("cuda_description", &cudaDeviceDescription);
}
