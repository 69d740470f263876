// SPDX-License-Identifier: MIT
#include "uvr/server/view_state.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/text.h"
#include "uvr/render/settings_vocabulary.h"

namespace uvr::server {

namespace {

using Json = nlohmann::json;

std::string fmtG(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

/// Containers nested deeper than this in an error's description show as [...] or {...}.
constexpr int kDescribeDepth = 4;

/// Appends value as compact JSON to out, stopping soon after out passes maxBytes: strings and
/// keys cut to about 40 bytes, containers deeper than kDescribeDepth elided. Bounded work and
/// recursion whatever the value's size and depth.
void appendShort(const Json& v, std::string& out, std::size_t maxBytes, int depth) {
    if (v.is_array() || v.is_object()) {
        const bool array = v.is_array();
        if (depth >= kDescribeDepth && !v.empty()) {
            out += array ? "[...]" : "{...}";
            return;
        }
        out += array ? '[' : '{';
        for (auto it = v.begin(); it != v.end(); ++it) {
            if (out.size() > maxBytes) return;
            if (it != v.begin()) out += ',';
            if (!array) out += "\"" + printableShort(it.key(), 40) + "\":";
            appendShort(*it, out, maxBytes, depth + 1);
        }
        out += array ? ']' : '}';
    } else if (v.is_string()) {
        out += "\"" + printableShort(v.get_ref<const std::string&>(), 40) + "\"";
    } else {
        out += v.dump();  // a number, boolean or null: short
    }
}

/// A one-line description of a value of a message for an error, at most maxBytes long.
std::string describe(const Json& v, std::size_t maxBytes = 80) {
    std::string out;
    appendShort(v, out, maxBytes, 0);
    return printableShort(out, maxBytes);
}

[[noreturn]] void bad(const std::string& key, const std::string& expected, const Json& got) {
    throwError(ErrorKind::Argument, "",
               "\"" + key + "\": expected " + expected + ", got " + describe(got));
}

double number(const std::string& key, const Json& v) {
    if (!v.is_number() || !std::isfinite(v.get<double>())) bad(key, "a finite number", v);
    return v.get<double>();
}

float floatIn(const std::string& key, const Json& v, double lo, double hi) {
    const double x = number(key, v);
    if (x < lo || x > hi) bad(key, "a number in [" + fmtG(lo) + ", " + fmtG(hi) + "]", v);
    return static_cast<float>(x);
}

float finiteFloat(const std::string& key, const Json& v) {
    const double x = number(key, v);
    if (std::fabs(x) > 3.0e38) bad(key, "a number within float range", v);
    return static_cast<float>(x);
}

Vec3f vec3(const std::string& key, const Json& v) {
    if (!v.is_array() || v.size() != 3) bad(key, "3 numbers [x, y, z]", v);
    return {finiteFloat(key + "[0]", v[0]), finiteFloat(key + "[1]", v[1]),
            finiteFloat(key + "[2]", v[2])};
}

bool boolean(const std::string& key, const Json& v) {
    if (!v.is_boolean()) bad(key, "true or false", v);
    return v.get<bool>();
}

const Json& object(const std::string& key, const Json& v) {
    if (!v.is_object()) bad(key, "an object", v);
    return v;
}

/// Rows [x, c...] of `width` numbers, x increasing in [0, 1], the rest in [0, 1].
std::vector<std::vector<float>> rows(const std::string& key, const Json& v, std::size_t width) {
    const std::string shape =
        width == 4 ? "rows [x, r, g, b] of numbers in [0, 1]" : "rows [x, alpha] in [0, 1]";
    if (!v.is_array() || v.empty()) bad(key, "a non-empty array of " + shape, v);
    if (v.size() > kMaxTfPoints) bad(key, "at most " + std::to_string(kMaxTfPoints) + " rows", v);
    std::vector<std::vector<float>> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string where = key + "[" + std::to_string(i) + "]";
        if (!v[i].is_array() || v[i].size() != width) bad(where, shape, v[i]);
        std::vector<float> row;
        for (std::size_t k = 0; k < width; ++k)
            row.push_back(floatIn(where + "[" + std::to_string(k) + "]", v[i][k], 0.0, 1.0));
        if (!out.empty() && row[0] < out.back()[0])
            bad(where, "x not below the previous row's", v[i]);
        out.push_back(std::move(row));
    }
    return out;
}

/// Clip planes [[ox, oy, oz, nx, ny, nz], ...], checked as the library checks them.
std::vector<ClipPlane> clipPlanes(const std::string& key, const Json& v) {
    const std::string shape = "at most " + std::to_string(kMaxClipPlanes) +
                              " planes [ox, oy, oz, nx, ny, nz] (a point and the kept side's "
                              "normal)";
    if (!v.is_array() || v.size() > std::size_t(kMaxClipPlanes)) bad(key, shape, v);
    RenderSettings s;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string where = key + "[" + std::to_string(i) + "]";
        if (!v[i].is_array() || v[i].size() != 6) bad(where, "[ox, oy, oz, nx, ny, nz]", v[i]);
        float x[6];
        for (int c = 0; c < 6; ++c)
            x[c] = finiteFloat(where + "[" + std::to_string(c) + "]", v[i][c]);
        s.clipPlanes.push_back({Vec3f(x[0], x[1], x[2]), Vec3f(x[3], x[4], x[5])});
    }
    try {
        checkClip(s);
    } catch (const SettingError& e) {
        throwError(ErrorKind::Argument, "", e.spelledAs("\"" + key + "\":", " "));
    }
    return s.clipPlanes;
}

Json clipPlanesJson(const std::vector<ClipPlane>& planes) {
    Json out = Json::array();
    for (const ClipPlane& p : planes)
        out.push_back({p.origin.x, p.origin.y, p.origin.z, p.normal.x, p.normal.y, p.normal.z});
    return out;
}

/// Isosurfaces ["VALUE[,OPACITY[,#RRGGBB]]" or a bare number, ...], checked as the library
/// checks them.
std::vector<IsoSurface> isoSurfaces(const std::string& key, const Json& v) {
    const std::string shape = "at most " + std::to_string(kMaxIsoSurfaces) +
                              " isosurfaces, each \"VALUE[,OPACITY[,#RRGGBB]]\" or a number";
    if (!v.is_array() || v.size() > std::size_t(kMaxIsoSurfaces)) bad(key, shape, v);
    RenderSettings s;
    for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string where = key + "[" + std::to_string(i) + "]";
        try {
            if (v[i].is_number())
                s.isoSurfaces.push_back({finiteFloat(where, v[i])});
            else if (v[i].is_string() && v[i].get_ref<const std::string&>().size() <= 64)
                s.isoSurfaces.push_back(parseIsoSurface(v[i].get<std::string>()));
            else
                bad(where, "\"VALUE[,OPACITY[,#RRGGBB]]\" or a number", v[i]);
            checkIso(s);
        } catch (const SettingError& e) {
            throwError(ErrorKind::Argument, "", e.spelledAs("\"" + where + "\":", " "));
        }
    }
    return s.isoSurfaces;
}

