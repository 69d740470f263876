// SPDX-License-Identifier: MIT
// Line plots: nice ticks, layout, series pixels, the bitmap font.
#include "uvr/render/plot.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "uvr/core/error.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

const Vec3f kRed(0.9f, 0.1f, 0.1f), kBlue(0.1f, 0.2f, 0.9f), kGreen(0.1f, 0.7f, 0.2f);

bool hasColor(const Image& img, int x, int y, Vec3f c) {
    if (x < 0 || y < 0 || x >= img.width || y >= img.height) return false;
    return img.at(x, y).xyz() == c;
}

/// Number of pixels of colour c in the rows [y0, y1] and columns [x0, x1].
int countColor(const Image& img, int x0, int y0, int x1, int y1, Vec3f c) {
    int n = 0;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) n += hasColor(img, x, y, c);
    return n;
}

TEST(Plot, NiceTicks) {
    AxisTicks t = niceTicks(0.13, 9.7);
    EXPECT_DOUBLE_EQ(t.lo, 0.0);
    EXPECT_DOUBLE_EQ(t.hi, 10.0);
    EXPECT_DOUBLE_EQ(t.step, 2.0);
    EXPECT_EQ(t.count(), 6);
    t = niceTicks(0.0, 1.0);
    EXPECT_DOUBLE_EQ(t.lo, 0.0);
    EXPECT_DOUBLE_EQ(t.hi, 1.0);
    EXPECT_DOUBLE_EQ(t.step, 0.2);
    EXPECT_DOUBLE_EQ(t.value(3), 0.6000000000000001);  // lo + 3 * step
    t = niceTicks(-37.0, 512.0);                       // range 549 -> 1000, step 1000 / 5 -> 200
    EXPECT_DOUBLE_EQ(t.step, 200.0);
    EXPECT_DOUBLE_EQ(t.lo, -200.0);
    EXPECT_DOUBLE_EQ(t.hi, 600.0);
    t = niceTicks(0.00123, 0.00456);
    EXPECT_NEAR(t.step, 0.001, 1e-18);
    EXPECT_NEAR(t.lo, 0.001, 1e-15);
    EXPECT_NEAR(t.hi, 0.005, 1e-15);
    // Ticks straddling zero hit exactly 0.
    t = niceTicks(-0.3, 0.7);
    EXPECT_EQ(t.value(static_cast<int>(std::llround(-t.lo / t.step))), 0.0);
    // Degenerate ranges.
    t = niceTicks(5.0, 5.0);
    EXPECT_LT(t.lo, 5.0);
    EXPECT_GT(t.hi, 5.0);
    for (auto [lo, hi] : {std::pair{std::nan(""), 1.0}, std::pair{1.0, -1.0},
                          std::pair{-1e308, 1e308}, std::pair{0.0, 5e-324}}) {
        t = niceTicks(lo, hi);
        EXPECT_DOUBLE_EQ(t.lo, 0.0) << lo << " " << hi;
        EXPECT_DOUBLE_EQ(t.hi, 1.0) << lo << " " << hi;
    }
    // Every step is 1, 2 or 5 times a power of ten and the ticks cover the data.
    for (double hi : {0.017, 3.3, 77.0, 1234.5, 9.9e7}) {
        t = niceTicks(-hi / 3, hi);
        const double mantissa = t.step / std::pow(10.0, std::floor(std::log10(t.step)));
        EXPECT_TRUE(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 ||
                    std::abs(mantissa - 5) < 1e-9)
            << t.step;
        EXPECT_LE(t.lo, -hi / 3);
        EXPECT_GE(t.hi, hi);
        EXPECT_GE(t.count(), 3);
        EXPECT_LE(t.count(), 12);
    }
}

TEST(Plot, FormatTick) {
    EXPECT_EQ(formatTick(0.6000000000000001, 0.2), "0.6");
    EXPECT_EQ(formatTick(400.0, 100.0), "400");
    EXPECT_EQ(formatTick(0.0015, 0.0005), "0.0015");
    EXPECT_EQ(formatTick(-2.5, 0.5), "-2.5");
    EXPECT_EQ(formatTick(2e7, 5e6), "2e+07");
}

