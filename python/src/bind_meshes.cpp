// SPDX-License-Identifier: MIT
// Meshes, time steps and field selection.
#include "support.h"

namespace uvr::python {

void bindMeshes(py::module_& m) {
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
}

}  // namespace uvr::python