Json isoSurfacesJson(const std::vector<IsoSurface>& surfaces) {
    Json out = Json::array();
    for (const IsoSurface& s : surfaces) out.push_back(isoText(s));
    return out;
}

void applyCamera(Camera& cam, const Json& v) {
    for (const auto& [k, x] : object("camera", v).items()) {
        const std::string key = "camera." + k;
        if (k == "position")
            cam.position = vec3(key, x);
        else if (k == "focal_point")
            cam.focalPoint = vec3(key, x);
        else if (k == "view_up")
            cam.viewUp = vec3(key, x);
        else if (k == "view_angle")
            cam.viewAngle = floatIn(key, x, kMinViewAngle, kMaxViewAngle);
        else if (k == "parallel")
            cam.parallelProjection = boolean(key, x);
        else if (k == "parallel_scale") {
            cam.parallelScale = finiteFloat(key, x);
            if (!(cam.parallelScale > 0.f)) bad(key, "a positive number", x);
        } else
            bad("camera",
                "keys position, focal_point, view_up, view_angle, parallel, "
                "parallel_scale (not \"" +
                    printableShort(k, 40) + "\")",
                v);
    }
    validateCamera(cam);
}

void applyTf(TransferFunction& tf, const Json& v) {
    for (const auto& [k, x] : object("tf", v).items()) {
        const std::string key = "tf." + k;
        if (k == "colors") {
            tf.colors.clear();
            for (const auto& r : rows(key, x, 4)) tf.colors.push_back({r[0], {r[1], r[2], r[3]}});
        } else if (k == "opacity") {
            tf.opacities.clear();
            for (const auto& r : rows(key, x, 2)) tf.opacities.push_back({r[0], r[1]});
        } else if (k == "log") {
            tf.logScale = boolean(key, x);
        } else if (k == "nan_color") {
            const Vec3f c = vec3(key, x);
            if (!(c.x >= 0.f && c.y >= 0.f && c.z >= 0.f && c.x <= 1.f && c.y <= 1.f && c.z <= 1.f))
                bad(key, "3 numbers in [0, 1]", x);
            tf.nanColor = c;
        } else if (k == "nan_opacity") {
            tf.nanOpacity = floatIn(key, x, 0.0, 1.0);
        } else if (k == "name") {
            if (!x.is_string() || x.get<std::string>().size() > 256)
                bad(key, "a string of at most 256 bytes", x);
            tf.name = x.get<std::string>();
        } else if (k == "color_space") {
            const auto space = colorSpaceFromName(x.is_string() ? x.get<std::string>() : "");
            if (!space) bad(key, "\"RGB\", \"Lab\" or \"Diverging\"", x);
            tf.colorSpace = *space;
        } else {
            bad("tf",
                "keys colors, opacity, log, nan_color, nan_opacity, name, color_space (not \"" +
                    printableShort(k, 40) + "\")",
                v);
        }
    }
}

}  // namespace

