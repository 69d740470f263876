// SPDX-License-Identifier: MIT
#pragma once

// Clipping the volume (issue 32): up to kMaxClipPlanes half-spaces and a box, as plain data every
// integrator reads on the CPU and the GPU. A ray keeps the one interval of its path inside all of
// them (they are convex), so each integrator integrates exactly that part: the exact integrator
// cuts the cells at the planes, the sampling methods take the samples inside.

#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

/// Most clip planes a frame takes (ParaView's volume mappers take six).
inline constexpr int kMaxClipPlanes = 6;

/// One clip plane in the renderer's coordinates: the kept side is where
/// dot(normal, x - origin) >= 0 (the side the normal points to, as VTK's volume mappers keep).
struct ClipPlane {
    Vec3f origin{0.f, 0.f, 0.f};
    Vec3f normal{1.f, 0.f, 0.f};
};

/// The clip region of a frame: the intersection of its planes' kept sides and its box (when it
/// has one). None of either: nothing is clipped.
struct ClipView {
    ClipPlane planes[kMaxClipPlanes];
    int planeCount = 0;
    bool hasBox = false;
    Bounds3f box;  ///< kept inside, with hasBox

    UVR_HOST_DEVICE bool active() const { return planeCount > 0 || hasBox; }

    /// Narrows [t0, t1] of the ray org + t dir to its part inside the region; false when none
    /// is left. invDir is 1 / dir per component (as intersectBox takes it).
    UVR_HOST_DEVICE bool restrict(Vec3f org, Vec3f dir, Vec3f invDir, float& t0, float& t1) const {
        if (hasBox && !intersectBox(box, org, invDir, t0, t1)) return false;
        for (int i = 0; i < planeCount; ++i) {
            const ClipPlane& p = planes[i];
            // dot(n, org + t dir - o) = a + t b >= 0.
            const float a = dot(p.normal, org - p.origin);
            const float b = dot(p.normal, dir);
            if (b > 0.f) {
                const float t = -a / b;
                t0 = t > t0 ? t : t0;
            } else if (b < 0.f) {
                const float t = -a / b;
                t1 = t < t1 ? t : t1;
            } else if (a < 0.f) {
                return false;  // parallel to the plane, on the clipped side
            }
        }
        return t0 <= t1;
    }
};

}  // namespace uvr
