// SPDX-License-Identifier: MIT
#include "uvr/render/settings_vocabulary.h"

#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "uvr/core/error.h"
#include "uvr/core/text.h"

namespace uvr {

namespace {

using Json = nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A number as messages write it (%g).
std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

/// A float setting as JSON: the shortest decimal that reads back as the same float (0.99, not
/// 0.9900000095367432), so that defaults and reports read as written.
Json floatJson(float v) {
    char buf[32];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    if (ec != std::errc() || !std::isfinite(v)) return Json(double(v));
    return Json(std::strtod(std::string(buf, end).c_str(), nullptr));
}

/// A per-mesh default length: null while 0 (anything else is checked as given).
Json lengthOrNull(float v) {
    return v == 0.f ? Json(nullptr) : floatJson(v);
}
float lengthOf(const Json& v) {
    return v.is_null() ? 0.f : v.get<float>();
}

SettingDef setting(const char* name, SettingType type, const char* doc) {
    SettingDef d;
    d.name = name, d.type = type, d.doc = doc;
    return d;
}

/// One of ParaView's lighting coefficients: a number in [0, 1], read with `shade`.
SettingDef lightingCoefficient(const char* name, const char* doc) {
    SettingDef d = setting(name, SettingType::Number, doc);
    d.min = 0.0, d.max = 1.0;
    d.needs = "shade";
    return d;
}

std::vector<SettingDef> makeVocabulary() {
    std::vector<SettingDef> v;
    SettingDef method =
        setting("method", SettingType::Choice,
                "Integrator: auto (exact where a ray crosses few cells, else adaptive), "
                "adaptive, reference or exact");
    method.detail =
        "auto is adaptive whenever a setting tunes sampling; adaptive: k-d partitions and "
        "macrocells, space skipping and error-bounded adaptive steps (Morrical et al. 2019 and "
        "beyond); reference: the fixed step s1 everywhere; exact: no sampling, every cell's "
        "segment integrated exactly";
    method.choices = methodNames();
    method.get = [](const RenderSettings& s) { return Json(methodName(s.method)); };
    method.set = [](RenderSettings& s, const Json& x) {
        s.method = *parseMethod(x.get<std::string>());
    };
    v.push_back(method);

    SettingDef sampling =
        setting("sampling", SettingType::Choice,
                "Reference and adaptive: preintegrated (between consecutive samples) or "
                "point (point samples with opacity correction, Morrical et al. 2019)");
    sampling.detail =
        "preintegrated takes the scalar linear from one sample to the next: no "
        "transfer-function feature is missed";
    sampling.choices = {samplingName(true), samplingName(false)};
    sampling.tunesAdaptive = true;
    sampling.readBy = {RenderMethod::Reference, RenderMethod::Partitions};
    sampling.get = [](const RenderSettings& s) { return Json(samplingName(s.preintegrated)); };
    sampling.set = [](RenderSettings& s, const Json& x) {
        s.preintegrated = x.get<std::string>() == samplingName(true);
    };
    v.push_back(sampling);

    SettingDef rule =
        setting("step_rule", SettingType::Choice,
                "Adaptive: each partition's step from a bound on the integration error "
                "(error; quality) or from the colour variance (variance; power)");
    rule.detail =
        "error: a bounded integration error from the transfer function's rate of change and "
        "the field's gradients (`quality`); variance: Morrical et al. 2019's normalised colour "
        "variance (`power`)";
    rule.choices = {stepRuleName(StepRule::ErrorBound), stepRuleName(StepRule::Variance)};
    rule.tunesAdaptive = true;
    rule.readBy = {RenderMethod::Partitions};
    rule.get = [](const RenderSettings& s) { return Json(stepRuleName(s.stepRule)); };
    rule.set = [](RenderSettings& s, const Json& x) {
        s.stepRule = x.get<std::string>() == stepRuleName(StepRule::Variance)
                         ? StepRule::Variance
                         : StepRule::ErrorBound;
    };
    v.push_back(rule);

    SettingDef quality =
        setting("quality", SettingType::Number,
                "Adaptive, error rule: the SSIM against the exact integrator to aim at");
    quality.detail =
        "with `step_rule` error (the default); docs/PERFORMANCE.md shows what it gives";
    quality.min = kMinQuality, quality.max = kMaxQuality;
    quality.tunesAdaptive = true;
    quality.readBy = {RenderMethod::Partitions};
    quality.get = [](const RenderSettings& s) { return floatJson(s.quality); };
    quality.set = [](RenderSettings& s, const Json& x) { s.quality = x.get<float>(); };
    v.push_back(quality);

    SettingDef step =
        setting("sample_distance", SettingType::Number,
                "Sample spacing s1 in the file's units, ParaView's Sample Distance (default: "
                "half the cube root of the mean tetrahedron volume)");
    step.min = 0.0, step.max = kInf, step.minOpen = true, step.nullDefault = true;
    step.tunesAdaptive = true;
    step.get = [](const RenderSettings& s) { return lengthOrNull(s.step); };
    step.set = [](RenderSettings& s, const Json& x) { s.step = lengthOf(x); };
    v.push_back(step);

    SettingDef maxStep = setting("max_sample_distance", SettingType::Number,
                                 "Adaptive: the largest step s2 in the file's units (default: "
                                 "16 s1; shaded or with a gradient opacity, from 3 s1 in "
                                 "opaque regions up to 16 s1 in faint ones)");
    maxStep.min = 0.0, maxStep.max = kInf, maxStep.minOpen = true, maxStep.nullDefault = true;
    maxStep.tunesAdaptive = true;
    maxStep.readBy = {RenderMethod::Partitions};
    maxStep.get = [](const RenderSettings& s) { return lengthOrNull(s.maxStep); };
    maxStep.set = [](RenderSettings& s, const Json& x) { s.maxStep = lengthOf(x); };
    v.push_back(maxStep);

    SettingDef power = setting("power", SettingType::Number,
                               "Adaptive, variance rule: the power p of the step formula");
    power.detail = "with `step_rule` variance";
    power.min = 1.0, power.max = 64.0;
    power.tunesAdaptive = true;
    power.readBy = {RenderMethod::Partitions};
    power.get = [](const RenderSettings& s) { return floatJson(s.power); };
    power.set = [](RenderSettings& s, const Json& x) { s.power = x.get<float>(); };
    v.push_back(power);

    SettingDef unit =
        setting("opacity_unit", SettingType::Number,
                "Distance over which a transfer-function opacity applies, in the file's "
                "units (default: ParaView's, the bounds' diagonal over the cube root of the "
                "cells)");
    unit.min = 0.0, unit.max = kInf, unit.minOpen = true, unit.nullDefault = true;
    unit.get = [](const RenderSettings& s) { return lengthOrNull(s.opacityUnit); };
    unit.set = [](RenderSettings& s, const Json& x) { s.opacityUnit = lengthOf(x); };
    v.push_back(unit);

    SettingDef law = setting("opacity_law", SettingType::Choice,
                             "How an opacity per opacity unit absorbs: attenuation (ParaView's "
                             "unstructured mappers) or transmittance");
    law.detail =
        "attenuation: extinction a / u, so that a slab L thick has opacity 1 - exp(-a L / u); "
        "transmittance: extinction -ln(1 - a) / u, opacity 1 - (1 - a)^(L / u), a = 1 opaque at "
        "once (docs/TRANSFER_FUNCTIONS.md)";
    law.choices = {
        opacityLawName(kDefaultOpacityLaw),
        opacityLawName(kDefaultOpacityLaw == OpacityLaw::Attenuation ? OpacityLaw::Transmittance
                                                                     : OpacityLaw::Attenuation)};
    law.get = [](const RenderSettings& s) { return Json(opacityLawName(s.opacityLaw)); };
    law.set = [](RenderSettings& s, const Json& x) {
        parseOpacityLaw(x.get<std::string>().c_str(), s.opacityLaw);
    };
    v.push_back(law);

    SettingDef skip =
        setting("skip", SettingType::Flag,
                "Adaptive: skip partitions and macrocells the transfer function makes "
                "transparent");
    skip.offDoc = "Adaptive: also march partitions of zero opacity (\"adaptive only\")";
    skip.tunesAdaptive = true;
    skip.readBy = {RenderMethod::Partitions};
    skip.get = [](const RenderSettings& s) { return Json(s.skip); };
    skip.set = [](RenderSettings& s, const Json& x) { s.skip = x.get<bool>(); };
    v.push_back(skip);

    SettingDef adaptive = setting("adaptive", SettingType::Flag,
                                  "Adaptive: adaptive steps (false: every partition at s1)");
    adaptive.offDoc = "Adaptive: every partition at s1 (\"skipping only\")";
    adaptive.tunesAdaptive = true;
    adaptive.readBy = {RenderMethod::Partitions};
    adaptive.get = [](const RenderSettings& s) { return Json(s.adaptive); };
    adaptive.set = [](RenderSettings& s, const Json& x) { s.adaptive = x.get<bool>(); };
    v.push_back(adaptive);

    SettingDef supersample = setting("supersample", SettingType::Integer,
                                     "Anti-aliasing: N x N rays per pixel, their colours averaged");
    supersample.detail =
        "a pixel's sample count (heat map, statistics) sums its rays; 1: one ray through the "
        "pixel's centre";
    supersample.min = 1.0, supersample.max = double(kMaxSupersample);
    supersample.get = [](const RenderSettings& s) { return Json(s.supersample); };
    supersample.set = [](RenderSettings& s, const Json& x) { s.supersample = x.get<int>(); };
    v.push_back(supersample);

    SettingDef jitter =
        setting("jitter", SettingType::Flag,
                "With supersample: each ray at a fixed pseudo-random place in its cell of "
                "the N x N grid");
    jitter.detail = "the same rays every run and on every device";
    jitter.get = [](const RenderSettings& s) { return Json(s.jitter); };
    jitter.set = [](RenderSettings& s, const Json& x) { s.jitter = x.get<bool>(); };
    v.push_back(jitter);

    SettingDef shade = setting("shade", SettingType::Flag,
                               "Gradient shading: a headlight lights the volume, the field's "
                               "gradient its normal (ParaView's Shade)");
    shade.detail =
        "colour (`ambient` + `diffuse` c) + `specular` c^`specular_power`, c the cosine between "
        "the gradient and the view ray; exact per cell: constant in a linear tetrahedron";
    shade.get = [](const RenderSettings& s) { return Json(s.lighting.on); };
    shade.set = [](RenderSettings& s, const Json& x) { s.lighting.on = x.get<bool>(); };
    v.push_back(shade);

    SettingDef clipSurface =
        setting("clip_surface", SettingType::Flag,
                "Clipping: the cut face as an opaque surface coloured by the field, lit with the "
                "face's normal");
    clipSurface.detail =
        "where the clip planes or box cut the mesh; read with `--clip-plane` or `--clip-box`; "
        "lit by `ambient`, `diffuse`, `specular` and `specular_power`, shaded or not";
    clipSurface.get = [](const RenderSettings& s) { return Json(s.clipSurface); };
    clipSurface.set = [](RenderSettings& s, const Json& x) { s.clipSurface = x.get<bool>(); };
    v.push_back(clipSurface);

    SettingDef normals =
        setting("normals", SettingType::Choice,
                "Shading: smooth (the points' gradients interpolated in each cell) or cell "
                "(each cell's own gradient)");
    normals.detail =
        "smooth: each point's gradient the volume-weighted mean of its cells', made when first "
        "shaded (12 bytes per point); cell: constant in a linear tetrahedron, so its light is "
        "exact per cell but faceted";
    normals.choices = {"smooth", "cell"};
    normals.needs = "shade";
    normals.get = [](const RenderSettings& s) {
        return Json(s.lighting.smooth ? "smooth" : "cell");
    };
    normals.set = [](RenderSettings& s, const Json& x) {
        s.lighting.smooth = x.get<std::string>() == "smooth";
    };
    v.push_back(normals);

    SettingDef ambient =
        lightingCoefficient("ambient", "Shading: the light every point gets whatever its gradient");
    ambient.get = [](const RenderSettings& s) { return floatJson(s.lighting.ambient); };
    ambient.set = [](RenderSettings& s, const Json& x) { s.lighting.ambient = x.get<float>(); };
    v.push_back(ambient);

    SettingDef diffuse = lightingCoefficient(
        "diffuse", "Shading: the light a point gets times the cosine of its gradient to the ray");
    diffuse.get = [](const RenderSettings& s) { return floatJson(s.lighting.diffuse); };
    diffuse.set = [](RenderSettings& s, const Json& x) { s.lighting.diffuse = x.get<float>(); };
    v.push_back(diffuse);

    SettingDef specular = lightingCoefficient(
        "specular", "Shading: the white highlight where the gradient faces the ray");
    specular.get = [](const RenderSettings& s) { return floatJson(s.lighting.specular); };
    specular.set = [](RenderSettings& s, const Json& x) { s.lighting.specular = x.get<float>(); };
    v.push_back(specular);

    SettingDef shininess =
        setting("specular_power", SettingType::Number,
                "Shading: the highlight's exponent (larger: smaller highlights)");
    shininess.detail = "with `specular`";
    shininess.min = 0.0, shininess.max = 128.0;
    shininess.needs = "shade";
    shininess.get = [](const RenderSettings& s) { return floatJson(s.lighting.specularPower); };
    shininess.set = [](RenderSettings& s, const Json& x) {
        s.lighting.specularPower = x.get<float>();
    };
    v.push_back(shininess);
    return v;
}

/// "'a', 'b' or 'c'".
std::string choiceList(const std::vector<std::string>& choices) {
    std::string out;
    for (std::size_t i = 0; i < choices.size(); ++i) {
        if (i > 0) out += i + 1 == choices.size() ? " or " : ", ";
        out += "'" + choices[i] + "'";
    }
    return out;
}

/// What a Number or Integer setting expects, in words.
std::string rangeText(const SettingDef& d) {
    const char* what = d.type == SettingType::Integer ? "an integer" : "a number";
    if (d.minOpen && d.min == 0.0 && d.max == kInf) return "a positive finite number";
    return std::string(what) + " in [" + number(d.min) + ", " + number(d.max) + "]";
}

}  // namespace

const std::vector<SettingDef>& settingsVocabulary() {
    static const std::vector<SettingDef> vocabulary = makeVocabulary();
    return vocabulary;
}

const SettingDef* findSetting(std::string_view name) {
    for (const SettingDef& d : settingsVocabulary())
        if (name == d.name) return &d;
    return nullptr;
}

const SettingDef& settingNamed(std::string_view name) {
    if (const SettingDef* d = findSetting(name)) return *d;
    std::vector<std::string> names;
    for (const SettingDef& d : settingsVocabulary()) names.emplace_back(d.name);
    throw SettingError("setting", "'" + printableShort(name) + "'",
                       "not a setting; the settings are " + choiceList(names));
}

std::string settingValueText(const Json& value) {
    if (value.is_string()) return "'" + printableShort(value.get_ref<const std::string&>()) + "'";
    return printableShort(value.dump(-1, ' ', false, Json::error_handler_t::replace));
}

void checkSetting(const SettingDef& d, const Json& value) {
    auto refuse = [&](const std::string& expected) {
        throw SettingError(d.name, settingValueText(value), "expected " + expected);
    };
    switch (d.type) {
        case SettingType::Choice:
            if (!value.is_string()) refuse(choiceList(d.choices));
            for (const std::string& c : d.choices)
                if (value.get_ref<const std::string&>() == c) return;
            refuse(choiceList(d.choices));
            return;
        case SettingType::Flag:
            if (!value.is_boolean()) refuse("true or false");
            return;
        case SettingType::Number:
        case SettingType::Integer: {
            if (value.is_null() && d.nullDefault) return;
            const bool integer = d.type == SettingType::Integer;
            if (!value.is_number() || (integer && !value.is_number_integer())) refuse(rangeText(d));
            const double x = value.get<double>();
            const bool above = d.minOpen ? x > d.min : x >= d.min;
            // A number a float holds (the settings are float): no overflow to infinity.
            const double limit = integer ? d.max : std::min(d.max, double(FLT_MAX));
            if (!(std::isfinite(x) && above && x <= limit)) refuse(rangeText(d));
            return;
        }
    }
}

void applySetting(RenderSettings& settings, std::string_view name, const Json& value) {
    const SettingDef& d = settingNamed(name);
    checkSetting(d, value);
    d.set(settings, value);
}

bool settingReadBy(const SettingDef& d, RenderMethod method) {
    return method == RenderMethod::Auto || d.readBy.empty() ||
           std::find(d.readBy.begin(), d.readBy.end(), method) != d.readBy.end();
}

std::string settingExpectation(const SettingDef& d) {
    switch (d.type) {
        case SettingType::Choice:
            return choiceList(d.choices);
        case SettingType::Flag:
            return "true or false";
        case SettingType::Number:
        case SettingType::Integer:
            return rangeText(d);
    }
    return "";
}

bool settingNeedMet(const SettingDef& d, const RenderSettings& settings) {
    if (!d.needs) return true;
    // The lighting settings light isosurfaces and the cut face too, shaded or not.
    if (std::string_view(d.needs) == "shade" &&
        (!settings.isoSurfaces.empty() || settings.clipSurface))
        return true;
    // The normals' gradients are the gradient opacity's too.
    if (std::string_view(d.name) == "normals" && settings.gradientOpacity.active()) return true;
    return settingNamed(d.needs).get(settings) == true;
}

void refuseUnreadSettings(const RenderSettings& settings, const std::vector<std::string>& given) {
    for (const std::string& name : given)
        if (name == "clip_surface" && settings.clipSurface && settings.clipPlanes.empty() &&
            !settings.clipBox)
            throw SettingError("clip_surface", "true",
                               "read only with clip planes or a clip box: there is no cut face");
    for (const std::string& name : given)
        if (const SettingDef* d = findSetting(name); d && !settingNeedMet(*d, settings))
            throw SettingError(
                d->name, settingValueText(d->get(settings)),
                std::string("read only with `") + d->needs + "` on" +
                    (std::string_view(d->needs) == "shade"
                         ? std::string(" or an `iso` surface or `clip_surface`") +
                               (std::string_view(d->name) == "normals" ? " or a `gradient_opacity`"
                                                                       : "")
                         : std::string()));
}

Json settingDefault(const SettingDef& d) {
    return d.get(RenderSettings{});
}

std::string cliFlag(const SettingDef& d) {
    const bool negated = d.type == SettingType::Flag && settingDefault(d) == true;
    std::string flag = std::string(negated ? "--no-" : "--") + d.name;
    for (char& c : flag)
        if (c == '_') c = '-';
    return flag;
}

Json settingsVocabularyJson() {
    Json out = Json::array();
    for (const SettingDef& d : settingsVocabulary()) {
        static const char* const kTypes[] = {"choice", "number", "integer", "flag"};
        Json readBy = Json::array();
        for (RenderMethod m : d.readBy) readBy.push_back(methodName(m));
        Json j = {{"name", d.name},
                  {"type", kTypes[int(d.type)]},
                  {"doc", d.doc},
                  {"detail", d.detail},
                  {"read_by", readBy},
                  {"default", settingDefault(d)},
                  {"tunes_adaptive", d.tunesAdaptive},
                  {"needs", d.needs ? Json(d.needs) : Json(nullptr)}};
        if (d.type == SettingType::Choice) j["choices"] = d.choices;
        if (d.type == SettingType::Number || d.type == SettingType::Integer) {
            j["min"] = d.min;
            if (std::isfinite(d.max)) j["max"] = d.max;  // else none
            j["min_open"] = d.minOpen;
        }
        out.push_back(std::move(j));
    }
    return out;
}

}  // namespace uvr
