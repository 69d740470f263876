// SPDX-License-Identifier: MIT
// Transfer functions and the presets.
#include "support.h"

namespace uvr::python {

void bindTransferFunctions(py::module_& m) {
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
}

}  // namespace uvr::python