TEST(Plot, DrawText) {
    Image img(40, 20);
    drawText(img, 2, 3, " ", kRed);
    for (const Vec4f& p : img.pixels) ASSERT_EQ(p.w, 0.f);
    drawText(img, 2, 3, "8", kRed);
    // "8" of the 5x7 font: 3+2+2+3+2+2+3 = 17 pixels, all inside its cell.
    EXPECT_EQ(countColor(img, 0, 0, 39, 19, kRed), 17);
    EXPECT_EQ(countColor(img, 2, 3, 6, 9, kRed), 17);
    EXPECT_TRUE(hasColor(img, 3, 3, kRed));   // top bar
    EXPECT_FALSE(hasColor(img, 2, 3, kRed));  // rounded corner
    EXPECT_TRUE(hasColor(img, 2, 4, kRed));   // left side
    EXPECT_FALSE(hasColor(img, 4, 5, kRed));  // upper hole
    // Scale 2 quadruples the pixel count; characters outside 32..126 draw as '?'.
    Image big(40, 20);
    drawText(big, 0, 0, "8", kRed, 2);
    EXPECT_EQ(countColor(big, 0, 0, 39, 19, kRed), 4 * 17);
    Image q1(20, 10), q2(20, 10);
    drawText(q1, 0, 0, "?", kRed);
    drawText(q2, 0, 0, "\x01", kRed);
    EXPECT_EQ(q1.pixels.size(), q2.pixels.size());
    for (size_t i = 0; i < q1.pixels.size(); ++i) EXPECT_EQ(q1.pixels[i].w, q2.pixels[i].w) << i;
    // Every printable character except the space sets pixels; text off the image is clipped.
    for (int ch = 33; ch <= 126; ++ch) {
        Image g(8, 8);
        drawText(g, 0, 0, std::string(1, static_cast<char>(ch)), kRed);
        EXPECT_GT(countColor(g, 0, 0, 7, 7, kRed), 2) << static_cast<char>(ch);
    }
    Image clip(4, 4);
    drawText(clip, -3, -3, "WWW", kRed);
    drawText(clip, 100, 100, "W", kRed);
    EXPECT_EQ(textWidth("abc"), 17);
    EXPECT_EQ(textWidth("abc", 2), 34);
    EXPECT_EQ(textWidth(""), 0);
}

TEST(Plot, SeriesLandWhereTheirValuesSay) {
    PlotSpec spec;
    spec.title = "Time and SSIM vs step";
    spec.xLabel = "step";
    spec.yLabel = "y";
    spec.series.push_back({"diagonal", {0.0, 1.0}, {0.0, 1.0}, kRed, false});
    spec.series.push_back({"half", {0.0, 0.5, 1.0}, {0.5, 0.5, 0.5}, kBlue, false});
    const Image img = renderPlot(spec);
    ASSERT_EQ(img.width, 800);
    ASSERT_EQ(img.height, 500);
    for (const Vec4f& p : img.pixels) ASSERT_EQ(p.w, 1.f);  // opaque

    const PlotFrame f = plotFrame(spec);
    EXPECT_DOUBLE_EQ(f.y.lo, 0.0);
    EXPECT_DOUBLE_EQ(f.y.hi, 1.0);
    EXPECT_FALSE(f.hasRightAxis);
    EXPECT_GT(f.left, 20);  // room for tick labels and the y label
    EXPECT_GT(f.top, 14);   // room for the title
    EXPECT_LT(f.bottom, 480);
    EXPECT_LT(f.right, 800);
    // The axis box is black along the left edge, except where series start on it.
    EXPECT_GT(countColor(img, f.left, f.top, f.left, f.bottom, Vec3f(0, 0, 0)),
              f.bottom - f.top - 12);
    EXPECT_EQ(countColor(img, f.left - 6, f.top, f.left - 6, f.bottom, Vec3f(0, 0, 0)), 0);

    // y = 0.5 is the middle row of the plot area: blue across the width there (apart from where
    // the red diagonal crosses it and the legend box).
    // Pixel rows/columns of data values: pixel centres, y.lo on row bottom, x.lo on column left.
    const int mid = static_cast<int>(std::floor(f.bottom + 0.5 - 0.5 * (f.bottom - f.top)));
    const int cx = static_cast<int>(std::floor(f.left + 0.5 + 0.5 * (f.right - f.left)));
    EXPECT_NEAR(mid, (f.top + f.bottom) / 2, 1);
    int blueColumns = 0;
    for (int x = f.left + 3; x <= f.right - 3; ++x)
        blueColumns += countColor(img, x, mid - 1, x, mid + 1, kBlue) > 0;
    EXPECT_GT(blueColumns, (f.right - f.left) * 9 / 10);
    // ...and nowhere well above (below the legend box at the top) or below it.
    EXPECT_EQ(countColor(img, f.left, f.top + 60, f.right, mid - 4, kBlue), 0);
    EXPECT_EQ(countColor(img, f.left, mid + 4, f.right, f.bottom, kBlue), 0);

    // The diagonal passes through the centre and near the corners of the plot area.
    EXPECT_GT(countColor(img, cx - 4, mid - 4, cx + 4, mid + 4, kRed), 0);
    const int qx = f.left + (f.right - f.left) / 4, qy = f.bottom - (f.bottom - f.top) / 4;
    EXPECT_GT(countColor(img, qx - 1, qy - 1, qx + 1, qy + 1, kRed), 0);
    EXPECT_EQ(countColor(img, qx - 1, f.top + (f.bottom - f.top) / 4 - 1, qx + 1,
                         f.top + (f.bottom - f.top) / 4 + 1, kRed),
              0);
    // A 5x5 marker at the middle point of the blue series, drawn over the red line.
    EXPECT_EQ(countColor(img, cx - 2, mid - 2, cx + 2, mid + 2, kBlue), 25);
    EXPECT_EQ(countColor(img, cx - 3, mid - 3, cx + 3, mid + 3, kBlue), 25 + 4);
    // Legend: a blue sample line in the top-right part of the plot area.
    EXPECT_GT(countColor(img, (f.left + f.right) / 2, f.top, f.right, f.top + 40, kBlue), 10);
    // Title text in the top margin.
    EXPECT_GT(countColor(img, 0, 0, 799, f.top - 2, Vec3f(0, 0, 0)), 50);
}

