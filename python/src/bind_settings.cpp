// SPDX-License-Identifier: MIT
// The settings vocabulary and the methods, as the library defines them once.
#include "support.h"

namespace uvr::python {

void bindSettings(py::module_& m) {
    // The integrators' names, the default first (the library's one list: kMethods).
    m.attr("METHODS") = methodNames();
    // The settings vocabulary (settings_vocabulary.h): name, type, doc, default, choices or range.
    m.attr("SETTINGS") = fromJson(settingsVocabularyJson());
    // The image size a frame has unless told (RenderSettings', the CLI's --size default).
    m.attr("DEFAULT_SIZE") = py::make_tuple(RenderSettings{}.width, RenderSettings{}.height);
    m.def(
        "check_settings", [](const py::dict& settings) { settingsOf(settings); },
        py::arg("settings"),
        "Raises ArgumentError naming the first setting of the dict that the vocabulary refuses.");
    m.def(
        "tunes_adaptive",
        [](const py::dict& settings) { return tunesAdaptive(settingsOf(settings)); },
        py::arg("settings"),
        "True when the settings tune the sampling methods: method 'auto' then renders adaptive.");
}

}  // namespace uvr::python
