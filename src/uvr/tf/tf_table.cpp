// SPDX-License-Identifier: MIT
#include "uvr/tf/tf_table.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace uvr {

const char* opacityLawName(OpacityLaw law) {
    return law == OpacityLaw::Attenuation ? "attenuation" : "transmittance";
}

bool parseOpacityLaw(const char* name, OpacityLaw& law) {
    for (OpacityLaw l : {OpacityLaw::Attenuation, OpacityLaw::Transmittance})
        if (name && std::strcmp(name, opacityLawName(l)) == 0) {
            law = l;
            return true;
        }
    return false;
}

std::vector<std::int32_t> tfTableBreaks(const Vec4f* entries, int count, float colorTolerance,
                                        float opacityTolerance) {
    std::vector<std::int32_t> out(2 * static_cast<std::size_t>(std::max(count, 0)), 0);
    if (count < 2) return out;
    // Breakpoints in increasing order: a run from breakpoint b may end at entry j when the chord
    // from b to j stays within tolerance of every entry between; for each channel that holds
    // while the chord's slope lies in the intersection of the intervals
    // [(e_k - e_b - tol) / (k - b), (e_k - e_b + tol) / (k - b)] of the entries k inside.
    std::vector<std::int32_t> points{0};
    int b = 0;
    while (b < count - 1) {
        // A run of transparent entries is one piece whatever its colours: nothing is emitted or
        // absorbed over it (segment::integrate then steps over it at once).
        if (entries[b].w == 0.f && entries[b + 1].w == 0.f) {
            int end = b + 1;
            while (end + 1 < count && entries[end + 1].w == 0.f) ++end;
            points.push_back(end);
            b = end;
            continue;
        }
        float lo[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
        float hi[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
        int end = b + 1;
        for (int j = b + 1; j < count; ++j) {
            const float d = static_cast<float>(j - b);
            bool fits = true;
            for (int c = 0; c < 4 && fits; ++c) {
                const float slope = (entries[j][c] - entries[b][c]) / d;
                fits = slope >= lo[c] && slope <= hi[c];
            }
            if (!fits) break;
            end = j;
            for (int c = 0; c < 4; ++c) {
                const float tolerance = c == 3 ? opacityTolerance : colorTolerance;
                const float rise = entries[j][c] - entries[b][c];
                lo[c] = std::max(lo[c], (rise - tolerance) / d);
                hi[c] = std::min(hi[c], (rise + tolerance) / d);
            }
        }
        points.push_back(end);
        b = end;
    }
    // breaks[i]: first breakpoint above i; breaks[count + i]: last breakpoint below i.
    std::size_t next = 1;
    for (int i = 0; i < count; ++i) {
        while (next + 1 < points.size() && points[next] <= i) ++next;
        out[i] = points[next] > i ? points[next] : count - 1;
    }
    std::size_t prev = 0;
    for (int i = 0; i < count; ++i) {
        while (prev + 1 < points.size() && points[prev + 1] < i) ++prev;
        out[count + i] = points[prev] < i ? points[prev] : 0;
    }
    return out;
}

}  // namespace uvr
