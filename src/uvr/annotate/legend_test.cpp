// SPDX-License-Identifier: MIT
#include "uvr/annotate/legend.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "font_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using Labels = std::vector<std::string>;
const std::string kMinus = "\u2212";

TEST(LegendTicks, LinearRangesGetOneTwoFiveSteps) {
    LegendTicks t = legendTicks(0.0, 1.0, false);
    EXPECT_EQ(t.labels, (Labels{"0.0", "0.2", "0.4", "0.6", "0.8", "1.0"}));
    ASSERT_EQ(t.values.size(), 6u);
    EXPECT_DOUBLE_EQ(t.values[3], 0.6);

    t = legendTicks(-5.0, 5.0, false);
    EXPECT_EQ(t.values, (std::vector<double>{-4, -2, 0, 2, 4}));
    EXPECT_EQ(t.labels, (Labels{kMinus + "4", kMinus + "2", "0", "2", "4"}));

    t = legendTicks(1e-30, 3e-30, false);
    EXPECT_EQ(t.labels,
              (Labels{"1.0e" + kMinus + "30", "1.5e" + kMinus + "30", "2.0e" + kMinus + "30",
                      "2.5e" + kMinus + "30", "3.0e" + kMinus + "30"}));
    EXPECT_DOUBLE_EQ(t.values.front(), 1e-30);
    EXPECT_DOUBLE_EQ(t.values.back(), 3e-30);

    t = legendTicks(-1e30, 1e30, false);
    EXPECT_EQ(t.labels, (Labels{kMinus + "1e30", kMinus + "5e29", "0", "5e29", "1e30"}));

    // The blunt fin's density and SPX's scalars: ticks inside the range only.
    t = legendTicks(0.1996, 4.686, false);
    EXPECT_EQ(t.labels, (Labels{"1", "2", "3", "4"}));
    t = legendTicks(0.0, 2.254, false);
    EXPECT_EQ(t.labels, (Labels{"0.0", "0.5", "1.0", "1.5", "2.0"}));
    t = legendTicks(1000.0, 1000.004, false);
    EXPECT_EQ(t.labels, (Labels{"1000.000", "1000.001", "1000.002", "1000.003", "1000.004"}));
    t = legendTicks(0.0, 250000.0, false);
    EXPECT_EQ(t.labels, (Labels{"0", "5.0e4", "1.0e5", "1.5e5", "2.0e5", "2.5e5"}));
    t = legendTicks(0.0, 0.0004, false);
    EXPECT_EQ(t.labels, (Labels{"0", "1e" + kMinus + "4", "2e" + kMinus + "4", "3e" + kMinus + "4",
                                "4e" + kMinus + "4"}));

    // A single value, and a count cap.
    t = legendTicks(3.5, 3.5, false);
    EXPECT_EQ(t.labels, Labels{"3.5"});
    t = legendTicks(0.3, 1.65, false);  // 3 or 7 ticks: the more
    EXPECT_EQ(t.labels, (Labels{"0.4", "0.6", "0.8", "1.0", "1.2", "1.4", "1.6"}));
    t = legendTicks(0.0, 1.0, false, 5, 3);
    EXPECT_EQ(t.labels, (Labels{"0.0", "0.5", "1.0"}));
    // A range no step fits: its ends.
    t = legendTicks(0.123, 0.1234, false, 5, 2);
    EXPECT_EQ(t.values, (std::vector<double>{0.123, 0.1234}));
}

