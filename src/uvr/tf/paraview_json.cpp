// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <nlohmann/json.hpp>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/text.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

namespace {

using Json = nlohmann::json;

/// Largest colour-map file read (ParaView's biggest presets are a few hundred kilobytes).
constexpr std::uint64_t kMaxJsonBytes = 64ull << 20;

/// Segments each HSV-interpolated colour segment is resampled into for RGB interpolation.
constexpr int kHsvSubdivisions = 32;

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

/// A short, one-line rendering of a JSON value for error messages: scalars as JSON (strings
/// cut to about 40 characters, invalid UTF-8 and control characters escaped), arrays and
/// objects by their size, so that no large or deeply nested value is ever serialised.
std::string describe(const Json& v) {
    if (v.is_array()) return "an array of " + std::to_string(v.size()) + " value(s)";
    if (v.is_object()) return "an object with " + std::to_string(v.size()) + " key(s)";
    if (v.is_string()) return "\"" + printableShort(v.get_ref<const std::string&>(), 38) + "\"";
    return v.dump(-1, ' ', false, Json::error_handler_t::replace);
}

/// Refuses UTF-16 and UTF-32 text and arrays or objects nested deeper than kMaxJsonDepth
/// (found by a scan of the brackets outside strings, before the parser sees them), naming the
/// byte offset.
void checkJsonShape(const std::string& path, const std::vector<char>& bytes) {
    if (const char* wide = wideTextEncoding(bytes.data(), bytes.size()))
        throwParseError(path, atByte(0),
                        std::string(wide) + " text is not supported; save the colour map as UTF-8");
    const std::size_t deep = jsonTooDeepAt(std::string_view(bytes.data(), bytes.size()));
    if (deep != std::string_view::npos)
        throwParseError(path, atByte(deep),
                        "JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                            " levels (a ParaView colour map nests 3)");
}

/// Reads a flat array of numbers whose length is a non-zero multiple of 4.
std::vector<double> readQuads(const std::string& path, const std::string& where, const Json& v) {
    if (!v.is_array()) {
        throwParseError(path, where, "expected an array of numbers, got " + describe(v));
    }
    if (v.empty() || v.size() % 4 != 0) {
        throwParseError(path, where,
                        "expected a non-empty multiple of 4 numbers (x, then 3 values per "
                        "point), got " +
                            std::to_string(v.size()));
    }
    std::vector<double> out;
    out.reserve(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
        const Json& e = v[i];
        if (!e.is_number() || !std::isfinite(e.get<double>())) {
            throwParseError(path, where + "[" + std::to_string(i) + "]",
                            "expected a finite number, got " + describe(e));
        }
        out.push_back(e.get<double>());
    }
    for (size_t i = 4; i < out.size(); i += 4) {
        if (out[i] < out[i - 4]) {
            throwParseError(path, where + "[" + std::to_string(i) + "]",
                            "expected positions that do not decrease, got " +
                                std::to_string(out[i]) + " after " + std::to_string(out[i - 4]));
        }
    }
    return out;
}

void checkUnit(const std::string& path, const std::string& where, size_t i, double v,
               const std::string& what) {
    if (v < 0.0 || v > 1.0) {
        throwParseError(path, where + "[" + std::to_string(i) + "]",
                        "expected " + what + " in [0, 1], got " + std::to_string(v));
    }
}

Vec3f hsvToRgb(double h, double s, double v) {
    h = (h - std::floor(h)) * 6.0;
    int sector = static_cast<int>(h) % 6;
    double f = h - std::floor(h);
    double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    double r = v, g = t, b = p;
    switch (sector) {
        case 1:
            r = q, g = v, b = p;
            break;
        case 2:
            r = p, g = v, b = t;
            break;
        case 3:
            r = p, g = q, b = v;
            break;
        case 4:
            r = t, g = p, b = v;
            break;
        case 5:
            r = v, g = p, b = q;
            break;
        default:
            break;
    }
    return {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b)};
}

void rgbToHsv(Vec3f c, double& h, double& s, double& v) {
    double mx = std::max({c.x, c.y, c.z}), mn = std::min({c.x, c.y, c.z});
    v = mx;
    double d = mx - mn;
    s = mx > 0 ? d / mx : 0;
    if (d <= 0) {
        h = 0;
        return;
    }
    if (mx == c.x)
        h = (c.y - c.z) / d;
    else if (mx == c.y)
        h = 2.0 + (c.z - c.x) / d;
    else
        h = 4.0 + (c.x - c.y) / d;
    h /= 6.0;
    if (h < 0) h += 1.0;
}

}  // namespace

