// SPDX-License-Identifier: MIT
#include "uvr/tf/range_stats.h"

#include <cmath>

namespace uvr {

TfRangeTables::TfRangeTables(const TfTableView& table) {
    const int n = table.count;
    prefix.assign(5 * static_cast<std::size_t>(n + 1), 0.0);
    for (int i = 0; i < n; ++i) {
        const Vec4f e = table.entries[i];
        const double v[5] = {
            e.x, e.y, e.z, e.w,
            double(e.x) * e.x + double(e.y) * e.y + double(e.z) * e.z + double(e.w) * e.w};
        for (int c = 0; c < 5; ++c) prefix[5 * (i + 1) + c] = prefix[5 * i + c] + v[c];
    }
    levels = 1;
    while ((1 << levels) <= n) ++levels;
    maxLevels.assign(static_cast<std::size_t>(levels) * n, 0.f);
    rateLevels.assign(static_cast<std::size_t>(levels) * n, 0.f);
    for (int i = 0; i < n; ++i) {
        const Vec4f e = table.entries[i];
        maxLevels[i] = e.w;
        if (i + 1 == n) break;
        const Vec4f f = table.entries[i + 1];
        const float te = extinctionPerUnit(e.w, table.law), tf = extinctionPerUnit(f.w, table.law);
        float rate = std::fabs(tf - te);
        for (int c = 0; c < 3; ++c) rate = std::fmax(rate, std::fabs(f[c] * tf - e[c] * te));
        rateLevels[i] = rate;
    }
    for (std::vector<float>* sparse : {&maxLevels, &rateLevels}) {
        float* s = sparse->data();
        for (int k = 1; k < levels; ++k)
            for (int i = 0; i + (1 << k) <= n; ++i) {
                const float a = s[(k - 1) * n + i];
                const float b = s[(k - 1) * n + i + (1 << (k - 1))];
                s[k * n + i] = a > b ? a : b;
            }
    }
}

}  // namespace uvr
