// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/render/image.h"

namespace uvr {

/// Colours a per-pixel sample-count buffer as a heat map (Morrical et al. 2019, Fig. 5): counts
/// 0..maxCount mapped through a perceptual colour map (0 black), with a colour bar and its
/// numeric scale (0, the middle and maxCount) drawn along the right edge. maxCount 0 means the
/// largest count in the buffer, so two heat maps are comparable only when given the same maxCount.
Image sampleHeatmap(const std::vector<std::uint32_t>& counts, int width, int height,
                    std::uint32_t maxCount = 0);

}  // namespace uvr