TEST(LegendTicks, LogRangesGetDecades) {
    LegendTicks t = legendTicks(1.0, 1e6, true);
    EXPECT_EQ(t.values, (std::vector<double>{1, 10, 100, 1e3, 1e4, 1e5, 1e6}));
    EXPECT_EQ(t.labels, (Labels{"10\u2070", "10\u00B9", "10\u00B2", "10\u00B3", "10\u2074",
                                "10\u2075", "10\u2076"}));
    t = legendTicks(1e-3, 1e3, true);
    EXPECT_EQ(t.labels, (Labels{"0.001", "0.01", "0.1", "1", "10", "100", "1000"}));
    t = legendTicks(0.5, 2e3, true);  // inside the range only
    EXPECT_EQ(t.labels, (Labels{"1", "10", "100", "1000"}));
    // Many decades: every 10th, aligned to multiples of 10.
    t = legendTicks(1e-30, 1e30, true);
    EXPECT_EQ(t.labels.size(), 7u);
    EXPECT_EQ(t.labels.front(), "10\u207B\u00B3\u2070");
    EXPECT_EQ(t.labels[3], "10\u2070");
    EXPECT_EQ(t.labels.back(), "10\u00B3\u2070");
    // Within a decade: 1-2-5 multiples, else linear ticks.
    t = legendTicks(2.0, 8.0, true);
    EXPECT_EQ(t.labels, (Labels{"2", "5"}));
    t = legendTicks(0.5, 50.0, true);  // two decades: 1-2-5 ticks between them
    EXPECT_EQ(t.labels, (Labels{"0.5", "1", "2", "5", "10", "20", "50"}));
    t = legendTicks(0.5, 50.0, true, 5, 4);  // too many: the decades
    EXPECT_EQ(t.labels, (Labels{"1", "10"}));
    t = legendTicks(1e-5, 1e-3, true);
    EXPECT_EQ(t.labels, (Labels{"10\u207B\u2075", "10\u207B\u2074", "10\u207B\u00B3"}));
    t = legendTicks(3.0, 4.0, true);
    EXPECT_EQ(t.values.front(), 3.0);
    EXPECT_EQ(t.values.back(), 4.0);
    EXPECT_GE(t.values.size(), 3u);
}

TEST(LegendTicks, BadRangesAreRefused) {
    EXPECT_THROW(legendTicks(std::nan(""), 1.0, false), Error);
    EXPECT_THROW(legendTicks(0.0, INFINITY, false), Error);
    EXPECT_THROW(legendTicks(2.0, 1.0, false), Error);
    EXPECT_THROW(legendTicks(0.0, 1.0, true), Error);
    EXPECT_THROW(legendTicks(-1.0, 1.0, true), Error);
    EXPECT_THROW(legendTicks(0.0, 1.0, false, 5, 1), Error);
}

TEST(LegendTicks, LabelsTellValuesApartInOneFormat) {
    EXPECT_EQ(formatTickLabels({0.0, 0.5, 1.0, 1.5}), (Labels{"0.0", "0.5", "1.0", "1.5"}));
    EXPECT_EQ(formatTickLabels({-0.5, -0.0, 0.5}), (Labels{kMinus + "0.5", "0.0", "0.5"}));
    EXPECT_EQ(formatTickLabels({0.1 + 0.2, 0.6000000000000001}), (Labels{"0.3", "0.6"}));
    EXPECT_EQ(formatTickLabels({-0.0}), Labels{"0"});
    EXPECT_EQ(formatTickLabels({-2.5e-7, 2.5e-7}),
              (Labels{kMinus + "2.5e" + kMinus + "7", "2.5e" + kMinus + "7"}));
    EXPECT_EQ(formatTickLabels({1e20}), Labels{"1e20"});
    EXPECT_EQ(formatTickLabels({99999.0}), Labels{"99999"});
    EXPECT_EQ(formatTickLabels({2e-3, 5e-3}, true), (Labels{"0.002", "0.005"}));
    EXPECT_EQ(formatTickLabels({2e-7, 5e-7}, true),
              (Labels{"2\u00D710\u207B\u2077", "5\u00D710\u207B\u2077"}));
    EXPECT_TRUE(formatTickLabels({}).empty());
}

TEST(LegendTicks, PositionsAreLinearOrLogarithmic) {
    EXPECT_DOUBLE_EQ(legendPosition(0.25, 0.0, 1.0, false), 0.25);
    EXPECT_DOUBLE_EQ(legendPosition(-3.0, 0.0, 1.0, false), 0.0);
    EXPECT_DOUBLE_EQ(legendPosition(5.0, 0.0, 1.0, false), 1.0);
    EXPECT_NEAR(legendPosition(1e3, 1.0, 1e6, true), 0.5, 1e-12);
    EXPECT_DOUBLE_EQ(legendPosition(7.0, 7.0, 7.0, false), 0.5);
}

bool inside(const PixelRect& r, int x, int y) {
    return x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
}

