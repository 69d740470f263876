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

/// "RGB", "Lab" or "Diverging": the name ParaView's colour-map JSON gives the space.
const char* colorSpaceName(ColorSpace space);

/// The space of one of colorSpaceName's names (exact spelling), or none.
std::optional<ColorSpace> colorSpaceFromName(const std::string& name);

/// Colour map plus piecewise-linear opacity over a normalised [0, 1] domain. The data range it is
/// applied to is chosen separately (default: the field's range).
struct TransferFunction {
    std::string name;
    ColorSpace colorSpace = ColorSpace::RGB;
    std::vector<ColorPoint> colors;       ///< sorted by x, at least one point
    std::vector<OpacityPoint> opacities;  ///< sorted by x, at least one point
    /// Data range the points were defined over when imported from ParaView JSON (informational).
    std::optional<std::pair<float, float>> sourceRange;
    /// Colour of NaN values (ParaView's NanColor; Cool to Warm's yellow unless a preset or file
    /// gives one).
    Vec3f nanColor{1.f, 1.f, 0.f};
    /// Opacity of NaN values per opacity unit (ParaView's NanOpacity); 0 keeps NaN regions
    /// invisible.
    float nanOpacity = 0.f;
    /// Map values on a log scale (ParaView's UseLogScale): position t of value v in [lo, hi] is
    /// (log10 v - log10 lo) / (log10 hi - log10 lo); the range must be positive.
    bool logScale = false;

    /// Colour at normalised position t (clamped to [0, 1]), interpolated in colorSpace.
    Vec3f colorAt(float t) const;
    /// Opacity at normalised position t (clamped), piecewise linear.
    float opacityAt(float t) const;
    /// Samples colour and opacity at n evenly spaced positions over [0, 1] (n >= 2).
    std::vector<Vec4f> bake(int n) const;
    /// The table the renderer reads (TfTableView): colour and opacity at n values evenly spaced
    /// over [lo, hi], each at its normalised position: bake(n) for a linear scale; with logScale
    /// the position of value v is (log10 v - log10 lo) / (log10 hi - log10 lo), so the table
    /// stays linear in the value and every integrator reads it unchanged (ParaView's volume
    /// mappers do the same). With logScale lo must be positive (Error(Argument) otherwise).
    std::vector<Vec4f> bakeOverRange(int n, double lo, double hi) const;
};

/// What a listing of colour maps shows of one map.
struct ColorMapInfo {
    std::string name;        ///< ParaView's name ("Cool to Warm", "Viridis (matplotlib)")
    std::string colorSpace;  ///< as ParaView writes it: "RGB", "Lab", "Diverging", "HSV", ...
    int points = 0;          ///< colour control points (0: an indexed, categorical map)
};

/// The built-in colour presets, under ParaView's names and in ParaView's order of its
/// "default" presets.
std::vector<ColorMapInfo> transferFunctionPresets();

/// Most entries logTableSize gives a log-scale table (4 MiB of entries; its range statistics
/// take about 40 bytes per entry more).
inline constexpr int kMaxLogTableSize = 1 << 18;

/// Entries of a table over [lo, hi] (0 < lo < hi) for a log-scale transfer function: enough that
/// the step from lo to the next entry spans at most 1 / (linearSize - 1) of the log range (the
/// linear table's resolution, where the log map changes fastest per value), at least
/// linearSize, at most kMaxLogTableSize.
int logTableSize(int linearSize, double lo, double hi);

/// The lowest value above which a log-scale table of n entries over [lo, hi] resolves the map as
/// finely as a linear table of linearSize entries (lo itself when n suffices).
double logTableResolvedFrom(int n, int linearSize, double lo, double hi);

/// Names of the built-in colour presets (ParaView's: "Cool to Warm", "Viridis (matplotlib)", ...).
std::vector<std::string> transferFunctionPresetNames();

/// A built-in colour preset (ParaView's control points, colour space and NanColor) with a linear
/// 0 -> 1 opacity ramp; its name is ParaView's. Matching ignores case, spaces, ',', '-', '_' and
/// parentheses ("cool-to-warm", "black_body_radiation"), and a name that matches no preset whole
/// may leave out a trailing parenthesised suffix ("Viridis" for "Viridis (matplotlib)", "Blue
/// Orange" for "Blue Orange (divergent)"); "black-body", "greyscale", "gray" and "grey" are
/// aliases. Throws Error(Argument) naming close matches for an unknown name.
TransferFunction transferFunctionPreset(const std::string& name);