Json toJson(const ViewState& s) {
    auto vec = [](Vec3f v) { return Json::array({v.x, v.y, v.z}); };
    Json colors = Json::array(), opacity = Json::array();
    for (const ColorPoint& c : s.tf.colors) colors.push_back({c.x, c.rgb.x, c.rgb.y, c.rgb.z});
    for (const OpacityPoint& o : s.tf.opacities) opacity.push_back({o.x, o.alpha});
    Json j = {{"camera",
               {{"position", vec(s.camera.position)},
                {"focal_point", vec(s.camera.focalPoint)},
                {"view_up", vec(s.camera.viewUp)},
                {"view_angle", s.camera.viewAngle},
                {"parallel", s.camera.parallelProjection},
                {"parallel_scale", s.camera.parallelScale}}},
              {"tf",
               {{"name", s.tf.name},
                {"color_space", colorSpaceName(s.tf.colorSpace)},
                {"colors", colors},
                {"opacity", opacity},
                {"log", s.tf.logScale},
                {"nan_color", vec(s.tf.nanColor)},
                {"nan_opacity", s.tf.nanOpacity}}},
              {"range", {s.range.first, s.range.second}},
              {"field", s.field},
              {"heatmap", s.heatmap},
              {"clip_planes", clipPlanesJson(s.clipPlanes)},
              {"iso", isoSurfacesJson(s.isoSurfaces)},
              {"gradient_opacity", gradientOpacityText(s.gradientOpacity)},
              {"size", {s.width, s.height}},
              {"step", s.step},
              {"background", vec(s.background)}};
    // The viewer's settings of the vocabulary as set (`uvr view` starts every tab with all of
    // them from its command line; the library's default for one a state does not hold).
    for (const char* name : kViewerSettings) {
        const auto it = s.settings.find(name);
        j[name] = it != s.settings.end() ? *it : settingDefault(settingNamed(name));
    }
    return j;
}