TEST(LegendDraw, BarShowsTheTransferFunctionsColoursBottomToTop) {
    UVR_REQUIRE_FONT();
    const TransferFunction tf = transferFunctionPreset("viridis");
    Image image(800, 600);
    const LegendLayout L = drawLegend(image, font, tf, 0.0, 1.0, "density", false);
    const int x = (L.bar.x0 + L.bar.x1) / 2, h = L.bar.y1 - L.bar.y0;
    EXPECT_NEAR(h, 300, 1);  // half the height
    for (int y : {L.bar.y1 - 1, (L.bar.y0 + L.bar.y1) / 2, L.bar.y0}) {
        const float t = (L.bar.y1 - y - 0.5f) / h;
        const Vec3f want = tf.colorAt(t);
        const Vec4f got = image.at(x, y);
        EXPECT_FLOAT_EQ(got.w, 1.f) << y;  // opaque
        EXPECT_NEAR(got.x, want.x, 1e-5) << y;
        EXPECT_NEAR(got.y, want.y, 1e-5) << y;
        EXPECT_NEAR(got.z, want.z, 1e-5) << y;
    }
    // The ends are the transfer function's ends (viridis: dark purple at 0, yellow at 1).
    const Vec4f bottom = image.at(x, L.bar.y1 - 1), top = image.at(x, L.bar.y0);
    EXPECT_NEAR(bottom.x, tf.colorAt(0.f).x, 0.01);
    EXPECT_NEAR(top.y, tf.colorAt(1.f).y, 0.01);
    EXPECT_GT(top.y, bottom.y + 0.5f);
    // Ticks 0, 0.2, ..., 1 from the bottom row to the top row, evenly.
    EXPECT_EQ(L.ticks.labels, (Labels{"0.0", "0.2", "0.4", "0.6", "0.8", "1.0"}));
    ASSERT_EQ(L.tickRows.size(), 6u);
    EXPECT_EQ(L.tickRows.front(), L.bar.y1 - 1);
    EXPECT_EQ(L.tickRows.back(), L.bar.y0);
    for (size_t i = 1; i < L.tickRows.size(); ++i)
        EXPECT_NEAR(L.tickRows[i - 1] - L.tickRows[i], h / 5.0, 1.0);
}

TEST(LegendDraw, DrawsOnlyInItsBoxAtTheRightEdge) {
    UVR_REQUIRE_FONT();
    Image image(800, 600);
    const LegendLayout L = drawLegend(image, font, transferFunctionPreset("cool-to-warm"), -5.0,
                                      5.0, "pressure", false);
    EXPECT_GT(L.box.x0, 600);
    EXPECT_LT(L.box.x1, 800);
    EXPECT_GT(L.box.x1, 780);
    EXPECT_GT(L.box.y0, 0);
    EXPECT_LT(L.box.y1, 600);
    EXPECT_TRUE(inside(L.box, L.bar.x0, L.bar.y0));
    EXPECT_TRUE(inside(L.box, L.title.x1 - 1, L.title.y0));
    int outside = 0, ink = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const Vec4f p = image.at(x, y);
            if (!inside(L.box, x, y)) {
                outside += p.w != 0.f;
            } else if (!inside(L.bar, x, y)) {
                // The box is 80% white; the text and frame are opaque near-black.
                EXPECT_GE(p.w, 0.8f - 1e-6f) << x << "," << y;
                ink += p.w == 1.f && p.x < 0.2f;
            }
        }
    EXPECT_EQ(outside, 0);
    EXPECT_GT(ink, 200);  // title, labels, ticks and frame
    // ParaView's range labels: the ends beside the nice ticks (issue 35).
    EXPECT_EQ(L.ticks.labels,
              (Labels{kMinus + "5", kMinus + "4", kMinus + "2", "0", "2", "4", "5"}));
}

