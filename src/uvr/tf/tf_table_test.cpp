// SPDX-License-Identifier: MIT
// Breakpoints of baked tables: every run between breakpoints is linear to within the tolerance,
// no run could be longer, and the integrators' lookups (breakAbove/breakBelow) agree with them.
#include "uvr/tf/tf_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "uvr/tf/transfer_function.h"

namespace uvr {
namespace {

/// The breakpoints in increasing order, from the "above" half of the table.
std::vector<int> breakpoints(const std::vector<std::int32_t>& breaks, int count) {
    std::vector<int> out{0};
    while (out.back() < count - 1) out.push_back(breaks[out.back()]);
    return out;
}

/// Largest difference between the entries inside [b, e] and the chord from b to e, in units of
/// each channel's tolerance (colour kTfColorBreakTolerance, opacity kTfOpacityBreakTolerance).
float chordError(const std::vector<Vec4f>& t, int b, int e) {
    float worst = 0.f;
    for (int k = b + 1; k < e; ++k)
        for (int c = 0; c < 4; ++c) {
            const float f = float(k - b) / float(e - b);
            const float tolerance = c == 3 ? kTfOpacityBreakTolerance : kTfColorBreakTolerance;
            worst = std::fmax(worst,
                              std::fabs(t[k][c] - (t[b][c] + (t[e][c] - t[b][c]) * f)) / tolerance);
        }
    return worst;
}

TEST(TfTableBreaks, LinearTableHasOnlyItsEnds) {
    std::vector<Vec4f> t;
    for (int i = 0; i < 1024; ++i) {
        const float x = i / 1023.f;
        t.push_back(Vec4f(x, 1.f - x, 0.5f, 0.2f + 0.7f * x));
    }
    const std::vector<std::int32_t> b = tfTableBreaks(t.data(), 1024);
    EXPECT_EQ(breakpoints(b, 1024), (std::vector<int>{0, 1023}));
    const TfTableView view{t.data(), 1024, 0.f, 1.f, b.data()};
    EXPECT_EQ(view.breakAbove(0.0), 1023);
    EXPECT_EQ(view.breakAbove(517.3), 1023);
    EXPECT_EQ(view.breakBelow(517.3), 0);
    EXPECT_EQ(view.breakBelow(1023.0), 0);
}

TEST(TfTableBreaks, OpacityIsHeldTighterThanColour) {
    // A bump of 5e-4 in the middle of a linear table: inside the colour tolerance, outside the
    // opacity one.
    auto table = [](int channel) {
        std::vector<Vec4f> t;
        for (int i = 0; i < 101; ++i) {
            float e[4] = {0.2f, 0.4f, 0.6f, 0.5f};
            e[channel] += 5e-4f * (1.f - std::fabs(i - 50) / 50.f);
            t.push_back(Vec4f(e[0], e[1], e[2], e[3]));
        }
        return t;
    };
    for (int c = 0; c < 3; ++c) {
        const std::vector<Vec4f> t = table(c);
        EXPECT_EQ(breakpoints(tfTableBreaks(t.data(), 101), 101), (std::vector<int>{0, 100})) << c;
    }
    const std::vector<Vec4f> t = table(3);
    EXPECT_GT(breakpoints(tfTableBreaks(t.data(), 101), 101).size(), 2u);
    // Either tolerance can be given.
    EXPECT_EQ(breakpoints(tfTableBreaks(t.data(), 101, 1e-3f, 1e-3f), 101),
              (std::vector<int>{0, 100}));
}

TEST(TfTableBreaks, KinksAreKeptAndRunsAreLinearAndMaximal) {
    // ParaView-like maps (Lab and diverging colours curve between control points) with opacity
    // kinks, and random tables.
    std::vector<std::vector<Vec4f>> tables;
    for (const char* preset : {"cool-to-warm", "viridis", "black-body", "grayscale"}) {
        TransferFunction tf = transferFunctionPreset(preset);
        applyOpacitySpec(tf, "0:0,0.3:0,0.31:0.8,0.33:0.8,0.34:0,0.7:0.1,1:1");
        tables.push_back(tf.bake(1024));
    }
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int r = 0; r < 4; ++r) {
        std::vector<Vec4f> t(257);
        for (Vec4f& e : t) e = Vec4f(u(rng), u(rng), u(rng), u(rng) < 0.5f ? 0.f : u(rng));
        tables.push_back(t);
    }
    for (const std::vector<Vec4f>& t : tables) {
        const int n = static_cast<int>(t.size());
        const std::vector<std::int32_t> b = tfTableBreaks(t.data(), n);
        const std::vector<int> points = breakpoints(b, n);
        ASSERT_EQ(points.back(), n - 1);
        int transparentRuns = 0;
        for (std::size_t i = 0; i + 1 < points.size(); ++i) {
            const int b0 = points[i], b1 = points[i + 1];
            bool transparent = b1 > b0 + 1 || (t[b0].w == 0.f && t[b1].w == 0.f);
            for (int k = b0; k <= b1 && transparent; ++k) transparent = t[k].w == 0.f;
            if (transparent) {
                // A transparent run is one piece whatever its colours, and maximal.
                ++transparentRuns;
                if (b1 < n - 1) {
                    EXPECT_GT(t[b1 + 1].w, 0.f) << b1;
                }
                continue;
            }
            EXPECT_LE(chordError(t, b0, b1), 1.001f);
            if (b1 < n - 1) {  // greedy: one entry more breaks the tolerance
                EXPECT_GT(chordError(t, b0, b1 + 1), 1.f);
            }
        }
        // The presets are transparent over [0, 0.3] (one piece), and so are pairs of the random
        // tables' entries.
        EXPECT_GT(transparentRuns, 0);
        // The opacity kink at 0.3 of the presets' range (entry 306.9) is next to a breakpoint,
        // and the smooth colours need far fewer than all entries.
        if (n == 1024) {
            EXPECT_LT(points.size(), 400u);
            bool kink = false;
            for (int p : points) kink = kink || (p >= 306 && p <= 307);
            EXPECT_TRUE(kink);
        }
        // Lookups: for every position, the nearest breakpoints on either side.
        const TfTableView view{t.data(), n, 0.f, 1.f, b.data()};
        for (double g = 0.0; g < n - 1; g += 0.37) {
            const int above = view.breakAbove(g);
            EXPECT_GT(above, g);
            for (int p : points) EXPECT_FALSE(p > g && p < above) << g;
        }
        for (double g = 0.5; g <= n - 1; g += 0.37) {
            const int below = view.breakBelow(g);
            EXPECT_LT(below, g);
            for (int p : points) EXPECT_FALSE(p < g && p > below) << g;
        }
    }
}

}  // namespace
}  // namespace uvr
