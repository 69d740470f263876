// SPDX-License-Identifier: MIT
// Sample-count heat maps: monotonic brightness, black for 0, clamping, the legend margin.
#include "uvr/render/heatmap.h"

#include <gtest/gtest.h>

#include <cmath>

#include "uvr/core/error.h"

namespace uvr {
namespace {

float luminance(const Vec4f& p) {
    return 0.2126f * p.x + 0.7152f * p.y + 0.0722f * p.z;
}

bool isBlack(const Vec4f& p) {
    return p.x == 0.f && p.y == 0.f && p.z == 0.f && p.w == 1.f;
}

TEST(Heatmap, ColourRampIsMonotonicAndStartsBlack) {
    const Vec3f zero = heatmapColor(0.f);
    EXPECT_EQ(zero, Vec3f(0.f, 0.f, 0.f));
    EXPECT_EQ(heatmapColor(NAN), zero);
    EXPECT_EQ(heatmapColor(-1.f), zero);
    EXPECT_EQ(heatmapColor(2.f), heatmapColor(1.f));
    float previous = -1.f;
    for (int i = 0; i <= 1000; ++i) {
        const Vec3f c = heatmapColor(i / 1000.f);
        const float lum = luminance(Vec4f(c.x, c.y, c.z, 1.f));
        EXPECT_GT(lum, previous) << i;
        previous = lum;
        for (int k = 0; k < 3; ++k) {
            EXPECT_GE(c[k], 0.f);
            EXPECT_LE(c[k], 1.f);
        }
    }
    // Hot end: a bright yellow-white, red and green well above blue.
    const Vec3f hot = heatmapColor(1.f);
    EXPECT_GT(hot.x, 0.9f);
    EXPECT_GT(hot.y, 0.9f);
    EXPECT_LT(hot.z, hot.y);
}

TEST(Heatmap, MoreSamplesAreBrighterAndMaxCountClamps) {
    // One row of counts 0..20 then 50 and 1000, with maxCount 20.
    const int w = 23, h = 40;
    std::vector<std::uint32_t> counts(static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            counts[static_cast<size_t>(y) * w + x] = x <= 20 ? x : (x == 21 ? 50 : 1000);
    const Image img = sampleHeatmap(counts, w, h, 20);
    ASSERT_EQ(img.width, w + kHeatmapLegendWidth);
    ASSERT_EQ(img.height, h);
    EXPECT_TRUE(isBlack(img.at(0, 5)));
    for (int x = 1; x <= 20; ++x) {
        EXPECT_GT(luminance(img.at(x, 5)), luminance(img.at(x - 1, 5))) << x;
        const Vec3f expected = heatmapColor(x / 20.f);
        EXPECT_NEAR(img.at(x, 5).x, expected.x, 1e-6f) << x;
        EXPECT_EQ(img.at(x, 5).w, 1.f);
    }
    // Above maxCount: the same colour as maxCount.
    EXPECT_EQ(img.at(21, 5).xyz(), img.at(20, 5).xyz());
    EXPECT_EQ(img.at(22, 5).xyz(), img.at(20, 5).xyz());

    // maxCount 0: the buffer's largest count (1000) is the top, so 20 is now dim.
    const Image automatic = sampleHeatmap(counts, w, h);
    EXPECT_EQ(automatic.at(22, 5).xyz(), heatmapColor(1.f));
    EXPECT_LT(luminance(automatic.at(20, 5)), luminance(img.at(20, 5)));
    const Vec3f dim = heatmapColor(20.f / 1000.f);
    EXPECT_NEAR(automatic.at(20, 5).x, dim.x, 1e-6f);
}

TEST(Heatmap, LegendHasABarAndTickMarks) {
    const int w = 50, h = 120;
    const std::vector<std::uint32_t> counts(static_cast<size_t>(w) * h, 0);  // all black
    const Image img = sampleHeatmap(counts, w, h, 300);
    ASSERT_EQ(img.width, w + kHeatmapLegendWidth);
    // The heat map itself is black.
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) ASSERT_TRUE(isBlack(img.at(x, y))) << x << "," << y;
    // A column through the colour bar: brightness rises from bottom to top, hot at the top.
    int barColumn = -1;
    for (int x = w; x < img.width && barColumn < 0; ++x)
        if (img.at(x, h / 2).x > 0.f && img.at(x, h / 2).z != img.at(x, h / 2).x) barColumn = x;
    ASSERT_GE(barColumn, w);
    int barTop = 0;
    while (barTop < h && img.at(barColumn, barTop).xyz() != heatmapColor(1.f)) ++barTop;
    ASSERT_LT(barTop, h);
    // The bar ends at its black (count 0) row, above the grey frame.
    int barBottom = barTop;
    while (barBottom + 1 < h && img.at(barColumn, barBottom + 1).xyz() != Vec3f(0.5f, 0.5f, 0.5f))
        ++barBottom;
    EXPECT_EQ(img.at(barColumn, barBottom).xyz(), heatmapColor(0.f));
    ASSERT_GT(barBottom, barTop + h / 2);
    for (int y = barTop + 1; y <= barBottom; ++y)
        EXPECT_LT(luminance(img.at(barColumn, y)), luminance(img.at(barColumn, y - 1))) << y;
    // The bar is about 20 pixels wide.
    int barWidth = 0;
    for (int x = w; x < img.width; ++x)
        if (img.at(x, barTop).xyz() == heatmapColor(1.f)) ++barWidth;
    EXPECT_EQ(barWidth, 20);
    // White tick marks beside the bar at the top, the middle and the bottom, and nothing else
    // white in the margin (no text).
    auto whiteNear = [&](int row) {
        int n = 0;
        for (int y = std::max(row - 1, 0); y <= std::min(row + 1, h - 1); ++y)
            for (int x = barColumn + 10; x < img.width; ++x)
                if (img.at(x, y).xyz() == Vec3f(1.f, 1.f, 1.f)) ++n;
        return n;
    };
    EXPECT_EQ(whiteNear(barTop), 4);
    EXPECT_EQ(whiteNear((barTop + barBottom) / 2), 4);
    EXPECT_EQ(whiteNear(barBottom), 4);
    int white = 0;
    for (int y = 0; y < h; ++y)
        for (int x = w; x < img.width; ++x) white += img.at(x, y).xyz() == Vec3f(1.f, 1.f, 1.f);
    EXPECT_EQ(white, 12);
}

TEST(Heatmap, BadBuffersAreArgumentErrors) {
    std::vector<std::uint32_t> counts(99, 1);
    try {
        sampleHeatmap(counts, 10, 10);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_NE(std::string(e.what()).find("99 counts for a 10x10"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(sampleHeatmap({}, 0, 0), Error);
    EXPECT_THROW(sampleHeatmap(counts, -1, -99), Error);
    // An all-zero buffer with maxCount 0 still works (the scale top is 1).
    const Image img = sampleHeatmap(std::vector<std::uint32_t>(4, 0), 2, 2);
    EXPECT_TRUE(isBlack(img.at(1, 1)));
}

}  // namespace
}  // namespace uvr
