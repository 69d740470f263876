// SPDX-License-Identifier: MIT
// The helpers the binding's parts share (support.h).
#include "support.h"

namespace uvr::python {

ExceptionClasses gExceptions;

PyObject* addException(py::module_& m, const char* name, PyObject* builtin, const char* doc) {
    py::tuple bases = builtin ? py::make_tuple(py::handle(gExceptions.base), py::handle(builtin))
                              : py::make_tuple(py::handle(PyExc_Exception));
    const std::string qualified = std::string("uvr._uvr.") + name;
    PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
    if (!cls) throw py::error_already_set();
    m.add_object(name, py::handle(cls));  // the module holds a reference; cls is never freed
    return cls;
}

[[noreturn]] void raise(ErrorKind kind, const std::string& message) {
    throw Error(kind, message);
}

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

MeshView shapesNow(const MeshData& d) {
    if (d.owned) return *d.owned;
    return changedSinceMesh([&] { return borrowedView(d.arrays); });
}

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

Association parseAssociation(const std::string& s, const std::string& what) {
    if (s == "point") return Association::Point;
    if (s == "cell") return Association::Cell;
    raise(ErrorKind::Argument, what + ": expected 'point' or 'cell', got '" + s + "'");
}

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

std::string pythonName(const std::string& setting) {
    if (setting == "log") return "log_scale";
    if (setting == "seed_grid") return "seed_grids";
    return setting;
}

std::string pythonSpelling(const std::string& message) {
    return respellMentions(message, [](std::string_view setting) {
        return "`" + pythonName(std::string(setting)) + "`";
    });
}

py::object fromJson(const nlohmann::json& j) {
    return py::module_::import("json").attr("loads")(
        j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

namespace {

/// Six numbers from (a, b, c, d, e, f) or ((a, b, c), (d, e, f)); SettingError naming the
/// setting and the value otherwise.
std::array<float, 6> sixNumbers(const char* setting, const py::handle& v, const char* expected) {
    const auto refuse = [&]() -> std::array<float, 6> {
        throw SettingError(setting, py::str(py::repr(v)).cast<std::string>(), expected);
    };
    std::vector<float> out;
    try {
        for (const py::handle& item : py::iter(v)) {
            if (py::isinstance<py::str>(item)) return refuse();
            if (py::hasattr(item, "__float__")) {
                out.push_back(item.cast<float>());
                continue;
            }
            for (const py::handle& x : py::iter(item)) out.push_back(x.cast<float>());
        }
    } catch (const py::error_already_set&) {
        return refuse();
    } catch (const py::cast_error&) {
        return refuse();
    }
    if (out.size() != 6) return refuse();
    std::array<float, 6> a{};
    std::copy(out.begin(), out.end(), a.begin());
    return a;
}

}  // namespace

RenderSettings settingsOf(const py::dict& settings,
                          std::pair<py::ssize_t, py::ssize_t>* depthShape) {
    RenderSettings s;
    std::vector<std::string> given;
    for (const auto& [k, v] : settings) {
        const std::string key = py::str(k).cast<std::string>();
        given.push_back(key);
        // The clip region (not scalar settings): planes as (origin, normal), a box as (lo, hi).
        if (key == "clip_planes") {
            if (py::isinstance<py::str>(v) || !py::hasattr(v, "__iter__"))
                throw SettingError("clip_planes", py::str(py::repr(v)).cast<std::string>(),
                                   "expected a list of planes, each (origin, normal)");
            for (const py::handle& plane : py::iter(v)) {
                const auto a = sixNumbers("clip_planes", plane,
                                          "expected (origin, normal): six numbers, "
                                          "((ox, oy, oz), (nx, ny, nz))");
                s.clipPlanes.push_back({Vec3f(a[0], a[1], a[2]), Vec3f(a[3], a[4], a[5])});
            }
            continue;
        }
        // Isosurfaces: each a value, a (value, opacity[, colour]) tuple (the colour "#RRGGBB"
        // or (r, g, b) in [0, 1]) or the CLI's text "VALUE[,OPACITY[,#RRGGBB]]".
        if (key == "iso") {
            const std::string expected =
                "expected a list of isosurfaces, each a value, (value, opacity) or (value, "
                "opacity, colour) with colour '#RRGGBB' or (r, g, b), or the text "
                "'VALUE[,OPACITY[,#RRGGBB]]'";
            auto refuse = [&](const py::handle& x) {
                throw SettingError("iso", py::str(py::repr(x)).cast<std::string>(), expected);
            };
            if (py::isinstance<py::str>(v) || !py::hasattr(v, "__iter__")) refuse(v);
            for (const py::handle& item : py::iter(v)) {
                if (py::isinstance<py::str>(item)) {
                    s.isoSurfaces.push_back(parseIsoSurface(item.cast<std::string>()));
                    continue;
                }
                IsoSurface iso;
                try {
                    if (!py::hasattr(item, "__iter__")) {
                        if (py::isinstance<py::bool_>(item)) refuse(item);
                        iso.value = item.cast<float>();
                    } else {
                        const py::tuple t = py::tuple(py::reinterpret_borrow<py::object>(item));
                        if (t.size() < 1 || t.size() > 3) refuse(item);
                        iso.value = t[0].cast<float>();
                        if (t.size() > 1) iso.opacity = t[1].cast<float>();
                        if (t.size() > 2) {
                            iso.colorMapped = false;
                            if (py::isinstance<py::str>(t[2])) {
                                iso.color =
                                    parseIsoSurface("0,1," + t[2].cast<std::string>()).color;
                            } else {
                                const py::tuple c = py::tuple(t[2]);
                                if (c.size() != 3) refuse(item);
                                iso.color = Vec3f(c[0].cast<float>(), c[1].cast<float>(),
                                                  c[2].cast<float>());
                            }
                        }
                    }
                } catch (const py::error_already_set&) {
                    refuse(item);
                } catch (const py::cast_error&) {
                    refuse(item);
                } catch (const SettingError&) {
                    refuse(item);
                }
                s.isoSurfaces.push_back(iso);
            }
            continue;
        }
        // Gradient opacity: (magnitude, scale) pairs or the CLI's text "MAGNITUDE:SCALE,...";
        // None is off.
        if (key == "gradient_opacity") {
            const std::string text = py::str(py::repr(v)).cast<std::string>();
            const std::string expected =
                "expected up to " + std::to_string(kMaxGradientOpacityPoints) +
                " (magnitude, scale) pairs, magnitudes finite, >= 0 and non-decreasing, scales "
                "in [0, 1], or the text 'MAGNITUDE:SCALE,...'";
            if (v.is_none()) continue;
            if (py::isinstance<py::str>(v)) {
                s.gradientOpacity = parseGradientOpacity(v.cast<std::string>());
                continue;
            }
            if (!py::hasattr(v, "__iter__")) throw SettingError(key, text, expected);
            GradientOpacity g;
            try {
                for (const py::handle& item : py::iter(v)) {
                    if (py::isinstance<py::str>(item) || !py::hasattr(item, "__iter__"))
                        throw SettingError(key, text, expected);
                    const py::tuple t = py::tuple(py::reinterpret_borrow<py::object>(item));
                    if (t.size() != 2 || g.count == kMaxGradientOpacityPoints ||
                        py::isinstance<py::bool_>(t[0]) || py::isinstance<py::bool_>(t[1]))
                        throw SettingError(key, text, expected);
                    g.magnitude[g.count] = t[0].cast<float>();
                    g.scale[g.count] = t[1].cast<float>();
                    ++g.count;
                }
                if (g.count == 0) throw SettingError(key, text, expected);
                checkGradientOpacity(g);
            } catch (const py::error_already_set&) {
                throw SettingError(key, text, expected);
            } catch (const py::cast_error&) {
                throw SettingError(key, text, expected);
            } catch (const SettingError&) {
                throw SettingError(key, text, expected);
            }
            s.gradientOpacity = g;
            continue;
        }
        // Depth out: the opacity whose depth the frame reports (Image.depth); depth in: a 2-D
        // array of view depths of geometry rendered elsewhere (inf or NaN: none).
        if (key == "depth") {
            const std::string text = py::str(py::repr(v)).cast<std::string>();
            if (py::isinstance<py::bool_>(v) ||
                !(py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)))
                throw SettingError(
                    "depth", text,
                    "expected the opacity whose depth is written, a number in (0, 1]");
            s.depthAlpha = v.cast<float>();
            if (!(s.depthAlpha > 0.f && s.depthAlpha <= 1.f))
                throw SettingError(
                    "depth", text,
                    "expected the opacity whose depth is written, a number in (0, 1]");
            continue;
        }
        if (key == "depth_in") {
            py::array_t<float, py::array::c_style | py::array::forcecast> a;
            try {
                a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(v);
            } catch (const py::error_already_set&) {
            }
            if (!a || a.ndim() != 2)
                throw SettingError("depth_in",
                                   "a " + std::string(py::str(py::type::of(v).attr("__name__"))),
                                   "expected a 2-D array of view depths, shape (height, width)");
            s.depthIn.assign(a.data(), a.data() + a.size());
            if (depthShape) *depthShape = {a.shape(0), a.shape(1)};
            continue;
        }
        if (key == "clip_box") {
            const auto a = sixNumbers("clip_box", v,
                                      "expected (lo, hi): six numbers, ((x0, y0, z0), (x1, y1, "
                                      "z1))");
            s.clipBox = Bounds3f{Vec3f(a[0], a[1], a[2]), Vec3f(a[3], a[4], a[5])};
            continue;
        }
        applySetting(s, key, settingValue(v));
    }
    refuseUnreadSettings(s, given);  // e.g. ambient without shade
    checkClip(s);
    checkIso(s);
    return s;
}

py::tuple renderFrame(PyRenderer& self, const TransferFunction& tf,
                      std::optional<std::pair<float, float>> range, std::optional<Camera> camera,
                      int width, int height, const py::dict& settings, bool roomForLegend) {
    std::pair<py::ssize_t, py::ssize_t> depthShape{0, 0};
    RenderSettings s = settingsOf(settings, &depthShape);
    if (!s.depthIn.empty() && (depthShape.first != height || depthShape.second != width))
        throw SettingError("depth_in",
                           "shape (" + std::to_string(depthShape.first) + ", " +
                               std::to_string(depthShape.second) + ")",
                           "expected the frame's (height, width): (" + std::to_string(height) +
                               ", " + std::to_string(width) + ")");
    s.width = width, s.height = height;
    s.tf = tf;
    s.range = range;
    s.camera = camera;
    RenderResult r;
    {
        py::gil_scoped_release release;
        if (roomForLegend) {  // the reset camera keeps the volume off the legend
            const PreparedMesh& p = self.renderer->prepared();
            s.camera = cameraBesideLegend(p, s, fileBox(p), Font(findFontFile()),
                                          legendTitle(p.tets.fieldName, p.tets.association));
        }
        r = self.renderer->render(s);
    }
    // The library's frame report (the CLI's --stats, the viewer's frame messages), as a dict.
    py::object stats = fromJson(frameReport(*self.renderer, s, r));
    const auto h = static_cast<py::ssize_t>(height), w = static_cast<py::ssize_t>(width);
    py::array pixels = vectorArray<float>(std::move(r.image.pixels), {h, w, 4});
    py::array counts = vectorArray<std::uint32_t>(std::move(r.sampleCounts), {h, w});
    py::object depth = py::none();
    if (!r.depth.empty()) depth = vectorArray<float>(std::move(r.depth), {h, w});
    return py::make_tuple(pixels, counts, stats, depth);
}

namespace {

/// The prepared mesh's bounds' corners in the file's coordinates.
void fileCorners(const PreparedMesh& p, double lo[3], double hi[3]) {
    p.tets.frame.toFile(p.wholeBounds().lo, lo);
    p.tets.frame.toFile(p.wholeBounds().hi, hi);
}

}  // namespace

Bounds3f fileBox(const PreparedMesh& p) {
    double lo[3], hi[3];
    fileCorners(p, lo, hi);
    return {Vec3f(float(lo[0]), float(lo[1]), float(lo[2])),
            Vec3f(float(hi[0]), float(hi[1]), float(hi[2]))};
}

py::tuple fileBounds(const PreparedMesh& p) {
    double lo[3], hi[3];
    fileCorners(p, lo, hi);
    return py::make_tuple(py::make_tuple(lo[0], lo[1], lo[2]), py::make_tuple(hi[0], hi[1], hi[2]));
}

Bounds3f boundsOf(const std::array<std::array<float, 3>, 2>& b) {
    return {vec3(b[0]), vec3(b[1])};
}

void writeText(const std::string& path, const std::string& text) {
    OutputFile out(path);
    out.write(text);
    out.commit();
}

}  // namespace uvr::python
