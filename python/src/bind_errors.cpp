// SPDX-License-Identifier: MIT
// The exceptions: one Python class per ErrorKind, and the library's messages in Python's spelling.
#include "support.h"

namespace uvr::python {

void bindErrors(py::module_& m) {
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
}

}  // namespace uvr::python
