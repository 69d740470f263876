// SPDX-License-Identifier: MIT
// Images, comparison, legends and the device queries.
#include "support.h"

namespace uvr::python {

void bindImages(py::module_& m) {
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
        "draw_legend",
        [](const py::handle& pixels, const TransferFunction& tf, double lo, double hi,
           const std::string& field, const std::string& association, bool logScale,
           std::optional<std::array<float, 3>> background) {
            Image image = imageOf(pixels);
            const std::string title =
                legendTitle(field, parseAssociation(association, "association"));
            LegendStyle style;
            if (background) style.background = vec3(*background);
            {
                py::gil_scoped_release release;
                const Font font(findFontFile());
                drawLegend(image, font, tf, lo, hi, title, logScale, style);
            }
            return vectorArray<float>(std::move(image.pixels), {image.height, image.width, 4});
        },
        py::arg("pixels"), py::arg("tf"), py::arg("lo"), py::arg("hi"), py::arg("field"),
        py::arg("association"), py::arg("log_scale"), py::arg("background") = py::none(),
        "The image with `uvr render --legend`'s colour legend drawn on it (a new array).");
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

}  // namespace uvr::python