TEST(Plot, RightAxisScalesItsOwnSeries) {
    PlotSpec spec;
    spec.width = 640;
    spec.height = 400;
    spec.yRightLabel = "time (ms)";
    spec.series.push_back({"ssim", {0, 1, 2, 3}, {0.2, 0.4, 0.6, 0.8}, kGreen, false});
    spec.series.push_back({"time", {0, 1, 2, 3}, {300, 300, 300, 300}, kBlue, true});
    spec.series.push_back({"", {0, 3}, {1000, 1000}, kRed, true});
    const PlotFrame f = plotFrame(spec);
    EXPECT_TRUE(f.hasRightAxis);
    // Right axis from the right series only (300..1000: range 1000, step 200), left from 0.2..0.8.
    EXPECT_DOUBLE_EQ(f.yRight.lo, 200.0);
    EXPECT_DOUBLE_EQ(f.yRight.hi, 1000.0);
    EXPECT_NEAR(f.y.lo, 0.2, 1e-12);
    EXPECT_NEAR(f.y.hi, 0.8, 1e-12);
    const Image img = renderPlot(spec);
    // 300 on the [200, 1000] right axis: an eighth of the way up.
    const double frac = (300.0 - 200.0) / (1000.0 - 200.0);
    const int row = static_cast<int>(f.bottom + 0.5 - frac * (f.bottom - f.top));
    const int x = f.left + (f.right - f.left) / 3;
    EXPECT_GT(countColor(img, x - 2, row - 2, x + 2, row + 2, kBlue), 0);
    // Tick numbers to the right of the right axis.
    EXPECT_GT(countColor(img, f.right + 2, f.top, 639, f.bottom, Vec3f(0, 0, 0)), 50);
}

TEST(Plot, BadSpecsAreArgumentErrors) {
    PlotSpec spec;
    spec.series.push_back({"bad", {0, 1, 2}, {0, 1}, kRed, false});
    try {
        renderPlot(spec);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_THAT(e.what(), HasSubstr("series 0 ('bad') has 3 x values and 2 y values"));
    }
    PlotSpec small;
    small.width = 100;
    EXPECT_THROW(renderPlot(small), Error);
    PlotSpec huge;
    huge.width = 1 << 20;
    EXPECT_THROW(renderPlot(huge), Error);
    // Empty plots and non-finite points render without trouble.
    EXPECT_EQ(renderPlot(PlotSpec{}).width, 800);
    PlotSpec gaps;
    gaps.series.push_back({"gaps", {0, 1, NAN, 3, 1e300}, {1, INFINITY, 2, 3, 4}, kRed, false});
    EXPECT_EQ(renderPlot(gaps).height, 500);
}

}  // namespace
}  // namespace uvr
