// SPDX-License-Identifier: MIT
#include "uvr/render/render_settings.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/core/text.h"
#include "uvr/render/settings_vocabulary.h"

namespace uvr {

float toleranceForQuality(float quality) {
    checkSetting(settingNamed("quality"), quality);  // SettingError out of range
    return kToleranceScale * (1.f - quality);
}

[[noreturn]] void refuseLogRange(bool given, double lo, double hi) {
    const std::string range = "[" + formatG(lo, 6) + ", " + formatG(hi, 6) + "]";
    throwError(ErrorKind::Argument, "",
               "`log` needs positive values: " +
                   (given ? "`range` " + range : "the field's range " + range) +
                   " has none; give `range` LO,HI with 0 < LO <= HI");
}

bool tunesAdaptive(const RenderSettings& s) {
    const RenderSettings d;
    for (const SettingDef& def : settingsVocabulary())
        if (def.tunesAdaptive && def.get(s) != def.get(d)) return true;
    return false;
}

const char* stepRuleName(StepRule rule) {
    return rule == StepRule::Variance ? "variance" : "error";
}

const char* samplingName(bool preintegrated) {
    return preintegrated ? "preintegrated" : "point";
}

ClipView clipView(const RenderSettings& s, const MeshFrame& frame) {
    ClipView v;
    for (const ClipPlane& p : s.clipPlanes) {
        if (v.planeCount == kMaxClipPlanes) break;  // validateSettings refuses more
        double o[3];
        frame.toLocal(p.origin, o);
        const float len = length(p.normal);
        ClipPlane& q = v.planes[v.planeCount++];
        q.origin = Vec3f(float(o[0]), float(o[1]), float(o[2]));
        q.normal = len > 0.f ? p.normal / len : p.normal;
    }
    if (s.clipBox) {
        double lo[3], hi[3];
        frame.toLocal(s.clipBox->lo, lo);
        frame.toLocal(s.clipBox->hi, hi);
        v.hasBox = true;
        v.box.lo = Vec3f(float(lo[0]), float(lo[1]), float(lo[2]));
        v.box.hi = Vec3f(float(hi[0]), float(hi[1]), float(hi[2]));
    }
    v.surface = s.clipSurface && v.active();
    return v;
}

namespace {

/// Two points as "x0,y0,z0,x1,y1,z1".
std::string sixNumbersText(Vec3f a, Vec3f b) {
    std::string out;
    for (float x : {a.x, a.y, a.z, b.x, b.y, b.z}) out += (out.empty() ? "" : ",") + formatG(x, 6);
    return out;
}

}  // namespace

std::string clipPlaneText(const ClipPlane& p) {
    return sixNumbersText(p.origin, p.normal);
}

std::string clipBoxText(const Bounds3f& b) {
    return sixNumbersText(b.lo, b.hi);
}

IsoView isoView(const RenderSettings& s) {
    IsoView v;
    for (const IsoSurface& iso : s.isoSurfaces) {
        if (v.count == kMaxIsoSurfaces) break;  // validateSettings refuses more
        v.surfaces[v.count++] = iso;
    }
    std::stable_sort(v.surfaces, v.surfaces + v.count,
                     [](const IsoSurface& a, const IsoSurface& b) { return a.value < b.value; });
    return v;
}

namespace {

constexpr const char* kIsoForm =
    "expected VALUE[,OPACITY[,#RRGGBB]]: a finite value, an opacity in (0, 1] (default 1: "
    "opaque) and a "
    "colour (default: the colour map's at the value)";

/// A colour channel in [0, 1] as two hex digits (out of range or NaN: clamped, for messages).
std::string hexByte(float c) {
    const float v = c >= 0.f ? (c <= 1.f ? c : 1.f) : 0.f;
    char buf[4];
    std::snprintf(buf, sizeof buf, "%02x", int(std::lround(v * 255.f)));
    return buf;
}

/// A finite number written alone (no space before it, nothing after it), or nullopt.
std::optional<float> finiteNumber(const std::string& t) {
    char* end = nullptr;
    const float v = std::strtof(t.c_str(), &end);
    if (t.empty() || *end != '\0' || !std::isfinite(v) || std::isspace((unsigned char)t[0]))
        return std::nullopt;
    return v;
}

/// The shortest decimal that reads back as the same float ("0.1", not "0.100000001").
std::string shortest(float v) {
    char buf[32];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    return ec == std::errc() ? std::string(buf, end) : formatG(v, 9);
}

}  // namespace

std::string isoText(const IsoSurface& iso) {
    std::string out = shortest(iso.value);
    if (iso.opacity != 1.f || !iso.colorMapped) out += "," + shortest(iso.opacity);
    if (!iso.colorMapped)
        out += ",#" + hexByte(iso.color.x) + hexByte(iso.color.y) + hexByte(iso.color.z);
    return out;
}

IsoSurface parseIsoSurface(const std::string& text) {
    auto bad = [&]() { throw SettingError("iso", text, kIsoForm); };
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (;;) {
        const std::size_t comma = text.find(',', start);
        parts.push_back(text.substr(start, comma - start));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (parts.size() > 3) bad();
    auto number = [&](const std::string& t) {
        const std::optional<float> v = finiteNumber(t);
        if (!v) bad();
        return *v;
    };
    IsoSurface iso;
    iso.value = number(parts[0]);
    if (parts.size() > 1) iso.opacity = number(parts[1]);
    if (!(iso.opacity > 0.f && iso.opacity <= 1.f)) bad();
    if (parts.size() > 2) {
        const std::string& c = parts[2];
        if (c.size() != 7 || c[0] != '#' ||
            c.find_first_not_of("0123456789abcdefABCDEF", 1) != std::string::npos)
            bad();
        const long rgb = std::strtol(c.c_str() + 1, nullptr, 16);
        iso.colorMapped = false;
        iso.color = Vec3f(float((rgb >> 16) & 255) / 255.f, float((rgb >> 8) & 255) / 255.f,
                          float(rgb & 255) / 255.f);
    }
    return iso;
}

void checkIso(const RenderSettings& s) {
    if (s.isoSurfaces.size() > std::size_t(kMaxIsoSurfaces))
        throw SettingError("iso", std::to_string(s.isoSurfaces.size()) + " isosurfaces",
                           "expected at most " + std::to_string(kMaxIsoSurfaces));
    for (const IsoSurface& iso : s.isoSurfaces) {
        const Vec3f& c = iso.color;
        if (!std::isfinite(iso.value) || !(iso.opacity > 0.f && iso.opacity <= 1.f) ||
            !(c.x >= 0.f && c.x <= 1.f && c.y >= 0.f && c.y <= 1.f && c.z >= 0.f && c.z <= 1.f))
            throw SettingError("iso", isoText(iso), kIsoForm);
    }
}

namespace {

constexpr const char* kGradientOpacityForm =
    "expected MAGNITUDE:SCALE[,MAGNITUDE:SCALE...]: up to 8 points of a gradient magnitude (the "
    "field's units per length in the file, finite, >= 0, non-decreasing) and the opacity scale "
    "there, in [0, 1]";

}  // namespace

std::string gradientOpacityText(const GradientOpacity& g) {
    std::string out;
    for (int i = 0; i < g.count; ++i)
        out += (i ? "," : "") + shortest(g.magnitude[i]) + ":" + shortest(g.scale[i]);
    return out;
}

GradientOpacity parseGradientOpacity(const std::string& text) {
    auto bad = [&]() { throw SettingError("gradient_opacity", text, kGradientOpacityForm); };
    auto number = [&](const std::string& t) {
        const std::optional<float> v = finiteNumber(t);
        if (!v) bad();
        return *v;
    };
    GradientOpacity g;
    std::size_t start = 0;
    for (;;) {
        const std::size_t comma = text.find(',', start);
        const std::string point = text.substr(start, comma - start);
        const std::size_t colon = point.find(':');
        if (colon == std::string::npos || g.count == kMaxGradientOpacityPoints) bad();
        g.magnitude[g.count] = number(point.substr(0, colon));
        g.scale[g.count] = number(point.substr(colon + 1));
        ++g.count;
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    checkGradientOpacity(g, text);
    return g;
}

void checkGradientOpacity(const GradientOpacity& g, const std::string& text) {
    const std::string shown = text.empty() ? gradientOpacityText(g) : text;
    if (g.count < 0 || g.count > kMaxGradientOpacityPoints)
        throw SettingError("gradient_opacity", std::to_string(g.count) + " points",
                           kGradientOpacityForm);
    for (int i = 0; i < g.count; ++i) {
        const float m = g.magnitude[i], a = g.scale[i];
        if (!(std::isfinite(m) && m >= 0.f && a >= 0.f && a <= 1.f) ||
            (i > 0 && !(m >= g.magnitude[i - 1])))
            throw SettingError("gradient_opacity", shown, kGradientOpacityForm);
    }
}

void validateSettings(const RenderSettings& s) {
    auto bad = [](const std::string& msg) { throwError(ErrorKind::Argument, "", msg); };
    constexpr int kMaxSide = 16384;
    if (s.width < 1 || s.height < 1 || s.width > kMaxSide || s.height > kMaxSide)
        throw SettingError("size", std::to_string(s.width) + "x" + std::to_string(s.height),
                           "each side must be between 1 and " + std::to_string(kMaxSide));
    // Every setting of the vocabulary within its range (SettingError names it).
    for (const SettingDef& def : settingsVocabulary()) checkSetting(def, def.get(s));
    if (!(s.terminationAlpha > 0.f && s.terminationAlpha <= 1.f))
        bad("early termination threshold must lie in (0, 1]");
    if (s.range && !(std::isfinite(s.range->first) && std::isfinite(s.range->second) &&
                     s.range->first <= s.range->second))
        throw SettingError("range", formatG(s.range->first, 6) + "," + formatG(s.range->second, 6),
                           "expected finite lo <= hi");
    if (s.tfTableSize < 2 || s.tfTableSize > (1 << 20))
        bad("transfer function table size out of range");
    if (s.tf.colors.empty() || s.tf.opacities.empty())
        bad("transfer function needs at least one colour and one opacity point");
    if (s.camera) validateCamera(*s.camera);
    checkClip(s);
    checkIso(s);
    checkGradientOpacity(s.gradientOpacity);
    checkDepth(s);
}

namespace {

/// A per-pixel opacity setting (pixelStopAlpha, pixelDepthAlpha): none, or one opacity in [0, 1]
/// per pixel with one ray a pixel.
void checkPixelOpacities(const RenderSettings& s, const std::vector<float>& v, const char* name,
                         const char* what) {
    if (v.empty()) return;
    if (v.size() != std::size_t(s.width) * std::size_t(std::max(s.height, 0)))
        throw SettingError(name, std::to_string(v.size()) + " " + what,
                           "expected one per pixel: " + std::to_string(s.width) + " x " +
                               std::to_string(s.height));
    if (s.supersample != 1)
        throw SettingError(name, "given", "expected supersample 1 (one ray a pixel)");
    for (std::size_t i = 0; i < v.size(); ++i)
        if (!(v[i] >= 0.f && v[i] <= 1.f))
            throw SettingError(name, formatG(v[i], 6) + " at pixel " + std::to_string(i),
                               "expected opacities in [0, 1]");
}

}  // namespace

void checkDepth(const RenderSettings& s) {
    if (!(s.depthAlpha >= 0.f && s.depthAlpha <= 1.f))
        throw SettingError("depth_alpha", formatG(s.depthAlpha, 6), "expected a number in [0, 1]");
    if (!s.depthIn.empty() &&
        s.depthIn.size() != std::size_t(s.width) * std::size_t(std::max(s.height, 0)))
        throw SettingError("depth_in", std::to_string(s.depthIn.size()) + " depths",
                           "expected one per pixel: " + std::to_string(s.width) + " x " +
                               std::to_string(s.height));
    checkPixelOpacities(s, s.pixelStopAlpha, "pixel_stop_alpha", "stops");
    checkPixelOpacities(s, s.pixelDepthAlpha, "pixel_depth_alpha", "opacities");
    if (!s.pixelDepthAlpha.empty() && !(s.depthAlpha > 0.f))
        throw SettingError("pixel_depth_alpha", "given",
                           "expected depth_alpha above 0 (depth out)");
}

void checkClip(const RenderSettings& s) {
    if (s.clipPlanes.size() > std::size_t(kMaxClipPlanes))
        throw SettingError("clip_planes", std::to_string(s.clipPlanes.size()) + " planes",
                           "expected at most " + std::to_string(kMaxClipPlanes));
    for (const ClipPlane& p : s.clipPlanes)
        if (!isFinite(p.origin) || !isFinite(p.normal) || !(length(p.normal) > 0.f))
            throw SettingError("clip_planes", clipPlaneText(p),
                               "expected a finite origin and a finite normal other than 0,0,0");
    if (s.clipBox && (!isFinite(s.clipBox->lo) || !isFinite(s.clipBox->hi) ||
                      s.clipBox->lo.x > s.clipBox->hi.x || s.clipBox->lo.y > s.clipBox->hi.y ||
                      s.clipBox->lo.z > s.clipBox->hi.z))
        throw SettingError("clip_box", clipBoxText(*s.clipBox),
                           "expected finite x0,y0,z0,x1,y1,z1 with x0 <= x1, y0 <= y1, z0 <= z1");
    if (s.tf.logScale && s.range && !(s.range->second > 0.f))  // the field's range: at setup
        refuseLogRange(true, s.range->first, s.range->second);
}

}  // namespace uvr