bool isViewerSetting(std::string_view name) {
    for (const char* n : kViewerSettings)
        if (name == n) return true;
    return false;
}

SetResult applySet(ViewState& state, const Json& message, std::size_t stepCount) {
    if (!message.is_object()) bad("set", "a JSON object", message);
    ViewState next = state;  // all or nothing
    SetResult result;
    // Colour maps first: explicit tf keys in the same message refine them.
    if (auto it = message.find("preset"); it != message.end()) {
        if (!it->is_string()) bad("preset", "a preset name", *it);
        const TransferFunction preset = transferFunctionPreset(it->get<std::string>());
        next.tf.name = preset.name;
        next.tf.colorSpace = preset.colorSpace;
        next.tf.colors = preset.colors;
        next.tf.nanColor = preset.nanColor;
        result.echoState = true;
    }
    if (auto it = message.find("colormap_json"); it != message.end()) {
        if (!it->is_string()) bad("colormap_json", "the text of a ParaView colour-map JSON", *it);
        std::string name;
        if (auto n = message.find("colormap_name"); n != message.end()) {
            if (!n->is_string()) bad("colormap_name", "a string", *n);
            name = n->get<std::string>();
        }
        const std::string& text = it->get_ref<const std::string&>();
        TransferFunction loaded =
            parseParaViewColorMap({text.begin(), text.end()}, "the uploaded colour map", name);
        // The state (sent back in `state` and `export`, and by the page in later `set`s) holds
        // no more points than a page may send.
        const std::size_t points = std::max(loaded.colors.size(), loaded.opacities.size());
        if (points > kMaxTfPoints)
            throwError(ErrorKind::Argument, "the uploaded colour map",
                       std::to_string(points) +
                           " points (HSV segments count 32 each): the viewer takes at most " +
                           std::to_string(kMaxTfPoints));
        // A map without opacity points (the loader's ramp) keeps the page's opacity.
        const bool hasPoints = text.find("\"Points\"") != std::string::npos;
        if (!hasPoints) loaded.opacities = next.tf.opacities;
        if (loaded.sourceRange && loaded.sourceRange->first < loaded.sourceRange->second &&
            !message.contains("range")) {
            next.range = *loaded.sourceRange;
            result.rangeGiven = true;
        }
        next.tf = loaded;
        result.echoState = true;
    } else if (message.contains("colormap_name")) {
        bad("colormap_name", "to come with colormap_json", message["colormap_name"]);
    }
    for (const auto& [k, v] : message.items()) {
        if (k == "type" || k == "seq" || k == "interactive" || k == "preset" ||
            k == "colormap_json" || k == "colormap_name")
            continue;
        if (k == "camera") {
            applyCamera(next.camera, v);
        } else if (k == "tf") {
            applyTf(next.tf, v);
        } else if (k == "range") {
            if (!v.is_array() || v.size() != 2) bad(k, "[lo, hi]", v);
            const float lo = finiteFloat("range[0]", v[0]), hi = finiteFloat("range[1]", v[1]);
            if (!(lo < hi)) bad(k, "lo < hi", v);
            next.range = {lo, hi};
            result.rangeGiven = true;
        } else if (k == "field") {
            if (!v.is_string() || v.get<std::string>().size() > 1024)
                bad(k, "a field spec (\"pressure\", \"velocity:magnitude\", \"T:cell\")", v);
            parseFieldSpec(v.get<std::string>());  // a malformed suffix fails here
            result.fieldChanged = v.get<std::string>() != next.field;
            next.field = v.get<std::string>();
        } else if (isViewerSetting(k)) {
            // The vocabulary checks it; the page reads the key as it sent it.
            try {
                checkSetting(settingNamed(k), v);
            } catch (const SettingError& e) {
                throwError(ErrorKind::Argument, "", e.spelledAs("\"" + k + "\":", " "));
            }
            next.settings[k] = v;
        } else if (k == "heatmap") {
            next.heatmap = boolean(k, v);
        } else if (k == "clip_planes") {
            next.clipPlanes = clipPlanes(k, v);
        } else if (k == "iso") {
            next.isoSurfaces = isoSurfaces(k, v);
        } else if (k == "gradient_opacity") {
            if (!v.is_string() || v.get_ref<const std::string&>().size() > 256)
                bad(k, "\"MAGNITUDE:SCALE,...\" (up to 8 points) or \"\" (off)", v);
            try {
                const std::string& text = v.get_ref<const std::string&>();
                next.gradientOpacity =
                    text.empty() ? GradientOpacity{} : parseGradientOpacity(text);
            } catch (const SettingError& e) {
                throwError(ErrorKind::Argument, "", e.spelledAs("\"" + k + "\":", " "));
            }
        } else if (k == "size") {
            if (!v.is_array() || v.size() != 2 || !v[0].is_number_integer() ||
                !v[1].is_number_integer())
                bad(k, "[width, height] in pixels", v);
            const auto w = v[0].get<std::int64_t>(), h = v[1].get<std::int64_t>();
            if (w < kMinViewSize || h < kMinViewSize || w > kMaxViewSize || h > kMaxViewSize)
                bad(k,
                    "[width, height], each in [" + std::to_string(kMinViewSize) + ", " +
                        std::to_string(kMaxViewSize) + "]",
                    v);
            next.width = static_cast<int>(w);
            next.height = static_cast<int>(h);
        } else if (k == "background") {
            if (!v.is_array() || v.size() != 3) bad(k, "[r, g, b], each in [0, 1]", v);
            for (int c = 0; c < 3; ++c) {
                const double x = v[c].is_number() ? v[c].get<double>() : NAN;
                if (!(x >= 0.0 && x <= 1.0)) bad(k, "[r, g, b], each in [0, 1]", v);
                next.background[c] = static_cast<float>(x);
            }
        } else if (k == "step") {
            const bool index =
                v.is_number_unsigned() || (v.is_number_integer() && v.get<std::int64_t>() >= 0);
            if (!index || v.get<std::uint64_t>() >= stepCount)
                bad(k,
                    stepCount == 1 ? "0: the file has no other time step"
                                   : "a time step from 0 to " + std::to_string(stepCount - 1),
                    v);
            next.step = v.get<std::size_t>();
        } else {
            std::string keys =
                "camera, tf, range, field, heatmap, clip_planes, iso, gradient_opacity, size, "
                "step, background, "
                "preset, "
                "colormap_json";
            for (const char* name : kViewerSettings) keys += std::string(", ") + name;
            bad("set", "state keys (" + keys + "), not \"" + printableShort(k, 40) + "\"", message);
        }
    }
    // A log scale over a range from 0 or below maps from min(hi / 10^4, 1), as ParaView does
    // (the frame says so in its notes); one with nothing positive cannot map at all.
    if (next.tf.logScale && !(next.range.second > 0.f))
        throwError(ErrorKind::Argument, "",
                   "\"range\": a log-scale transfer function needs a range reaching above 0, "
                   "got [" +
                       fmtG(next.range.first) + ", " + fmtG(next.range.second) + "]");
    state = std::move(next);
    return result;
}

RenderSettings frameSettings(const ViewState& state, const RenderSettings& base, int scale) {
    RenderSettings s = base;
    s.progress = {};
    s.camera = state.camera;
    s.tf = state.tf;
    s.range = state.range;
    s.clipPlanes = state.clipPlanes;
    s.isoSurfaces = state.isoSurfaces;
    s.gradientOpacity = state.gradientOpacity;
    for (const auto& [name, value] : state.settings.items()) applySetting(s, name, value);
    scale = std::max(scale, 1);
    s.width = std::max(1, state.width / scale);
    s.height = std::max(1, state.height / scale);
    return s;
}

}  // namespace uvr::server
