// SPDX-License-Identifier: MIT
// uvr._uvr: the compiled half of the Python module, a thin pybind11 layer over the library's
// facade (uvr/uvr.h). It takes arrays only in the exact dtype and layout the library uses and
// refuses anything else naming the argument; conversions, defaults and the friendly API live in
// the pure-Python package beside it (python/uvr). docs/PYTHON.md describes both.
#include "support.h"
#include "uvr/core/version.h"

PYBIND11_MODULE(_uvr, m) {
    using namespace uvr::python;
    m.doc() = "uvr's compiled core (a thin layer over the C++ library); use the uvr package.";
    m.attr("__version__") = uvr::kVersion;
    bindSettings(m);
    bindErrors(m);
    bindMeshes(m);
    bindTransferFunctions(m);
    bindCameras(m);
    bindRenderer(m);
    bindImages(m);
}
