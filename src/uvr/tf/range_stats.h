// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

/// Transfer-function statistics over a value range.
struct RangeStats {
    float maxOpacity = 0.f;  ///< largest opacity the transfer function takes over the range
    float variance = 0.f;    ///< Var(r) + Var(g) + Var(b) + Var(a) over the range's table entries
    /// Largest change per table entry, over the range, of the extinction per opacity unit
    /// (extinctionPerUnit under the table's law) and of each colour channel times it (the
    /// emission): how fast the transfer function can change what a ray sees (the error-bound
    /// step rule).
    float maxRate = 0.f;
};

/// Plain-data tables for O(1) range statistics of a baked transfer function: prefix sums of
/// r, g, b, a and r^2 + g^2 + b^2 + a^2 (double) and sparse tables of opacity maxima and of rate
/// maxima (levels x count floats, level k holding the maximum over 2^k entries; the rate of
/// entry i is that of the table's piece from entry i to i + 1).
struct TfRangeView {
    TfTableView table;
    const double* prefix = nullptr;     ///< 5 * (count + 1) values
    const float* maxLevels = nullptr;   ///< levels * count values
    const float* rateLevels = nullptr;  ///< levels * count values
    int levels = 0;

    /// Maximum over entries [i0, i1] (i0 <= i1) of a sparse table.
    UVR_HOST_DEVICE float rangeMax(const float* sparse, int i0, int i1) const {
        const int n = table.count;
        int k = 0;
        while ((2 << k) <= i1 - i0 + 1) ++k;
        const float m0 = sparse[k * n + i0], m1 = sparse[k * n + i1 + 1 - (1 << k)];
        return m0 > m1 ? m0 : m1;
    }

    /// Maximum opacity and colour variance of the table over values [lo, hi] (clamped to the
    /// table's range like sampling is): the entries strictly inside plus the two interpolated
    /// end points, so the maximum is exact for the piecewise-linear function.
    UVR_HOST_DEVICE RangeStats query(float lo, float hi) const {
        const int n = table.count;
        // Positions in [0, n - 1] for any values (NaN, infinities, overflowing ranges).
        auto position = [&](float v) { return tfTablePosition(v, table.lo, table.hi, n); };
        const float f0 = position(lo), f1 = position(hi < lo ? lo : hi);
        const Vec4f e0 = table.sample(lo), e1 = table.sample(hi < lo ? lo : hi);
        // Entries strictly between the end points: indices i0 .. i1 - 1.
        int i0 = static_cast<int>(f0) + 1;
        int i1 = static_cast<int>(ceilf(f1));
        if (i1 < i0) i1 = i0;
        RangeStats out;
        out.maxOpacity = e0.w > e1.w ? e0.w : e1.w;
        double sum[5] = {
            double(e0.x) + e1.x, double(e0.y) + e1.y, double(e0.z) + e1.z, double(e0.w) + e1.w,
            double(dot(e0.xyz(), e0.xyz())) + e0.w * e0.w + dot(e1.xyz(), e1.xyz()) + e1.w * e1.w};
        double count = 2.0;
        if (i1 > i0) {
            for (int c = 0; c < 5; ++c) sum[c] += prefix[5 * i1 + c] - prefix[5 * i0 + c];
            count += i1 - i0;
            const float m = rangeMax(maxLevels, i0, i1 - 1);
            out.maxOpacity = out.maxOpacity > m ? out.maxOpacity : m;
        }
        // Rate: the table's pieces that [f0, f1] overlaps (the one holding f0 when they are
        // equal).
        if (n > 1 && rateLevels) {
            const int j0 = static_cast<int>(f0) < n - 2 ? static_cast<int>(f0) : n - 2;
            int j1 = static_cast<int>(ceilf(f1)) - 1;
            j1 = j1 < j0 ? j0 : (j1 > n - 2 ? n - 2 : j1);
            out.maxRate = rangeMax(rateLevels, j0, j1);
        }
        const double mean2 =
            (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2] + sum[3] * sum[3]) /
            (count * count);
        const double var = sum[4] / count - mean2;
        out.variance = var > 0.0 ? static_cast<float>(var) : 0.f;
        return out;
    }
};

/// Owner of the range tables of one baked transfer function (rebuilt on every change, cost
/// O(count log count)).
struct TfRangeTables {
    std::vector<double> prefix;
    std::vector<float> maxLevels;
    std::vector<float> rateLevels;
    int levels = 0;

    /// Builds the tables for a baked table (entries must outlive the view).
    explicit TfRangeTables(const TfTableView& table);
    /// View for kernels.
    TfRangeView view(const TfTableView& table) const {
        return {table, prefix.data(), maxLevels.data(), rateLevels.data(), levels};
    }
};

}  // namespace uvr
