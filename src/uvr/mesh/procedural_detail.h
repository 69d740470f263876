// SPDX-License-Identifier: MIT
#pragma once
// What the procedural generators share (procedural.cpp, procedural_fields.cpp, mixed_cells.cpp):
// deterministic hashing and the signed volume of a tetrahedron.

#include <cstdint>

#include "uvr/core/vec.h"

namespace uvr::procedural_detail {

/// Deterministic hashing: the SplitMix64 finaliser.
inline constexpr std::uint64_t mix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// Uniform double in [-1, 1) from the top 53 bits of a hash.
inline double hashToSigned(std::uint64_t h) {
    return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

/// Deterministic point in the unit ball for (seed, point index), by rejection sampling a cube.
inline Vec3f unitBallSample(std::uint64_t seed, std::uint64_t pointIndex) {
    const std::uint64_t base = mix64(seed ^ mix64(pointIndex));
    for (std::uint64_t attempt = 0; attempt < 64; ++attempt) {
        const std::uint64_t h = base + 3 * attempt;
        const double x = hashToSigned(mix64(h));
        const double y = hashToSigned(mix64(h + 1));
        const double z = hashToSigned(mix64(h + 2));
        if (x * x + y * y + z * z <= 1.0)
            return {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    }
    return {};  // unreachable in practice (probability 0.48^64)
}

/// Signed volume of tetrahedron (a, b, c, d); positive when d sees a, b, c counter-clockwise.
inline double signedVolume(Vec3f a, Vec3f b, Vec3f c, Vec3f d) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
    return (ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx)) / 6.0;
}

}  // namespace uvr::procedural_detail
