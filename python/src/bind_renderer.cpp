// SPDX-License-Identifier: MIT
// The renderer.
#include "support.h"
#include "uvr/core/text.h"

namespace uvr::python {

void bindRenderer(py::module_& m) {
    // The renderer.
    py::class_<PyRenderer>(m, "Renderer", "The library's renderer (see uvr.Renderer).")
        .def(py::init([](const MeshData& mesh, const std::string& name,
                         const std::string& association, const py::handle& values,
                         const std::string& device, const std::string& buildDevice,
                         std::uint32_t leafCells, bool meshBvh, bool seedGrids, bool splitCells,
                         bool partitions, bool forAuto, int ranks, float largestSampleDistance) {
                 ScalarField field = scalarField(name, association, values);
                 if (!(largestSampleDistance >= 0.f && largestSampleDistance < INFINITY))
                     raise(ErrorKind::Argument,
                           "largest_sample_distance " + formatG(largestSampleDistance, 6) +
                               ": expected a finite sample distance (0: the default's)");
                 RendererOptions o;
                 o.largestSampleDistance = largestSampleDistance;
                 o.device = parseDevice(device, "device");
                 o.buildDevice = parseDevice(buildDevice, "build_device");
                 o.leafCells = leafCells;
                 o.meshBvh = meshBvh;
                 o.partitions = partitions;
                 o.forAuto = forAuto;
                 o.seedGrids = seedGrids;
                 o.splitCells = splitCells;
                 if (ranks > 1) {
                     // Data-parallel over MPI's world (mpi4py's COMM_WORLD, checked in Python).
                     Communicator& world = mpiWorld();
                     if (world.size() != ranks)
                         raise(ErrorKind::Argument, "comm: " + std::to_string(ranks) +
                                                        " ranks, but MPI's world has " +
                                                        std::to_string(world.size()));
                     o.communicator = &world;
                 }
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
             py::arg("for_auto") = false, py::arg("ranks") = 1,
             py::arg("largest_sample_distance") = 0.f)
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
             py::arg("width"), py::arg("height"), py::arg("settings") = py::dict(),
             py::arg("room_for_legend") = false)
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
            d["value_range"] = py::make_tuple(p.wholeValueMin(), p.wholeValueMax());
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
}

}  // namespace uvr::python
