// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>

#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"

namespace uvr {

/// Spreads the low 21 bits of v to every third bit.
UVR_HOST_DEVICE inline std::uint64_t spreadBits3(std::uint64_t v) {
    v &= 0x1fffffull;
    v = (v | (v << 32)) & 0x1f00000000ffffull;
    v = (v | (v << 16)) & 0x1f0000ff0000ffull;
    v = (v | (v << 8)) & 0x100f00f00f00f00full;
    v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
    v = (v | (v << 2)) & 0x1249249249249249ull;
    return v;
}

/// Cells per axis of the Morton grid (21 bits each, 63 in all): fine enough that graded meshes
/// (cells 1000x smaller near a wall than in the far field) still get distinct codes.
inline constexpr float kMortonGrid = 2097152.f;

/// 63-bit Morton code of p on a 2^21-per-axis grid over `bounds` (points outside, NaN and flat
/// axes clamp into the grid).
UVR_HOST_DEVICE inline std::uint64_t morton63(Vec3f p, const Bounds3f& bounds) {
    std::uint64_t q[3];
    for (int a = 0; a < 3; ++a) {
        const float ext = bounds.hi[a] - bounds.lo[a];
        const float scale = ext > 0.f ? kMortonGrid / ext : 0.f;
        float x = (p[a] - bounds.lo[a]) * scale;
        x = x > 0.f ? x : 0.f;  // also NaN
        x = x < kMortonGrid - 1.f ? x : kMortonGrid - 1.f;
        q[a] = static_cast<std::uint64_t>(x);
    }
    return (spreadBits3(q[0]) << 2) | (spreadBits3(q[1]) << 1) | spreadBits3(q[2]);
}

}  // namespace uvr
