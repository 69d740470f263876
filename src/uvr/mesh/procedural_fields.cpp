// SPDX-License-Identifier: MIT
// The procedural fields (constant, linear, jet, Marschner-Lobb, multiscale) and the names of the
// procedural shapes and fields.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "uvr/core/error.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/procedural_detail.h"

namespace uvr {

namespace {

using namespace procedural_detail;

constexpr double kPi = std::numbers::pi;

// Value and gradient noise.

/// Hash of an integer lattice point for the noise functions.
std::uint64_t latticeHash(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
    std::uint64_t h = mix64(static_cast<std::uint64_t>(ix) + 0x632be59bd9b4e019ull);
    h = mix64(h ^ static_cast<std::uint64_t>(iy));
    return mix64(h ^ static_cast<std::uint64_t>(iz));
}

/// Gradient noise in the manner of Perlin (2002, "Improving Noise"): pseudo-random gradients from
/// the 12 cube-edge directions at lattice points, blended with the quintic fade 6t^5-15t^4+10t^3.
/// Smooth (C2), zero at lattice points, roughly in [-1, 1].
double gradientNoise(double x, double y, double z) {
    static constexpr int kGrad[12][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                         {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                         {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}};
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
               iz = static_cast<std::int64_t>(fz);
    const double tx = x - fx, ty = y - fy, tz = z - fz;
    auto fade = [](double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); };
    auto corner = [&](int dx, int dy, int dz) {
        const int* g = kGrad[latticeHash(ix + dx, iy + dy, iz + dz) % 12];
        return g[0] * (tx - dx) + g[1] * (ty - dy) + g[2] * (tz - dz);
    };
    const double u = fade(tx), v = fade(ty), w = fade(tz);
    auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
    const double x00 = lerp(corner(0, 0, 0), corner(1, 0, 0), u);
    const double x10 = lerp(corner(0, 1, 0), corner(1, 1, 0), u);
    const double x01 = lerp(corner(0, 0, 1), corner(1, 0, 1), u);
    const double x11 = lerp(corner(0, 1, 1), corner(1, 1, 1), u);
    return lerp(lerp(x00, x10, v), lerp(x01, x11, v), w);
}

/// Fractal Brownian motion: `octaves` octaves of gradient noise, each at twice the frequency and
/// `gain` times the amplitude of the previous; normalised to roughly [-1, 1].
double fbm(double x, double y, double z, int octaves, double gain = 0.5) {
    double sum = 0.0, amplitude = 1.0, norm = 0.0;
    for (int o = 0; o < octaves; ++o) {
        sum += amplitude * gradientNoise(x, y, z);
        norm += amplitude;
        amplitude *= gain;
        x = 2.0 * x + 17.13;  // shift each octave so lattice zeros do not line up
        y = 2.0 * y + 5.71;
        z = 2.0 * z + 11.37;
    }
    return sum / norm;
}

/// A turbulent plume: a Gaussian jet rising along +y from y = -1, its width growing with height,
/// its axis meandering and its edge broken up by fractal noise; values in [0, 1].
double jetValue(double x, double y, double z) {
    const double h = std::clamp((y + 1.0) * 0.5, 0.0, 1.0);  // 0 at the nozzle, 1 at the top
    // Meandering axis: low-frequency noise whose amplitude grows with height.
    const double ox = 0.3 * h * gradientNoise(0.3, 1.6 * y + 0.5, 4.7);
    const double oz = 0.3 * h * gradientNoise(7.9, 1.6 * y + 2.5, 0.3);
    const double width = 0.08 + 0.32 * h;
    const double dx = x - ox, dz = z - oz;
    // Turbulence: distorts the radius and modulates the intensity, stronger higher up.
    const double turb = fbm(3.0 * x + 1.3, 3.0 * y - 0.7, 3.0 * z + 2.1, 4);
    const double r = std::sqrt(dx * dx + dz * dz) * (1.0 + 0.6 * h * turb);
    const double core = std::exp(-(r * r) / (width * width));
    const double intensity = (1.0 - 0.5 * h) * (1.0 + 0.5 * turb);
    return std::clamp(core * intensity, 0.0, 1.0);
}

/// The multiscale field: octaves of gradient noise from wavelength 1 (half the domain) down to
/// cellSize, each 1/sqrt(2) of the previous in amplitude; values in [0, 1].
double multiscaleValue(double x, double y, double z, double cellSize) {
    int octaves = 8;
    if (cellSize > 0.0)
        octaves = std::clamp(static_cast<int>(std::ceil(-std::log2(cellSize))) + 1, 1, 30);
    return std::clamp(0.5 + 1.2 * fbm(x + 0.37, y + 0.61, z + 0.13, octaves, std::sqrt(0.5)), 0.0,
                      1.0);
}

/// Marschner & Lobb (1994), "An evaluation of reconstruction filters for volume rendering",
/// eq. 3 with alpha = 0.25 and f_M = 6, over [-1, 1]^3; values in [0, 1].
double marschnerLobbValue(double x, double y, double z) {
    constexpr double kAlpha = 0.25, kFm = 6.0;
    const double r = std::sqrt(x * x + y * y);
    const double rhoR = std::cos(2.0 * kPi * kFm * std::cos(kPi * r / 2.0));
    return (1.0 - std::sin(kPi * z / 2.0) + kAlpha * (1.0 + rhoR)) / (2.0 * (1.0 + kAlpha));
}

}  // namespace

double proceduralCellSize(const ProceduralSpec& spec) {
    return 2.0 / std::cbrt(std::max(1.0, static_cast<double>(spec.targetCells) / 6.0));
}

float proceduralFieldValue(ProceduralField field, Vec3f p, double cellSize) {
    const double x = p.x, y = p.y, z = p.z;
    switch (field) {
        case ProceduralField::Constant:
            return 1.f;
        case ProceduralField::Linear:
            return static_cast<float>(x + 2.0 * y - z);
        case ProceduralField::Jet:
            return static_cast<float>(jetValue(x, y, z));
        case ProceduralField::MarschnerLobb:
            return static_cast<float>(marschnerLobbValue(x, y, z));
        case ProceduralField::Multiscale:
            return static_cast<float>(multiscaleValue(x, y, z, cellSize));
    }
    return 0.f;
}

const char* proceduralFieldName(ProceduralField field) {
    switch (field) {
        case ProceduralField::Constant:
            return "constant";
        case ProceduralField::Linear:
            return "linear";
        case ProceduralField::Jet:
            return "jet";
        case ProceduralField::MarschnerLobb:
            return "marschner_lobb";
        case ProceduralField::Multiscale:
            return "multiscale";
    }
    return "?";
}

const char* proceduralShapeName(ProceduralShape shape) {
    switch (shape) {
        case ProceduralShape::Box:
            return "box";
        case ProceduralShape::Shell:
            return "shell";
        case ProceduralShape::Graded:
            return "graded";
    }
    return "?";
}

ProceduralShape parseProceduralShape(const std::string& name) {
    for (ProceduralShape s :
         {ProceduralShape::Box, ProceduralShape::Shell, ProceduralShape::Graded})
        if (name == proceduralShapeName(s)) return s;
    throwError(ErrorKind::Argument, "",
               "unknown procedural shape '" + name + "': expected box, shell or graded");
}

ProceduralField parseProceduralField(const std::string& name) {
    for (ProceduralField f :
         {ProceduralField::Constant, ProceduralField::Linear, ProceduralField::Jet,
          ProceduralField::MarschnerLobb, ProceduralField::Multiscale})
        if (name == proceduralFieldName(f)) return f;
    throwError(ErrorKind::Argument, "",
               "unknown procedural field '" + name +
                   "': expected constant, linear, jet, marschner_lobb or multiscale");
}

}  // namespace uvr
