// SPDX-License-Identifier: MIT
#include "uvr/tf/range_stats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace uvr {
namespace {

/// Brute force over the same points query() uses: the two interpolated ends and the entries
/// strictly between them.
RangeStats bruteForce(const TfTableView& t, float lo, float hi) {
    std::vector<Vec4f> pts{t.sample(lo), t.sample(hi)};
    const float f0 = tfTablePosition(lo, t.lo, t.hi, t.count);
    const float f1 = tfTablePosition(hi, t.lo, t.hi, t.count);
    for (int i = 0; i < t.count; ++i)
        if (float(i) > f0 && float(i) < f1) pts.push_back(t.entries[i]);
    RangeStats s;
    double mean[4] = {}, sq = 0;
    for (const Vec4f& p : pts) {
        s.maxOpacity = std::max(s.maxOpacity, p.w);
        mean[0] += p.x, mean[1] += p.y, mean[2] += p.z, mean[3] += p.w;
        sq += double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z + double(p.w) * p.w;
    }
    const double n = pts.size();
    s.variance = static_cast<float>(
        sq / n -
        (mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2] + mean[3] * mean[3]) / (n * n));
    return s;
}

/// The largest rate (RangeStats::maxRate) over the table's pieces that [lo, hi] overlaps.
float bruteForceRate(const TfTableView& t, float lo, float hi) {
    const float f0 = tfTablePosition(lo, t.lo, t.hi, t.count);
    const float f1 = tfTablePosition(hi, t.lo, t.hi, t.count);
    float rate = 0.f;
    for (int i = 0; i + 1 < t.count; ++i) {
        const bool overlaps = (float(i + 1) > f0 && float(i) < f1) ||
                              (f0 >= float(i) && f0 < float(i + 1)) ||
                              (i + 2 == t.count && f0 >= float(i + 1));
        if (!overlaps) continue;
        const Vec4f a = t.entries[i], b = t.entries[i + 1];
        const float ta = extinctionPerUnit(a.w, t.law), tb = extinctionPerUnit(b.w, t.law);
        rate = std::max(rate, std::fabs(tb - ta));
        for (int c = 0; c < 3; ++c) rate = std::max(rate, std::fabs(b[c] * tb - a[c] * ta));
    }
    return rate;
}

TEST(RangeStats, MatchBruteForceOnRandomTablesAndRanges) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int count : {2, 3, 17, 256, 1000}) {
        std::vector<Vec4f> e(count);
        for (auto& v : e) v = Vec4f(u(rng), u(rng), u(rng), u(rng) < 0.3f ? 0.f : u(rng));
        TfTableView table{e.data(), count, -2.f, 5.f};
        table.law = count % 2 ? OpacityLaw::Transmittance : OpacityLaw::Attenuation;
        const TfRangeTables tables(table);
        const TfRangeView view = tables.view(table);
        for (int i = 0; i < 2000; ++i) {
            float a = -3.f + 9.f * u(rng), b = -3.f + 9.f * u(rng);
            if (a > b) std::swap(a, b);
            const RangeStats got = view.query(a, b), want = bruteForce(table, a, b);
            ASSERT_FLOAT_EQ(got.maxOpacity, want.maxOpacity) << count << " " << a << " " << b;
            ASSERT_NEAR(got.variance, std::max(want.variance, 0.f), 1e-5f);
            ASSERT_FLOAT_EQ(got.maxRate, bruteForceRate(table, a, b)) << count << " " << a;
        }
    }
}

TEST(RangeStats, ConstantTableHasZeroVarianceAndRampMaxIsTheUpperEnd) {
    std::vector<Vec4f> flat(64, Vec4f(0.2f, 0.4f, 0.6f, 0.5f));
    const TfTableView t{flat.data(), 64, 0.f, 1.f};
    const TfRangeTables tables(t);
    EXPECT_NEAR(tables.view(t).query(0.1f, 0.9f).variance, 0.f, 1e-7f);
    std::vector<Vec4f> ramp(101);
    for (int i = 0; i <= 100; ++i) ramp[i] = Vec4f(0, 0, 0, i / 100.f);
    const TfTableView r{ramp.data(), 101, 0.f, 1.f};
    const TfRangeTables rt(r);
    EXPECT_NEAR(rt.view(r).query(0.2f, 0.355f).maxOpacity, 0.355f, 1e-6f);
    EXPECT_EQ(rt.view(r).query(-1.f, -0.5f).maxOpacity, 0.f);  // below the range: first entry
}

