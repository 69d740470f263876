// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uvr/core/vec.h"

namespace uvr {

/// A colour control point at normalised position x in [0, 1].
struct ColorPoint {
    float x = 0.f;
    Vec3f rgb;
};

/// An opacity control point at normalised position x in [0, 1]; alpha in [0, 1] is the opacity
/// per opacity unit distance (ParaView's ScalarOpacityUnitDistance convention).
struct OpacityPoint {
    float x = 0.f;
    float alpha = 0.f;
};

/// Colour space in which colours between control points are interpolated (as ParaView does).
enum class ColorSpace { RGB, Lab, Diverging };

/// Colour map plus piecewise-linear opacity over a normalised [0, 1] domain. The data range it is
/// applied to is chosen separately (default: the field's range).
struct TransferFunction {
    std::string name;
    ColorSpace colorSpace = ColorSpace::RGB;
    std::vector<ColorPoint> colors;       ///< sorted by x, at least one point
    std::vector<OpacityPoint> opacities;  ///< sorted by x, at least one point
    /// Data range the points were defined over when imported from ParaView JSON (informational).
    std::optional<std::pair<float, float>> sourceRange;

    /// Colour at normalised position t (clamped to [0, 1]), interpolated in colorSpace.
    Vec3f colorAt(float t) const;
    /// Opacity at normalised position t (clamped), piecewise linear.
    float opacityAt(float t) const;
    /// Samples colour and opacity at n evenly spaced positions over [0, 1] (n >= 2).
    std::vector<Vec4f> bake(int n) const;
};

/// Names of the built-in colour presets ("cool-to-warm", "viridis", "black-body", "grayscale",
/// ...).
std::vector<std::string> transferFunctionPresetNames();

/// A built-in colour preset with a linear 0 -> 1 opacity ramp; throws Error(Argument) naming the
/// valid presets for an unknown name. Matching ignores case, spaces, '-' and '_', so ParaView's
/// names ("Cool to Warm", "Black-Body Radiation", "Viridis (matplotlib)") work too.
TransferFunction transferFunctionPreset(const std::string& name);

/// Loads a ParaView colour-map JSON export (an array of objects, or one object) with RGBPoints
/// (x, r, g, b, ...) and optional Points (x, opacity, midpoint, sharpness, ...) and ColorSpace;
/// positions are normalised to [0, 1] over the RGBPoints range. Throws Error(Parse) naming the
/// file and the offending key on malformed input.
TransferFunction loadParaViewColorMap(const std::string& path);

/// Replaces the opacity points from a spec: "ramp" (0 -> 1), "ramp:A" (0 -> A), "constant:A",
/// "step:T[:A]" (0 below normalised T, A (default 1) at and above: a "binary" transfer function),
/// or a list "x0:a0,x1:a1,..." of normalised positions. Throws Error(Argument) on a bad spec.
void applyOpacitySpec(TransferFunction& tf, const std::string& spec);

/// Loads a preset name or, when the string names an existing .json file, a ParaView export.
TransferFunction loadTransferFunction(const std::string& presetOrPath);

/// CIE L*a*b* (D65 white, via linear sRGB and XYZ) of an sRGB colour with components in [0, 1].
Vec3f srgbToLab(Vec3f rgb);

/// sRGB colour, clamped to [0, 1], of a CIE L*a*b* (D65 white) colour; inverse of srgbToLab.
Vec3f labToSrgb(Vec3f lab);

/// Colour between sRGB colours a (f = 0) and b (f = 1) interpolated in the given colour space;
/// Diverging follows Moreland 2009's Msh interpolation through an unsaturated midpoint.
Vec3f interpolateColor(ColorSpace space, Vec3f a, Vec3f b, float f);

}  // namespace uvr
