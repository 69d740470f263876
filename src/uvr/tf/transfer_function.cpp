// SPDX-License-Identifier: MIT
#include "uvr/tf/transfer_function.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/setting_error.h"
#include "uvr/core/text.h"

namespace uvr {

namespace {

struct Vec3d {
    double x, y, z;
};

float clamp01(float v) {
    return v < 0.f ? 0.f : (v > 1.f ? 1.f : v);
}

/// Index i of the segment [x_i, x_{i+1}) holding t in a sorted point list, with the weight of
/// point i+1; i = -1 before the first point and i = n-1 at or after the last.
template <typename Point>
int findSegment(const std::vector<Point>& points, float t, float& w) {
    auto it = std::upper_bound(points.begin(), points.end(), t,
                               [](float v, const Point& p) { return v < p.x; });
    int j = static_cast<int>(it - points.begin());
    w = 0.f;
    if (j == 0) return -1;
    int n = static_cast<int>(points.size());
    if (j == n) return n - 1;
    int i = j - 1;
    w = (t - points[i].x) / (points[j].x - points[i].x);  // x_j > t >= x_i, so no zero division
    return i;
}

// sRGB <-> linear sRGB (IEC 61966-2-1 transfer curve).
double srgbToLinear(double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}
double linearToSrgb(double c) {
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

// D65 reference white, as VTK's vtkMath::XYZToLab uses it.
constexpr double kWhiteX = 0.9505;
constexpr double kWhiteY = 1.0;
constexpr double kWhiteZ = 1.089;

double labF(double t) {
    return t > 0.008856 ? std::cbrt(t) : 7.787 * t + 16.0 / 116.0;
}
double labFInverse(double f) {
    double t = f * f * f;
    return t > 0.008856 ? t : (f - 16.0 / 116.0) / 7.787;
}

Vec3d srgbToLabD(Vec3f rgb) {
    double r = srgbToLinear(rgb.x), g = srgbToLinear(rgb.y), b = srgbToLinear(rgb.z);
    double x = 0.4124 * r + 0.3576 * g + 0.1805 * b;
    double y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    double z = 0.0193 * r + 0.1192 * g + 0.9505 * b;
    double fx = labF(x / kWhiteX), fy = labF(y / kWhiteY), fz = labF(z / kWhiteZ);
    return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

Vec3f labToSrgbD(Vec3d lab) {
    double fy = (lab.x + 16.0) / 116.0;
    double fx = fy + lab.y / 500.0;
    double fz = fy - lab.z / 200.0;
    double x = kWhiteX * labFInverse(fx), y = kWhiteY * labFInverse(fy),
           z = kWhiteZ * labFInverse(fz);
    double r = 3.2406 * x - 1.5372 * y - 0.4986 * z;
    double g = -0.9689 * x + 1.8758 * y + 0.0415 * z;
    double b = 0.0557 * x - 0.2040 * y + 1.0570 * z;
    return {clamp01(static_cast<float>(linearToSrgb(r))),
            clamp01(static_cast<float>(linearToSrgb(g))),
            clamp01(static_cast<float>(linearToSrgb(b)))};
}

// Moreland 2009, "Diverging Color Maps for Scientific Visualization", Sec. 4: the Msh polar form
// of L*a*b* (magnitude M, saturation s, hue h).
Vec3d labToMsh(Vec3d lab) {
    double m = std::sqrt(lab.x * lab.x + lab.y * lab.y + lab.z * lab.z);
    double s = m > 0.0 ? std::acos(std::clamp(lab.x / m, -1.0, 1.0)) : 0.0;
    double h = std::atan2(lab.z, lab.y);
    return {m, s, h};
}
Vec3d mshToLab(Vec3d msh) {
    return {msh.x * std::cos(msh.y), msh.x * std::sin(msh.y) * std::cos(msh.z),
            msh.x * std::sin(msh.y) * std::sin(msh.z)};
}

// Moreland 2009, "AdjustHue": the hue to give an unsaturated colour of magnitude mUnsat so that
// the interpolation towards the saturated colour (mSat, sSat, hSat) spins the hue smoothly.
double adjustHue(double mSat, double sSat, double hSat, double mUnsat) {
    if (mSat >= mUnsat) return hSat;
    double spin = sSat * std::sqrt(mUnsat * mUnsat - mSat * mSat) / (mSat * std::sin(sSat));
    return hSat > -std::numbers::pi / 3.0 ? hSat + spin : hSat - spin;
}

// Moreland 2009, "InterpolateColor": Msh interpolation, through an unsaturated white of
// magnitude max(M1, M2, 88) when both ends are saturated with hues more than pi/3 apart.
Vec3f interpolateDiverging(Vec3f a, Vec3f b, double f) {
    constexpr double kUnsaturated = 0.05;
    Vec3d m1 = labToMsh(srgbToLabD(a));
    Vec3d m2 = labToMsh(srgbToLabD(b));
    if (m1.y > kUnsaturated && m2.y > kUnsaturated &&
        std::abs(m1.z - m2.z) > std::numbers::pi / 3.0) {
        double mMid = std::max({m1.x, m2.x, 88.0});
        if (f < 0.5) {
            m2 = {mMid, 0.0, 0.0};
            f = 2.0 * f;
        } else {
            m1 = {mMid, 0.0, 0.0};
            f = 2.0 * f - 1.0;
        }
    }
    if (m1.y < kUnsaturated && m2.y > kUnsaturated) {
        m1.z = adjustHue(m2.x, m2.y, m2.z, m1.x);
    } else if (m2.y < kUnsaturated && m1.y > kUnsaturated) {
        m2.z = adjustHue(m1.x, m1.y, m1.z, m2.x);
    }
    Vec3d mid{(1.0 - f) * m1.x + f * m2.x, (1.0 - f) * m1.y + f * m2.y,
              (1.0 - f) * m1.z + f * m2.z};
    return labToSrgbD(mshToLab(mid));
}

[[noreturn]] void badSpec(const std::string& spec, const std::string& why) {
    throw SettingError("opacity", "\"" + printableShort(spec, 60) + "\"",
                       printableShort(why, 100) +
                           "; expected \"ramp\", \"ramp:A\", \"constant:A\", \"step:T[:A]\" or "
                           "\"x0:a0,x1:a1,...\" with numbers in [0, 1]");
}

/// Parses a whole string as a finite number in [0, 1].
float parseUnit(const std::string& spec, const std::string& text) {
    if (text.empty()) badSpec(spec, "missing number");
    const char* begin = text.c_str();
    char* end = nullptr;
    errno = 0;
    double v = std::strtod(begin, &end);
    if (end == begin || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        badSpec(spec, "\"" + text + "\" is not a number");
    if (v < 0.0 || v > 1.0) badSpec(spec, "\"" + text + "\" is outside [0, 1]");
    return static_cast<float>(v);
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> parts;
    size_t start = 0;
    while (true) {
        size_t pos = s.find(sep, start);
        parts.push_back(s.substr(start, pos - start));
        if (pos == std::string::npos) return parts;
        start = pos + 1;
    }
}

}  // namespace

Vec3f srgbToLab(Vec3f rgb) {
    Vec3d lab = srgbToLabD(rgb);
    return {static_cast<float>(lab.x), static_cast<float>(lab.y), static_cast<float>(lab.z)};
}

Vec3f labToSrgb(Vec3f lab) {
    return labToSrgbD({lab.x, lab.y, lab.z});
}

Vec3f interpolateColor(ColorSpace space, Vec3f a, Vec3f b, float f) {
    switch (space) {
        case ColorSpace::Lab: {
            Vec3d la = srgbToLabD(a), lb = srgbToLabD(b);
            double g = f;
            return labToSrgbD(
                {la.x + g * (lb.x - la.x), la.y + g * (lb.y - la.y), la.z + g * (lb.z - la.z)});
        }
        case ColorSpace::Diverging:
            return interpolateDiverging(a, b, f);
        case ColorSpace::RGB:
            break;
    }
    return a * (1.f - f) + b * f;
}

Vec3f TransferFunction::colorAt(float t) const {
    if (colors.empty()) return Vec3f(0.f);
    t = clamp01(std::isnan(t) ? 0.f : t);
    float w = 0.f;
    int i = findSegment(colors, t, w);
    if (i < 0) return colors.front().rgb;
    if (i >= static_cast<int>(colors.size()) - 1) return colors.back().rgb;
    if (w <= 0.f) return colors[i].rgb;
    return interpolateColor(colorSpace, colors[i].rgb, colors[i + 1].rgb, w);
}

float TransferFunction::opacityAt(float t) const {
    if (opacities.empty()) return 0.f;
    t = clamp01(std::isnan(t) ? 0.f : t);
    float w = 0.f;
    int i = findSegment(opacities, t, w);
    if (i < 0) return opacities.front().alpha;
    if (i >= static_cast<int>(opacities.size()) - 1) return opacities.back().alpha;
    return opacities[i].alpha * (1.f - w) + opacities[i + 1].alpha * w;
}

std::vector<Vec4f> TransferFunction::bake(int n) const {
    if (n < 2) {
        throwError(ErrorKind::Argument, "",
                   "transfer function table size must be at least 2, got " + std::to_string(n));
    }
    std::vector<Vec4f> table(static_cast<size_t>(n));
    for (int k = 0; k < n; ++k) {
        float t = static_cast<float>(k) / static_cast<float>(n - 1);
        Vec3f c = colorAt(t);
        table[k] = Vec4f(c.x, c.y, c.z, opacityAt(t));
    }
    return table;
}

std::vector<Vec4f> TransferFunction::bakeOverRange(int n, double lo, double hi) const {
    if (!logScale) return bake(n);
    if (n < 2) {
        throwError(ErrorKind::Argument, "",
                   "transfer function table size must be at least 2, got " + std::to_string(n));
    }
    if (!(lo > 0.0) || !(hi >= lo) || !std::isfinite(hi))
        throwError(ErrorKind::Argument, "",
                   "`log` needs a positive value range, got [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]");
    std::vector<Vec4f> table(static_cast<size_t>(n));
    const double logLo = std::log10(lo), logWidth = std::log10(hi) - logLo;
    for (int k = 0; k < n; ++k) {
        const double v = lo + (hi - lo) * (static_cast<double>(k) / (n - 1));
        const float t =
            logWidth > 0.0 ? static_cast<float>((std::log10(v) - logLo) / logWidth) : 0.f;
        const Vec3f c = colorAt(t);
        table[k] = Vec4f(c.x, c.y, c.z, opacityAt(t));
    }
    return table;
}

int logTableSize(int linearSize, double lo, double hi) {
    if (!(lo > 0.0) || !(hi > lo) || !std::isfinite(hi)) return linearSize;
    // The first step h from lo spans log10(1 + h / lo) / log10(hi / lo) of the log range.
    const double span = std::log10(hi / lo) / (linearSize - 1);
    const double h = lo * (std::pow(10.0, span) - 1.0);
    const double n = std::ceil((hi - lo) / h) + 1.0;
    return static_cast<int>(std::clamp(n, double(linearSize), double(kMaxLogTableSize)));
}

double logTableResolvedFrom(int n, int linearSize, double lo, double hi) {
    if (!(lo > 0.0) || !(hi > lo) || n < 2) return lo;
    // The value v whose step h = (hi - lo) / (n - 1) spans 1 / (linearSize - 1) of the range.
    const double h = (hi - lo) / (n - 1);
    const double span = std::log10(hi / lo) / (linearSize - 1);
    return std::max(lo, h / (std::pow(10.0, span) - 1.0));
}

void applyOpacitySpec(TransferFunction& tf, const std::string& spec) {
    if (spec.empty()) badSpec(spec, "empty spec");
    std::vector<OpacityPoint> points;
    std::vector<std::string> fields = split(spec, ':');
    const std::string& kind = fields[0];
    if (kind == "ramp") {
        if (fields.size() > 2) badSpec(spec, "too many fields");
        float a = fields.size() == 2 ? parseUnit(spec, fields[1]) : 1.f;
        points = {{0.f, 0.f}, {1.f, a}};
    } else if (kind == "constant") {
        if (fields.size() != 2) badSpec(spec, "\"constant\" takes one opacity");
        float a = parseUnit(spec, fields[1]);
        points = {{0.f, a}, {1.f, a}};
    } else if (kind == "step") {
        if (fields.size() < 2 || fields.size() > 3) badSpec(spec, "\"step\" takes T and [A]");
        float t = parseUnit(spec, fields[1]);
        float a = fields.size() == 3 ? parseUnit(spec, fields[2]) : 1.f;
        // Both points at T make the function jump there; opacityAt(T) takes the upper value.
        points = {{0.f, 0.f}, {t, 0.f}, {t, a}, {1.f, a}};
    } else {
        for (const std::string& item : split(spec, ',')) {
            std::vector<std::string> xa = split(item, ':');
            if (xa.size() != 2) badSpec(spec, "list item \"" + item + "\" is not x:a");
            OpacityPoint p{parseUnit(spec, xa[0]), parseUnit(spec, xa[1])};
            if (!points.empty() && p.x < points.back().x)
                badSpec(spec, "positions must not decrease (\"" + item + "\")");
            points.push_back(p);
        }
    }
    tf.opacities = std::move(points);
}

std::optional<std::pair<std::string, std::string>> splitColorMapFile(const std::string& spec) {
    std::string low = spec;
    for (char& c : low) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const size_t colon = low.find(".json:");
    if (colon != std::string::npos)
        return std::make_pair(spec.substr(0, colon + 5), spec.substr(colon + 6));
    if (fileExtension(spec) == ".json") return std::make_pair(spec, std::string());
    return std::nullopt;
}

TransferFunction loadTransferFunction(const std::string& presetOrPath) {
    const auto file = splitColorMapFile(presetOrPath);
    if (!file) return transferFunctionPreset(presetOrPath);
    const auto& [path, name] = *file;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throwError(ErrorKind::Io, path,
                   "no such file (expected a ParaView colour-map JSON export; `uvr presets` "
                   "lists the built-in presets)");
    if (file->second.empty() && presetOrPath.size() > path.size())
        throwError(ErrorKind::Argument, path,
                   "empty colour-map name after ':' in `tf` " + presetOrPath);
    return loadParaViewColorMap(path, name);
}

const char* colorSpaceName(ColorSpace space) {
    switch (space) {
        case ColorSpace::Lab:
            return "Lab";
        case ColorSpace::Diverging:
            return "Diverging";
        default:
            return "RGB";
    }
}

std::optional<ColorSpace> colorSpaceFromName(const std::string& name) {
    for (ColorSpace c : {ColorSpace::RGB, ColorSpace::Lab, ColorSpace::Diverging})
        if (name == colorSpaceName(c)) return c;
    return std::nullopt;
}

}  // namespace uvr
