// SPDX-License-Identifier: MIT
#pragma once

// The plain-data types every integrator shares, on the CPU and the GPU: the compositing
// parameters, the scene a ray reads and the counters it keeps.

#include <cmath>
#include <cstdint>

#include "uvr/accel/point_locator.h"
#include "uvr/core/bounds.h"
#include "uvr/render/clip.h"
#include "uvr/render/isosurface.h"
#include "uvr/render/lighting.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

/// Compositing parameters shared by every integrator.
struct MarchParams {
    float step = 0.f;                ///< sample spacing s1 along the ray (world units)
    float opacityUnit = 1.f;         ///< distance over which a TF opacity applies (ParaView's unit)
    float terminationAlpha = 0.99f;  ///< early ray termination threshold on accumulated opacity
    /// Integrate between consecutive samples with the scalar linear from one to the next
    /// (SampleSegments) instead of point samples with opacity correction.
    bool preintegrated = true;
    /// The clip region: each ray integrates only its part inside (none: the whole ray).
    ClipView clip;
    /// A data-parallel frame's piece of the ray (none: the whole ray).
    PieceView piece;
    /// Gradient shading (off: the transfer function's colours as they are).
    Lighting light;
    /// Gradient opacity (off: the transfer function's opacity as it is), magnitudes in
    /// rendering units.
    GradientOpacity gradientOpacity;
    /// Isosurfaces inside the volume (none: the volume alone).
    IsoView iso;
    /// Depth out: each ray reports where its accumulated opacity first reaches this (0: no
    /// depth asked for; RayCounters::depth).
    float depthAlpha = 0.f;
};

/// The sampling integrators' `stop` argument for a ray that stops at the scene's
/// MarchParams::terminationAlpha (any other value in (0, 1] is that ray's own stop: a
/// data-parallel rank's ray behind others stops where one process's would; FrameView::stopAlpha).
inline constexpr float kSceneStop = -1.f;

/// Whether a frame runs the integrators' instances with isosurfaces, depth and the clip's cut
/// face (kSurf).
UVR_HOST_DEVICE inline bool surfacesKernel(const MarchParams& p) {
    return p.iso.active() || p.depthAlpha > 0.f || (p.clip.surface && p.clip.active());
}

/// Whether a frame runs the integrators' lit instances (kLit): shaded or with a gradient opacity
/// (readsGradient). The surfaces' instances light their surfaces either way.
UVR_HOST_DEVICE inline bool litKernel(const MarchParams& p) {
    return readsGradient(p.light, p.gradientOpacity);
}

/// Everything a ray needs, as plain data for CPU and GPU.
struct SceneView {
    TetLocator locator;
    TfTableView tf;
    Bounds3f bounds;
    MarchParams params;
};

/// Per-ray counters, and the ray's depth.
struct RayCounters {
    std::uint32_t samples = 0;            ///< samples taken (point locations)
    std::uint32_t partitionsVisited = 0;  ///< k-d partitions the ray entered
    std::uint32_t partitionsSkipped = 0;  ///< of those, skipped as fully transparent
    LocateCounters locate;
    /// Depth out (MarchParams::depthAlpha): the ray parameter where the accumulated opacity
    /// first reached it; infinity where it never did.
    float depth = INFINITY;
    /// Depth out, in: the opacity whose depth this ray notes, when it is its own (a
    /// data-parallel rank's pixel behind others' light: FrameView::depthAlphas; 0: none);
    /// negative: the frame's, MarchParams::depthAlpha (rayDepthAlpha).
    float depthAlpha = -1.f;
};

/// The opacity whose depth a ray notes: its own (RayCounters::depthAlpha) or the frame's.
UVR_HOST_DEVICE inline float rayDepthAlpha(const MarchParams& p, const RayCounters& c) {
    return c.depthAlpha >= 0.f ? c.depthAlpha : p.depthAlpha;
}

/// Depth out: a stretch [t0, t1] of the ray took the accumulated opacity from a0 to a1; where
/// that first reaches `alpha` (> 0) the ray's depth is noted, read within the stretch as if its
/// extinction were constant (the optical depth -ln(1 - a) linear in t: exact for a constant
/// extinction; an opaque surface, t0 = t1, is where it is).
UVR_HOST_DEVICE inline void noteDepth(float alpha, float a0, float a1, float t0, float t1,
                                      RayCounters& c) {
    if (!(alpha > 0.f) || c.depth < INFINITY || !(a1 >= alpha)) return;
    float f = 0.f;
    if (a1 < 1.f && a1 > a0) {
        const float tau0 = -log1pf(-a0), tau1 = -log1pf(-a1), tau = -log1pf(-alpha);
        f = (tau - tau0) / (tau1 - tau0);
    }
    f = f > 0.f ? (f < 1.f ? f : 1.f) : 0.f;  // also NaN
    c.depth = t0 + (t1 - t0) * f;
}

}  // namespace uvr