std::vector<ColorPoint> resampleHsv(const std::vector<ColorPoint>& in, bool wrap) {
    std::vector<ColorPoint> out;
    for (size_t i = 0; i + 1 < in.size(); ++i) {
        double h0, s0, v0, h1, s1, v1;
        rgbToHsv(in[i].rgb, h0, s0, v0);
        rgbToHsv(in[i + 1].rgb, h1, s1, v1);
        if (wrap && h1 - h0 > 0.5) h0 += 1.0;
        if (wrap && h0 - h1 > 0.5) h1 += 1.0;
        for (int k = 0; k < kHsvSubdivisions; ++k) {
            double f = static_cast<double>(k) / kHsvSubdivisions;
            float x = in[i].x + static_cast<float>(f) * (in[i + 1].x - in[i].x);
            out.push_back(
                {x, k == 0 ? in[i].rgb
                           : hsvToRgb(h0 + f * (h1 - h0), s0 + f * (s1 - s0), v0 + f * (v1 - v0))});
        }
    }
    out.push_back(in.back());
    return out;
}

namespace {

/// Parses a colour-map JSON document (the bytes of `path`); Error(Parse) naming the byte for
/// invalid JSON.
Json parseColorMapDocument(const std::string& path, const std::vector<char>& bytes) {
    checkJsonShape(path, bytes);
    Json doc;
    try {
        doc = Json::parse(bytes.begin(), bytes.end());
    } catch (const Json::parse_error& e) {
        std::string msg = e.what();
        size_t bracket = msg.find("] ");
        if (bracket != std::string::npos) msg = msg.substr(bracket + 2);
        throwParseError(
            path, atByte(e.byte),
            "expected JSON (a ParaView colour-map export), got " + printableShort(msg, 160));
    } catch (const Json::exception& e) {
        // A well-formed number too large for a double ("number overflow parsing '1e999'") is an
        // out_of_range error without an offset: find the quoted number in the file.
        std::string msg = e.what();
        size_t bracket = msg.find("] ");
        if (bracket != std::string::npos) msg = msg.substr(bracket + 2);
        std::uint64_t offset = 0;
        const size_t open = msg.find('\''), close = msg.rfind('\'');
        if (open != std::string::npos && close > open + 1) {
            const std::string token = msg.substr(open + 1, close - open - 1);
            const auto it = std::search(bytes.begin(), bytes.end(), token.begin(), token.end());
            if (it != bytes.end()) offset = static_cast<std::uint64_t>(it - bytes.begin());
        }
        throwParseError(path, atByte(offset),
                        "expected JSON (a ParaView colour-map export) with numbers a double can "
                        "hold, got " +
                            printableShort(msg, 160));
    }
    return doc;
}

/// Lower case without spaces, tabs, '-' and '_': how names in a presets file are matched when
/// no name matches exactly.
std::string looseName(const std::string& name) {
    std::string out;
    for (char c : name)
        if (c != ' ' && c != '\t' && c != '-' && c != '_')
            out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

/// The "Name" of a colour-map object, or "" when it has none.
std::string mapName(const Json& map) {
    if (!map.is_object()) return "";
    const auto it = map.find("Name");
    return it != map.end() && it->is_string() ? it->get<std::string>() : "";
}

/// Up to `count` names quoted and comma-separated, with "and N more" for the rest.
std::string quotedNames(const std::vector<std::string>& names, std::size_t count) {
    std::string out;
    for (std::size_t i = 0; i < names.size() && i < count; ++i)
        out += (i ? ", \"" : "\"") + printableShort(names[i], 48) + "\"";
    if (names.size() > count) out += " and " + std::to_string(names.size() - count) + " more";
    return out;
}

/// The index of the map to load from an array of maps: the only one when `name` is empty (a file
/// of several is refused, naming them), else the first whose Name is `name`, or failing that
/// the first that matches it ignoring case, spaces, '-' and '_' (an unknown name is refused,
/// naming the close ones).
std::size_t selectMap(const std::string& path, const Json& maps, const std::string& name) {
    std::vector<std::string> names;
    for (const Json& m : maps) names.push_back(mapName(m));
    const std::string listing = "`uvr presets " + path + "` lists them";
    if (name.empty()) {
        if (maps.size() == 1) return 0;
        throwError(ErrorKind::Argument, path,
                   "holds " + std::to_string(maps.size()) + " colour maps: pick one with `tf` " +
                       path + ":NAME, one of " + quotedNames(names, 10) + " (" + listing + ")");
    }
    for (std::size_t i = 0; i < names.size(); ++i)
        if (names[i] == name) return i;
    const std::string key = looseName(name);
    for (std::size_t i = 0; i < names.size(); ++i)
        if (!names[i].empty() && looseName(names[i]) == key) return i;
    std::vector<std::string> keys;
    for (const std::string& n : names) keys.push_back(looseName(n));
    std::vector<std::string> close;
    for (const std::string& k : closeMatches(key, keys))
        for (const std::string& n : names)
            if (looseName(n) == k && std::find(close.begin(), close.end(), n) == close.end()) {
                close.push_back(n);
                break;
            }
    throwError(ErrorKind::Argument, path,
               "no colour map named \"" + printableShort(name, 60) + "\"" +
                   (close.empty() ? "; it holds " + quotedNames(names, 10)
                                  : "; did you mean " + quotedNames(close, 5) + "?") +
                   " (" + std::to_string(maps.size()) + " maps; " + listing + ")");
}

/// A flag that ParaView writes as true/false or 1/0.
bool jsonFlag(const Json& map, const char* key) {
    const auto it = map.find(key);
    if (it == map.end()) return false;
    if (it->is_boolean()) return it->get<bool>();
    return it->is_number() && it->get<double>() != 0.0;
}

}  // namespace

std::vector<ColorMapInfo> listParaViewColorMaps(const std::string& path) {
    const Json doc =
        parseColorMapDocument(path, readFileBytes(path, kMaxJsonBytes, "colour-map file"));
    std::vector<ColorMapInfo> out;
    auto add = [&](const Json& m, const std::string& where) {
        if (!m.is_object())
            throwParseError(path, where, "expected a colour-map object, got " + describe(m));
        ColorMapInfo info;
        info.name = mapName(m);
        const auto space = m.find("ColorSpace");
        info.colorSpace =
            space != m.end() && space->is_string() ? space->get<std::string>() : "RGB";
        const auto rgb = m.find("RGBPoints");
        if (rgb != m.end() && rgb->is_array())
            info.points = static_cast<int>(rgb->size() / 4);
        else if (m.contains("IndexedColors"))
            info.colorSpace = "indexed";
        out.push_back(info);
    };
    if (doc.is_array()) {
        for (std::size_t i = 0; i < doc.size(); ++i) add(doc[i], "colour map " + std::to_string(i));
    } else {
        add(doc, "colour map");
    }
    return out;
}

TransferFunction loadParaViewColorMap(const std::string& path, const std::string& name) {
    return parseParaViewColorMap(readFileBytes(path, kMaxJsonBytes, "colour-map file"), path, name);
}

TransferFunction parseParaViewColorMap(const std::vector<char>& bytes, const std::string& path,
                                       const std::string& name) {
    if (bytes.size() > kMaxJsonBytes)
        throwError(ErrorKind::Resource, path,
                   "colour map of " + std::to_string(bytes.size()) + " bytes: more than " +
                       std::to_string(kMaxJsonBytes));
    const Json doc = parseColorMapDocument(path, bytes);
    // Step 1: the colour-map object: a file's only one, or the one named (ParaView's exports
    // and presets files are arrays of them).
    std::string where = "colour map";
    const Json* map = &doc;
    if (doc.is_array()) {
        if (doc.empty()) {
            throwParseError(path, "top level",
                            "expected an array of colour-map objects, got an empty array");
        }
        const std::size_t index = selectMap(path, doc, name);
        map = &doc[index];
        where = "colour map " + std::to_string(index);
    } else if (!name.empty() && mapName(doc) != name &&
               looseName(mapName(doc)) != looseName(name)) {
        throwError(ErrorKind::Argument, path,
                   "no colour map named \"" + printableShort(name, 60) + "\"; it holds one, \"" +
                       printableShort(mapName(doc), 48) + "\"");
    }
    if (!map->is_object()) {
        throwParseError(path, where, "expected a colour-map object, got " + describe(*map));
    }

    TransferFunction tf;
    if (auto it = map->find("Name"); it != map->end() && it->is_string()) {
        tf.name = it->get<std::string>();
    }

    // Step 2: the colour space.
    bool hsv = false;
    if (auto it = map->find("ColorSpace"); it != map->end()) {
        std::string space = it->is_string() ? lower(it->get<std::string>()) : "";
        if (space == "rgb") {
            tf.colorSpace = ColorSpace::RGB;
        } else if (space == "lab" || space == "cielab") {
            tf.colorSpace = ColorSpace::Lab;
        } else if (space == "diverging") {
            tf.colorSpace = ColorSpace::Diverging;
        } else if (space == "hsv") {
            hsv = true;
        } else if (space == "step") {
            throwError(ErrorKind::Unsupported, path,
                       where + " \"ColorSpace\": \"Step\" colour maps are not supported");
        } else {
            throwParseError(
                path, where + " \"ColorSpace\"",
                "expected \"RGB\", \"Lab\", \"Diverging\" or \"HSV\", got " + describe(*it));
        }
    }

    // Step 3: colour points, normalised over their own range.
    auto rgbIt = map->find("RGBPoints");
    if (rgbIt == map->end()) {
        throwParseError(path, where,
                        "expected key \"RGBPoints\" (x, r, g, b, ...); indexed (categorical) "
                        "colour maps are not supported");
    }
    const std::string rgbWhere = where + " \"RGBPoints\"";
    std::vector<double> rgb = readQuads(path, rgbWhere, *rgbIt);
    for (size_t i = 0; i < rgb.size(); ++i) {
        if (i % 4 != 0) checkUnit(path, rgbWhere, i, rgb[i], "a colour component");
    }
    // "UseLogScale": positions are data values on a log scale (ParaView's vtkNormalize; as
    // there, a range that is not positive is taken linearly).
    double lo = rgb.front(), hi = rgb[rgb.size() - 4];
    tf.logScale = jsonFlag(*map, "UseLogScale");
    const bool logPositions = tf.logScale && lo > 0.0;
    auto position = [&](double x) {
        return logPositions ? std::log10(x > DBL_MIN ? x : DBL_MIN) : x;
    };
    const double pLoRgb = position(lo), pHiRgb = position(hi);
    auto normalise = [&](double x) {
        return pHiRgb > pLoRgb ? static_cast<float>((position(x) - pLoRgb) / (pHiRgb - pLoRgb))
                               : 0.f;
    };
    for (size_t i = 0; i < rgb.size(); i += 4) {
        tf.colors.push_back({normalise(rgb[i]),
                             Vec3f(static_cast<float>(rgb[i + 1]), static_cast<float>(rgb[i + 2]),
                                   static_cast<float>(rgb[i + 3]))});
    }
    if (hsv) {
        tf.colors = resampleHsv(tf.colors, jsonFlag(*map, "HSVWrap"));
        tf.colorSpace = ColorSpace::RGB;
    }
    tf.sourceRange = std::make_pair(static_cast<float>(lo), static_cast<float>(hi));

    // Step 4: the colour and opacity of NaN values.
    if (auto it = map->find("NanColor"); it != map->end()) {
        const std::string nanWhere = where + " \"NanColor\"";
        if (!it->is_array() || it->size() < 3 || it->size() > 4)
            throwParseError(path, nanWhere, "expected 3 numbers (r, g, b), got " + describe(*it));
        for (std::size_t i = 0; i < 3; ++i) {
            const Json& c = (*it)[i];
            if (!c.is_number())
                throwParseError(path, nanWhere + "[" + std::to_string(i) + "]",
                                "expected a number, got " + describe(c));
            checkUnit(path, nanWhere, i, c.get<double>(), "a colour component");
            tf.nanColor[static_cast<int>(i)] = static_cast<float>(c.get<double>());
        }
    }
    if (auto it = map->find("NanOpacity"); it != map->end()) {
        const std::string nanWhere = where + " \"NanOpacity\"";
        if (!it->is_number())
            throwParseError(path, nanWhere, "expected a number in [0, 1], got " + describe(*it));
        const double a = it->get<double>();
        if (!(a >= 0.0 && a <= 1.0))
            throwParseError(path, nanWhere,
                            "expected an opacity in [0, 1], got " + std::to_string(a));
        tf.nanOpacity = static_cast<float>(a);
    }

    // Step 5: opacity points over the same range; a midpoint other than 0.5 becomes an extra
    // knot (vtkPiecewiseFunction's linear midpoint shift), sharpness is treated as 0.
    auto ptsIt = map->find("Points");
    if (ptsIt == map->end()) {
        tf.opacities = {{0.f, 0.f}, {1.f, 1.f}};
        return tf;
    }
    const std::string ptsWhere = where + " \"Points\"";
    std::vector<double> pts = readQuads(path, ptsWhere, *ptsIt);
    for (size_t i = 0; i < pts.size(); i += 4) {
        checkUnit(path, ptsWhere, i + 1, pts[i + 1], "an opacity");
        checkUnit(path, ptsWhere, i + 2, pts[i + 2], "a midpoint");
        checkUnit(path, ptsWhere, i + 3, pts[i + 3], "a sharpness");
    }
    double pLo = pLoRgb, pHi = pHiRgb;
    if (!(pHi > pLo)) pLo = position(pts.front()), pHi = position(pts[pts.size() - 4]);
    auto normaliseOpacity = [&](double x) {
        return pHi > pLo ? static_cast<float>((position(x) - pLo) / (pHi - pLo)) : 0.f;
    };
    TransferFunction raw;
    for (size_t i = 0; i < pts.size(); i += 4) {
        float x = normaliseOpacity(pts[i]);
        float a = static_cast<float>(pts[i + 1]);
        raw.opacities.push_back({x, a});
        if (i + 4 < pts.size() && pts[i + 2] != 0.5) {
            float x1 = normaliseOpacity(pts[i + 4]);
            float a1 = static_cast<float>(pts[i + 5]);
            raw.opacities.push_back(
                {x + static_cast<float>(pts[i + 2]) * (x1 - x), 0.5f * (a + a1)});
        }
    }
    // Clip to [0, 1]: the values at the ends plus the knots strictly inside.
    tf.opacities.push_back({0.f, raw.opacityAt(0.f)});
    for (const OpacityPoint& p : raw.opacities) {
        if (p.x > 0.f && p.x < 1.f) tf.opacities.push_back(p);
    }
    tf.opacities.push_back({1.f, raw.opacityAt(1.f)});
    return tf;
}

std::string paraViewColorMapJson(const TransferFunction& tf, double lo, double hi) {
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi))
        throwError(ErrorKind::Argument, "",
                   "a colour-map export needs a finite range lo < hi, got [" + std::to_string(lo) +
                       ", " + std::to_string(hi) + "]");
    if (tf.logScale && !(lo > 0.0))
        throwError(ErrorKind::Argument, "",
                   "a log-scale colour-map export needs a positive range, got [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + "]");
    if (tf.colors.empty() || tf.opacities.empty())
        throwError(ErrorKind::Argument, "", "a colour-map export needs colour and opacity points");
    // Data value of normalised position t (vtkNormalize's inverse).
    const double pLo = tf.logScale ? std::log10(lo) : lo;
    const double pHi = tf.logScale ? std::log10(hi) : hi;
    auto value = [&](double t) {
        if (t <= 0.0) return lo;
        if (t >= 1.0) return hi;
        const double p = pLo + t * (pHi - pLo);
        return tf.logScale ? std::pow(10.0, p) : p;
    };
    Json rgb = Json::array();
    auto addColor = [&](double t, Vec3f c) {
        rgb.insert(rgb.end(), {value(t), double(c.x), double(c.y), double(c.z)});
    };
    if (tf.colors.front().x > 0.f) addColor(0.0, tf.colors.front().rgb);
    for (const ColorPoint& c : tf.colors) addColor(c.x, c.rgb);
    if (tf.colors.back().x < 1.f) addColor(1.0, tf.colors.back().rgb);
    Json points = Json::array();
    for (const OpacityPoint& o : tf.opacities)
        points.insert(points.end(), {value(o.x), double(o.alpha), 0.5, 0.0});
    Json map = {{"Name", tf.name.empty() ? "uvr" : tf.name},
                {"ColorSpace", colorSpaceName(tf.colorSpace)},
                {"RGBPoints", rgb},
                {"Points", points},
                {"NanColor", {double(tf.nanColor.x), double(tf.nanColor.y), double(tf.nanColor.z)}},
                {"NanOpacity", double(tf.nanOpacity)},
                {"UseLogScale", tf.logScale ? 1 : 0}};
    return Json::array({map}).dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace uvr
