// SPDX-License-Identifier: MIT
#pragma once

#include <cfloat>

#include "uvr/core/ray.h"
#include "uvr/core/vec.h"

namespace uvr {

/// Axis-aligned box; empty when lo > hi on any axis (the default).
struct Bounds3f {
    Vec3f lo{FLT_MAX, FLT_MAX, FLT_MAX};
    Vec3f hi{-FLT_MAX, -FLT_MAX, -FLT_MAX};

    UVR_HOST_DEVICE bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    UVR_HOST_DEVICE void extend(Vec3f p) {
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    }
    UVR_HOST_DEVICE void extend(const Bounds3f& b) {
        lo = vmin(lo, b.lo);
        hi = vmax(hi, b.hi);
    }
    UVR_HOST_DEVICE Vec3f center() const { return (lo + hi) * 0.5f; }
    UVR_HOST_DEVICE Vec3f extent() const { return hi - lo; }
    UVR_HOST_DEVICE float diagonal() const { return empty() ? 0.f : length(hi - lo); }
    /// Volume, in double (0 when empty).
    UVR_HOST_DEVICE double volume() const {
        return empty() ? 0.0 : double(hi.x - lo.x) * double(hi.y - lo.y) * double(hi.z - lo.z);
    }
    UVR_HOST_DEVICE bool contains(Vec3f p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z &&
               p.z <= hi.z;
    }
    /// Index of the longest axis.
    UVR_HOST_DEVICE int longestAxis() const {
        Vec3f e = extent();
        return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
    }
};

/// Slab test: clips [tMin, tMax] to the part of the ray inside the box; false when it misses.
/// invDir holds 1/dir per component (infinities for zero components are fine).
UVR_HOST_DEVICE inline bool intersectBox(const Bounds3f& b, Vec3f org, Vec3f invDir, float& tMin,
                                         float& tMax) {
    for (int a = 0; a < 3; ++a) {
        float t0 = (b.lo[a] - org[a]) * invDir[a];
        float t1 = (b.hi[a] - org[a]) * invDir[a];
        if (t0 > t1) {
            float t = t0;
            t0 = t1;
            t1 = t;
        }
        // NaN (0 * inf on a slab boundary) compares false and leaves the interval unchanged.
        tMin = t0 > tMin ? t0 : tMin;
        tMax = t1 < tMax ? t1 : tMax;
    }
    return tMin <= tMax;
}

}  // namespace uvr
