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

/// Draws text at (x, y) (top-left of the first glyph) with the built-in 5x7 bitmap font scaled by
/// `scale`; ASCII 32..126, others drawn as '?'.
void drawText(Image& image, int x, int y, const std::string& text, Vec3f color, int scale = 1);

}  // namespace uvr
