// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>

#include "uvr/core/host_device.h"

namespace uvr {

/// Index of the run holding element x of runs laid end to end: the last r with begin[r] <= x
/// (begin ascending, of `count` + 1 entries, begin[0] <= x < begin[count]); empty runs are passed
/// over. The LBVH's segments, a k-d level's nodes.
UVR_HOST_DEVICE inline std::uint32_t runOf(const std::uint64_t* begin, std::uint32_t count,
                                           std::uint64_t x) {
    std::uint32_t lo = 0, hi = count;  // begin[lo] <= x < begin[hi]
    while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (begin[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

}  // namespace uvr