TEST(RangeStats, RateIsTheSteepestChangeOfOpticalDepthOrEmission) {
    // Opacity 0 up to entry 50, 0.5 from entry 51: under transmittance the rate is -ln(0.5)
    // (times the white colour) on the piece 50-51 and 0 elsewhere.
    std::vector<Vec4f> step(101, Vec4f(1.f, 1.f, 1.f, 0.f));
    for (int i = 51; i <= 100; ++i) step[i].w = 0.5f;
    TfTableView t{step.data(), 101, 0.f, 1.f};
    t.law = OpacityLaw::Transmittance;
    const TfRangeTables tables(t);
    EXPECT_FLOAT_EQ(tables.view(t).query(0.1f, 0.9f).maxRate, std::log(2.f));
    EXPECT_FLOAT_EQ(tables.view(t).query(0.505f, 0.505f).maxRate, std::log(2.f));
    EXPECT_EQ(tables.view(t).query(0.1f, 0.45f).maxRate, 0.f);
    EXPECT_EQ(tables.view(t).query(0.6f, 2.f).maxRate, 0.f);
    // Opacity 1 is capped: a finite rate.
    step[100].w = 1.f;
    const TfRangeTables capped(t);
    EXPECT_NEAR(capped.view(t).query(0.95f, 1.f).maxRate, -std::log(1e-6f) - std::log(2.f), 0.1f);
    // Under attenuation the extinction is the opacity itself: 0.5 on the step, 1 - 0.5 at the
    // end.
    t.law = OpacityLaw::Attenuation;
    const TfRangeTables attenuation(t);
    EXPECT_FLOAT_EQ(attenuation.view(t).query(0.1f, 0.9f).maxRate, 0.5f);
    EXPECT_FLOAT_EQ(attenuation.view(t).query(0.95f, 1.f).maxRate, 0.5f);
}

TEST(TfTablePosition, AnyInputGivesAPositionInsideTheTable) {
    constexpr float kMax = std::numeric_limits<float>::max();
    constexpr float kInf = std::numeric_limits<float>::infinity();
    const float kNaN = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FLOAT_EQ(tfTablePosition(0.5f, 0.f, 1.f, 11), 5.f);
    // A range spanning the whole float range: its width overflows, its midpoint is the middle.
    EXPECT_FLOAT_EQ(tfTablePosition(0.f, -kMax, kMax, 11), 5.f);
    EXPECT_FLOAT_EQ(tfTablePosition(kMax, -kMax, kMax, 11), 10.f);
    EXPECT_FLOAT_EQ(tfTablePosition(-kMax, -kMax, kMax, 11), 0.f);
    EXPECT_FLOAT_EQ(tfTablePosition(1.5e38f, -3e38f, 3e38f, 5), 3.f);
    // Out of range, infinite and NaN values and degenerate ranges: a position in [0, count - 1].
    const float values[] = {-kInf, -kMax, -1e30f, -1.f, 0.f, 1e-45f, 1.f, 1e30f, kMax, kInf, kNaN};
    const float bounds[] = {-kInf, -kMax, -1.f, 0.f, 1e-45f, 1.f, kMax, kInf, kNaN};
    for (float v : values)
        for (float lo : bounds)
            for (float hi : bounds)
                for (int count : {1, 2, 1024}) {
                    const float f = tfTablePosition(v, lo, hi, count);
                    ASSERT_TRUE(f >= 0.f && f <= float(count - 1))
                        << f << " for " << v << " in [" << lo << ", " << hi << "], " << count;
                }
    EXPECT_EQ(tfTablePosition(kNaN, 0.f, 1.f, 8), 0.f);
    EXPECT_EQ(tfTablePosition(kInf, 0.f, 1.f, 8), 7.f);
    EXPECT_EQ(tfTablePosition(-kInf, 0.f, 1.f, 8), 0.f);
    EXPECT_EQ(tfTablePosition(0.5f, 1.f, 0.f, 8), 0.f);  // inverted range: the first entry
}

TEST(TfTablePosition, SamplingAndRangeStatsOverTheWholeFloatRange) {
    constexpr float kMax = std::numeric_limits<float>::max();
    // Opacity only in the middle of the table: a partition spanning it must see it.
    std::vector<Vec4f> e(64, Vec4f(0.f, 0.f, 0.f, 0.f));
    e[32] = Vec4f(1.f, 1.f, 1.f, 0.75f);
    const TfTableView t{e.data(), 64, -kMax, kMax};
    const TfRangeTables tables(t);
    EXPECT_EQ(tables.view(t).query(-kMax, kMax).maxOpacity, 0.75f);
    EXPECT_EQ(tables.view(t).query(-3e38f, -1e38f).maxOpacity, 0.f);
    EXPECT_GT(t.sample(1e36f).w, 0.f);
    EXPECT_EQ(t.sample(std::numeric_limits<float>::infinity()).w, 0.f);
    EXPECT_EQ(t.sample(std::numeric_limits<float>::quiet_NaN()).w, 0.f);
}

}  // namespace
}  // namespace uvr