TEST(LegendDraw, TheLayoutIsKnownBeforeDrawingWithTheColumnsItKeeps) {
    // legendLayout says where drawLegend draws, so that a camera can keep off the columns
    // before the frame is rendered (issue 35): from the edge past the box by a margin, at most
    // a third of the width.
    UVR_REQUIRE_FONT();
    const auto same = [](const PixelRect& a, const PixelRect& b) {
        return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1;
    };
    for (const auto& [w, h] : {std::pair{800, 600}, {320, 240}, {200, 900}})
        for (const LegendPosition position : {LegendPosition::Right, LegendPosition::Left})
            for (const std::string& title : {std::string("pressure"), std::string(200, 'w')}) {
                SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h) + " " + title);
                LegendStyle style;
                style.position = position;
                const TransferFunction tf = transferFunctionPreset("viridis");
                const LegendLayout before = legendLayout(w, h, font, 0.01, 3e4, title, true, style);
                Image image(w, h);
                const LegendLayout L = drawLegend(image, font, tf, 0.01, 3e4, title, true, style);
                EXPECT_TRUE(same(before.box, L.box));
                EXPECT_TRUE(same(before.bar, L.bar));
                EXPECT_TRUE(same(before.title, L.title));
                EXPECT_EQ(before.ticks.labels, L.ticks.labels);
                EXPECT_EQ(before.columns, L.columns);
                // The box's far side from the edge, and the gap between box and edge again.
                const int columns = position == LegendPosition::Right
                                        ? (w - L.box.x0) + (w - L.box.x1)
                                        : L.box.x1 + L.box.x0;
                EXPECT_EQ(L.columns, std::min(w / 3, columns));
                if (title.size() > 100) {
                    EXPECT_EQ(L.columns, w / 3);  // the long title's box
                }
            }
}

TEST(LegendTicks, TheRangeEndsJoinTheTicksAndCrowdedTicksLeave) {
    LegendTicks t = legendTicks(0.1926, 4.9775, false);
    ASSERT_EQ(t.labels, (Labels{"1", "2", "3", "4"}));
    addRangeEnds(t, 0.1926, 4.9775, false, 0.05);
    EXPECT_EQ(t.labels, (Labels{"0.1926", "1", "2", "3", "4", "4.978"}));
    // A tick within the gap of an end leaves; an end that is a tick is not doubled.
    t = legendTicks(0.0, 2.254, false);
    addRangeEnds(t, 0.0, 2.254, false, 0.15);
    EXPECT_EQ(t.values.front(), 0.0);
    EXPECT_EQ(t.labels.back(), "2.254");
    for (std::size_t i = 1; i < t.values.size(); ++i) EXPECT_GT(t.values[i], t.values[i - 1]);
    EXPECT_TRUE(std::none_of(t.values.begin(), t.values.end() - 1,
                             [](double v) { return v > 2.254 * 0.85 && v < 2.254; }));
    EXPECT_EQ(legendTitle("density", Association::Point), "density (point)");
}

TEST(LegendDraw, TextContrastsWithTheBackground) {
    UVR_REQUIRE_FONT();
    for (const Vec3f bg : {Vec3f{0.f, 0.f, 0.f}, Vec3f{1.f, 1.f, 1.f}, Vec3f{0.1f, 0.1f, 0.12f}}) {
        Image image(400, 300);
        LegendStyle style;
        style.background = bg;
        const LegendLayout L = drawLegend(image, font, transferFunctionPreset("grayscale"), 0.0,
                                          1.0, "T", false, style);
        // The title's pixels: the box (background colour at 0.8) and text of the other extreme.
        float lightest = 1.f, darkest = 0.f;
        bool first = true;
        for (int y = L.title.y0; y < L.title.y1; ++y)
            for (int x = L.title.x0; x < L.title.x1; ++x) {
                const Vec4f p = image.at(x, y);
                if (p.w < 1.f) continue;  // box only: composited later over the background
                lightest = first ? p.x : std::max(lightest, p.x);
                darkest = first ? p.x : std::min(darkest, p.x);
                first = false;
            }
        ASSERT_FALSE(first) << "no text in the title box";
        const bool darkBackground = bg.x < 0.5f;
        EXPECT_EQ(darkBackground, lightest > 0.9f) << bg.x;
        EXPECT_EQ(!darkBackground, darkest < 0.1f) << bg.x;
        EXPECT_FLOAT_EQ(image.at(L.box.x0, L.box.y0).w, 0.8f);
        EXPECT_FLOAT_EQ(image.at(L.box.x0, L.box.y0).x, 0.8f * bg.x);
    }
}

