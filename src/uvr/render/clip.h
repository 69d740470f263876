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
    /// The cut face as an opaque surface (RenderSettings::clipSurface): where a ray's part
    /// inside the region starts or ends on a plane or the box inside the mesh, the surface there
    /// is coloured by the transfer function at the field's value and lit with the face's normal.
    bool surface = false;

    UVR_HOST_DEVICE bool active() const { return planeCount > 0 || hasBox; }

    /// Narrows [t0, t1] of the ray org + t dir to its part inside the region; false when none
    /// is left. invDir is 1 / dir per component (as intersectBox takes it).
    UVR_HOST_DEVICE bool restrict(Vec3f org, Vec3f dir, Vec3f invDir, float& t0, float& t1) const {
        bool cut0, cut1;
        Vec3f n0, n1;
        return narrow<false>(org, dir, invDir, t0, t1, cut0, n0, cut1, n1);
    }

    /// restrict, and which ends of [t0, t1] the region moved onto one of its faces: cut0 (cut1)
    /// with that face's normal n0 (n1); an end the region left where it was keeps false.
    UVR_HOST_DEVICE bool restrictFaces(Vec3f org, Vec3f dir, Vec3f invDir, float& t0, float& t1,
                                       bool& cut0, Vec3f& n0, bool& cut1, Vec3f& n1) const {
        return narrow<true>(org, dir, invDir, t0, t1, cut0, n0, cut1, n1);
    }

private:
    /// restrict (kFaces false: the faces are not tracked) or restrictFaces.
    template <bool kFaces>
    UVR_HOST_DEVICE bool narrow(Vec3f org, Vec3f dir, Vec3f invDir, float& t0, float& t1,
                                bool& cut0, Vec3f& n0, bool& cut1, Vec3f& n1) const {
        cut0 = cut1 = false;
        if (hasBox) {
            if constexpr (kFaces) {
                for (int a = 0; a < 3; ++a) {
                    const float ta = (box.lo[a] - org[a]) * invDir[a];
                    const float tb = (box.hi[a] - org[a]) * invDir[a];
                    const float tNear = ta < tb ? ta : tb, tFar = ta < tb ? tb : ta;
                    Vec3f axis(0.f, 0.f, 0.f);
                    axis[a] = 1.f;
                    if (tNear > t0) t0 = tNear, cut0 = true, n0 = axis;
                    if (tFar < t1) t1 = tFar, cut1 = true, n1 = axis;
                }
            } else if (!intersectBox(box, org, invDir, t0, t1)) {
                return false;
            }
        }
        for (int i = 0; i < planeCount; ++i) {
            const ClipPlane& p = planes[i];
            // dot(n, org + t dir - o) = a + t b >= 0.
            const float a = dot(p.normal, org - p.origin);
            const float b = dot(p.normal, dir);
            if (b > 0.f) {
                const float t = -a / b;
                if (t > t0) {
                    t0 = t;
                    if constexpr (kFaces) cut0 = true, n0 = p.normal;
                }
            } else if (b < 0.f) {
                const float t = -a / b;
                if (t < t1) {
                    t1 = t;
                    if constexpr (kFaces) cut1 = true, n1 = p.normal;
                }
            } else if (a < 0.f) {
                return false;  // parallel to the plane, on the clipped side
            }
        }
        return t0 <= t1;
    }
};

/// A data-parallel frame's piece (issue 31, dist/): the box of the whole mesh's k-d tree that
/// this rank renders. A ray integrates only its part inside the box, so the ranks' parts of a
/// ray meet end to end and composite, front to back, into the whole ray. Where the box cuts a
/// ray's end inside the mesh the span goes on in the next rank's piece: the sampling
/// integrators leave the sample on the grid point there to that rank and take it only to end
/// their last segment (ReferenceMarch: the segment's far value, as one process takes it).
struct PieceView {
    bool active = false;
    Bounds3f box;  ///< the rank's box (rendering units), with active

    /// Narrows [t0, t1] of the ray org + t dir to the box (nothing without one); startCut
    /// (endCut): the box moved that end, so the ray's span goes on in another piece there. False
    /// when nothing is left. Computed as intersectBox, so the ends are the k-d traversal's
    /// split-plane crossings bit for bit.
    UVR_HOST_DEVICE bool narrow(Vec3f org, Vec3f invDir, float& t0, float& t1, bool& startCut,
                                bool& endCut) const {
        startCut = endCut = false;
        if (!active) return t0 <= t1;
        float a = t0, b = t1;
        if (!intersectBox(box, org, invDir, a, b)) return false;
        startCut = a > t0, endCut = b < t1;
        t0 = a, t1 = b;
        return t0 <= t1;
    }
};

}  // namespace uvr
