// SPDX-License-Identifier: MIT
// Cameras.
#include "support.h"

namespace uvr::python {

void bindCameras(py::module_& m) {
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
}

}  // namespace uvr::python
