// SPDX-License-Identifier: MIT
#include "uvr/tf/range_stats.h"

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
    for (int i = 0; i < n; ++i) maxLevels[i] = table.entries[i].w;
    for (int k = 1; k < levels; ++k)
        for (int i = 0; i + (1 << k) <= n; ++i) {
            const float a = maxLevels[(k - 1) * n + i];
            const float b = maxLevels[(k - 1) * n + i + (1 << (k - 1))];
            maxLevels[k * n + i] = a > b ? a : b;
        }
}

}  // namespace uvr