/// Control points resampled from HSV interpolation into RGB points, 32 per segment; the hue runs
/// linearly from one point's to the next, or with `wrap` the shorter way round the hue circle
/// (vtkColorTransferFunction's HSVWrap; ParaView applies presets without it unless they say
/// "HSVWrap": 1).
std::vector<ColorPoint> resampleHsv(const std::vector<ColorPoint>& points, bool wrap = false);

/// The colour maps of a ParaView colour-map JSON file (an export of one map, or a presets file of
/// many), in file order; a map without RGBPoints but with IndexedColors is listed with colour
/// space "indexed" and 0 points. Throws Error(Parse) for a file that is not such JSON.
std::vector<ColorMapInfo> listParaViewColorMaps(const std::string& path);

/// Loads a map from a ParaView colour-map JSON file (an array of objects, or one object) with
/// RGBPoints (x, r, g, b, ...), optional Points (x, opacity, midpoint, sharpness, ...),
/// ColorSpace, NanColor, NanOpacity, UseLogScale and HSVWrap; positions are normalised to
/// [0, 1] over the RGBPoints range (of log10 x with UseLogScale). `name` picks the map whose
/// Name it is (else the first matching it ignoring case, spaces, '-' and '_'); without a name the
/// file must hold one map. Throws Error(Argument) for a missing or unknown name, naming the maps
/// (close ones first), and Error(Parse) naming the file and the offending key on malformed input.
TransferFunction loadParaViewColorMap(const std::string& path, const std::string& name = "");

/// loadParaViewColorMap of a document held in memory (an upload); `source` names it in errors.
TransferFunction parseParaViewColorMap(const std::vector<char>& bytes, const std::string& source,
                                       const std::string& name = "");

/// The transfer function as a ParaView colour-map JSON export (an array of one map) over the data
/// range [lo, hi]: Name, ColorSpace, RGBPoints and Points (midpoint 0.5, sharpness 0) at data
/// values (spaced on a log scale with logScale), NanColor, NanOpacity and UseLogScale. Colour
/// points are written from 0 to 1 (the end colours repeated where the map starts later or ends
/// earlier), so loadParaViewColorMap reads the same map back. Throws Error(Argument) unless
/// lo < hi, both finite, and lo > 0 with logScale.
std::string paraViewColorMapJson(const TransferFunction& tf, double lo, double hi);

/// Replaces the opacity points from a spec: "ramp" (0 -> 1), "ramp:A" (0 -> A), "constant:A",
/// "step:T[:A]" (0 below normalised T, A (default 1) at and above: a "binary" transfer function),
/// or a list "x0:a0,x1:a1,..." of normalised positions. Throws Error(Argument) on a bad spec.
void applyOpacitySpec(TransferFunction& tf, const std::string& spec);

/// A --tf value split into a ParaView colour-map file and a map name: "FILE.json" -> (FILE.json,
/// ""), "FILE.json:NAME" -> (FILE.json, NAME) (the first ".json:", any case, ends the path);
/// std::nullopt for a preset name.
std::optional<std::pair<std::string, std::string>> splitColorMapFile(const std::string& spec);

/// Loads a preset name, a ParaView colour-map file "FILE.json" (holding one map) or a map of a
/// presets file "FILE.json:NAME" (loadParaViewColorMap).
TransferFunction loadTransferFunction(const std::string& presetOrPath);

/// CIE L*a*b* (D65 white, via linear sRGB and XYZ) of an sRGB colour with components in [0, 1].
Vec3f srgbToLab(Vec3f rgb);

/// sRGB colour, clamped to [0, 1], of a CIE L*a*b* (D65 white) colour; inverse of srgbToLab.
Vec3f labToSrgb(Vec3f lab);

/// Colour between sRGB colours a (f = 0) and b (f = 1) interpolated in the given colour space;
/// Diverging follows Moreland 2009's Msh interpolation through an unsaturated midpoint.
Vec3f interpolateColor(ColorSpace space, Vec3f a, Vec3f b, float f);

}  // namespace uvr