TEST(LegendDraw, ScalesWithTheImageHeight) {
    UVR_REQUIRE_FONT();
    const TransferFunction tf = transferFunctionPreset("viridis");
    float previousSize = 0.f;
    int previousBar = 0;
    for (int h : {kLegendMinHeight, 256, 1024, 4096}) {
        Image image(h * 4 / 3, h);
        const LegendLayout L = drawLegend(image, font, tf, 0.0, 2.254, "scalars", false);
        EXPECT_GE(L.fontSize, 10.f) << h;
        EXPECT_GE(L.fontSize, previousSize) << h;
        EXPECT_GT(L.bar.y1 - L.bar.y0, previousBar) << h;
        EXPECT_GE(L.box.y0, 0) << h;
        EXPECT_LE(L.box.y1, h) << h;
        EXPECT_GE(L.box.x0, image.width / 2) << h;
        EXPECT_GE(L.ticks.values.size(), 2u) << h;
        // Labels at least a digit height apart.
        for (size_t i = 1; i < L.tickRows.size(); ++i)
            EXPECT_GE(L.tickRows[i - 1] - L.tickRows[i], 0.7 * L.fontSize) << h;
        previousSize = L.fontSize, previousBar = L.bar.y1 - L.bar.y0;
    }
    EXPECT_NEAR(previousSize, 4096 / 40.f, 1.f);
}

TEST(LegendDraw, LogScaleSpacesDecadesEvenly) {
    UVR_REQUIRE_FONT();
    Image image(600, 600);
    const LegendLayout L =
        drawLegend(image, font, transferFunctionPreset("viridis"), 1.0, 1e6, "energy", true);
    ASSERT_EQ(L.ticks.values.size(), 7u);
    const double spacing = (L.bar.y1 - 1 - L.bar.y0) / 6.0;
    for (size_t i = 0; i < L.tickRows.size(); ++i)
        EXPECT_NEAR(L.tickRows[i], L.bar.y1 - 1 - i * spacing, 1.0) << i;
    EXPECT_THROW(drawLegend(image, font, transferFunctionPreset("viridis"), 0.0, 1.0, "x", true),
                 Error);
}

TEST(LegendDraw, AnyTitleIsDrawnAndLongOnesAreShortened) {
    UVR_REQUIRE_FONT();
    const TransferFunction tf = transferFunctionPreset("viridis");
    for (const std::string& title : {std::string("bad \xFF\xFE utf-8 \xC3"),
                                     std::string("tab\tnew\nline\0nul", 17), std::string(""),
                                     std::string("\xE6\xB8\xA9\xE5\xBA\xA6 (\xC2\xB0"
                                                 "C)")}) {
        Image image(300, 200);
        const LegendLayout L = drawLegend(image, font, tf, 0.0, 1.0, title, false);
        EXPECT_LE(L.title.x1 - L.title.x0, 300) << title;
    }
    Image image(400, 300);
    const LegendLayout L = drawLegend(image, font, tf, 0.0, 1.0, std::string(500, 'w'), false);
    EXPECT_LE(L.title.x1 - L.title.x0, static_cast<int>(0.45 * 400));
    EXPECT_GE(L.title.x1 - L.title.x0, static_cast<int>(0.45 * 400) - 60);  // as long as fits
    EXPECT_GE(L.box.x0, 0);
    // A name of megabytes (from a hostile file) is cut quickly, also on the widest image.
    Image wide(16384, 200);
    const LegendLayout W =
        drawLegend(wide, font, tf, 0.0, 1.0, std::string(4 << 20, 'i') + "\xFF", false);
    EXPECT_LE(W.title.x1 - W.title.x0, static_cast<int>(0.45 * 16384));
}

TEST(LegendDraw, LeftPositionAndTooSmallImages) {
    UVR_REQUIRE_FONT();
    const TransferFunction tf = transferFunctionPreset("viridis");
    Image image(800, 600);
    LegendStyle style;
    style.position = LegendPosition::Left;
    const LegendLayout L = drawLegend(image, font, tf, 0.0, 1.0, "x", false, style);
    EXPECT_GT(L.box.x0, 0);
    EXPECT_LT(L.box.x1, 200);
    for (const auto& [w, h] : {std::pair{127, 600}, std::pair{800, 127}, std::pair{1, 1}}) {
        Image small(w, h);
        try {
            drawLegend(small, font, tf, 0.0, 1.0, "x", false);
            ADD_FAILURE() << w << "x" << h;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
            EXPECT_NE(std::string(e.what()).find("128x128"), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace uvr
