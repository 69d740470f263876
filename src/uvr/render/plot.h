// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <vector>

#include "uvr/core/vec.h"
#include "uvr/render/image.h"

namespace uvr {

/// One line of a plot: points (x[i], y[i]) joined in order, drawn with markers.
struct PlotSeries {
    std::string label;
    std::vector<double> x, y;
    Vec3f color{0.f, 0.f, 0.f};
    bool rightAxis = false;  ///< scaled against the right y axis instead of the left
};

/// A line chart with a title, axis labels, ticks with numbers, a legend, and up to two y axes.
struct PlotSpec {
    std::string title;
    std::string xLabel, yLabel, yRightLabel;
    std::vector<PlotSeries> series;
    int width = 800, height = 500;
};

/// Rasterises the chart into an opaque image (white background) using a built-in bitmap font;
/// axis ranges are padded "nice" ranges covering the data.
Image renderPlot(const PlotSpec& spec);

/// Width of one glyph cell of the built-in font at scale 1: 5 pixels of glyph, 1 of spacing.
inline constexpr int kGlyphAdvance = 6;
/// Height of a glyph of the built-in font at scale 1.
inline constexpr int kGlyphHeight = 7;

/// Width in pixels of `text` drawn by drawText at `scale` (no trailing spacing).
int textWidth(const std::string& text, int scale = 1);

/// Tick marks of one axis: lo, lo + step, ..., hi, with step 1, 2 or 5 times a power of ten.
struct AxisTicks {
    double lo = 0.0, hi = 1.0, step = 0.2;  ///< first tick, last tick, spacing
    /// Number of ticks from lo to hi inclusive.
    int count() const;
    /// The i-th tick value (exactly 0 where rounding would give a tiny residue).
    double value(int i) const;
};

/// "Nice" ticks covering [dataMin, dataMax] with about targetCount ticks (Heckbert, "Nice
/// Numbers for Graph Labels", Graphics Gems 1990); an empty or non-finite range, or one beyond
/// double precision, gets [0, 1], a single value a range around it.
AxisTicks niceTicks(double dataMin, double dataMax, int targetCount = 6);

/// Formats a tick value with as many decimals as the step needs.
std::string formatTick(double value, double step);

/// The layout renderPlot uses: the plot area's pixel box (the axis lines lie on its edges) and
/// the ticks of each axis; data (x, y) maps linearly onto pixel centres, x.lo to column left and
/// y.lo to row bottom.
struct PlotFrame {
    int left = 0, top = 0, right = 0, bottom = 0;  ///< plot area, inclusive pixel bounds
    AxisTicks x, y, yRight;                        ///< bottom, left and right axes
    bool hasRightAxis = false;                     ///< true when some series has rightAxis set
};

/// Computes the layout of a plot; throws Error(Argument) for a size below 160x120, series whose
/// x and y differ in length, or a plot area too small for the labels.
PlotFrame plotFrame(const PlotSpec& spec);

/// Draws text at (x, y) (top-left of the first glyph) with the built-in 5x7 bitmap font scaled by
/// `scale`; ASCII 32..126, others drawn as '?'.
void drawText(Image& image, int x, int y, const std::string& text, Vec3f color, int scale = 1);

}  // namespace uvr
