// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/core/vec.h"
#include "uvr/render/image.h"

namespace uvr {

/// Width in pixels of the legend margin sampleHeatmap adds to the right of the heat map.
inline constexpr int kHeatmapLegendWidth = 40;

/// The heat map's colour at t in [0, 1] (clamped; NaN as 0): an inferno-like piecewise-linear
/// ramp from black through purple, red and orange to pale yellow whose luminance strictly rises.
Vec3f heatmapColor(float t);

/// Colours a per-pixel sample-count buffer as a heat map (Morrical et al. 2019, Fig. 5): counts
/// 0..maxCount mapped through a perceptual colour map (0 black), with a colour bar along the
/// right edge, maxCount at its top row and 0 at its bottom row, and tick marks at 0, the middle
/// and maxCount (no numbers: drawing text is not this library's job; callers state the scale).
/// maxCount 0 means the largest count in the buffer (at least 1), so two heat maps are comparable
/// only when given the same maxCount; larger counts are clamped to it. The returned image is opaque
/// and width + kHeatmapLegendWidth pixels wide and height tall: pixel (x, y) of the buffer is image
/// pixel (x, y), the legend fills the columns from width on. Throws Error(Argument) when the buffer
/// does not hold width * height counts.
Image sampleHeatmap(const std::vector<std::uint32_t>& counts, int width, int height,
                    std::uint32_t maxCount = 0);

}  // namespace uvr
