// SPDX-License-Identifier: MIT
#include "uvr/render/heatmap.h"

#include <algorithm>
#include <cmath>

#include "uvr/core/error.h"

namespace uvr {

namespace {

/// Control points (t, r, g, b) of the colour ramp; luminance rises at each point.
struct RampPoint {
    float t;
    Vec3f color;
};
const RampPoint kRamp[] = {
    {0.00f, {0.00f, 0.00f, 0.00f}}, {0.15f, {0.16f, 0.04f, 0.33f}}, {0.35f, {0.47f, 0.11f, 0.43f}},
    {0.55f, {0.78f, 0.24f, 0.31f}}, {0.75f, {0.97f, 0.52f, 0.09f}}, {0.90f, {0.98f, 0.80f, 0.20f}},
    {1.00f, {0.99f, 1.00f, 0.64f}},
};

/// Legend layout inside the kHeatmapLegendWidth margin.
constexpr int kBarGap = 8;
constexpr int kBarWidth = 20;
constexpr int kTickLength = 4;
constexpr int kBarMarginY = 8;

const Vec3f kTickColor(1.f, 1.f, 1.f);
const Vec3f kBarBorder(0.5f, 0.5f, 0.5f);

void fill(Image& image, int x0, int y0, int x1, int y1, Vec3f c) {
    for (int y = std::max(y0, 0); y <= std::min(y1, image.height - 1); ++y)
        for (int x = std::max(x0, 0); x <= std::min(x1, image.width - 1); ++x)
            image.at(x, y) = Vec4f(c.x, c.y, c.z, 1.f);
}

}  // namespace

Vec3f heatmapColor(float t) {
    t = t > 0.f ? (t < 1.f ? t : 1.f) : 0.f;  // NaN becomes 0
    for (size_t i = 1; i < std::size(kRamp); ++i) {
        if (t <= kRamp[i].t) {
            const float u = (t - kRamp[i - 1].t) / (kRamp[i].t - kRamp[i - 1].t);
            return kRamp[i - 1].color * (1.f - u) + kRamp[i].color * u;
        }
    }
    return kRamp[std::size(kRamp) - 1].color;
}

Image sampleHeatmap(const std::vector<std::uint32_t>& counts, int width, int height,
                    std::uint32_t maxCount) {
    constexpr int kMaxSide = 65536;
    if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide ||
        counts.size() != static_cast<size_t>(width) * height) {
        throwError(ErrorKind::Argument, "",
                   "sample-count buffer has " + std::to_string(counts.size()) + " counts for a " +
                       std::to_string(width) + "x" + std::to_string(height) +
                       " heat map; expected width * height counts, each side 1..65536");
    }
    // Step 1: the scale's top (the largest count when not given) and the coloured counts.
    std::uint32_t top = maxCount;
    if (top == 0) top = std::max<std::uint32_t>(1, *std::max_element(counts.begin(), counts.end()));
    Image image(width + kHeatmapLegendWidth, height);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const std::uint32_t c = std::min(counts[static_cast<size_t>(y) * width + x], top);
            const Vec3f color =
                c == 0 ? Vec3f(0.f, 0.f, 0.f)
                       : heatmapColor(static_cast<float>(static_cast<double>(c) / top));
            image.at(x, y) = Vec4f(color.x, color.y, color.z, 1.f);
        }
    }
    fill(image, width, 0, image.width - 1, height - 1, Vec3f(0.f, 0.f, 0.f));

    // Step 2: the colour bar, maxCount at its top row and 0 at its bottom row, framed in grey.
    const int barTop = height >= 3 * kBarMarginY ? kBarMarginY : 0;
    const int barBottom = height - 1 - barTop;
    const int barLeft = width + kBarGap, barRight = barLeft + kBarWidth - 1;
    const int span = std::max(barBottom - barTop, 1);
    fill(image, barLeft - 1, barTop - 1, barRight + 1, barBottom + 1, kBarBorder);
    for (int y = barTop; y <= barBottom; ++y) {
        const Vec3f color = heatmapColor(static_cast<float>(barBottom - y) / span);
        fill(image, barLeft, y, barRight, y, color);
    }

    // Step 3: tick marks at 0, the middle and the top of the scale (numbers are left to the
    // caller: the CLI logs the scale, bench/plot_bench.py draws a labelled colour bar).
    std::vector<std::uint32_t> ticks = {0};
    if (top / 2 > 0 && top / 2 < top) ticks.push_back(top / 2);
    ticks.push_back(top);
    for (std::uint32_t v : ticks) {
        const int y =
            barBottom - static_cast<int>(std::lround(static_cast<double>(v) / top * span));
        fill(image, barRight + 1, y, barRight + kTickLength, y, kTickColor);
    }
    return image;
}

}  // namespace uvr
