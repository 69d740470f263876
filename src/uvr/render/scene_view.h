// SPDX-License-Identifier: MIT
#pragma once

// The plain-data types every integrator shares, on the CPU and the GPU: the compositing
// parameters, the scene a ray reads and the counters it keeps.

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
    /// Gradient shading (off: the transfer function's colours as they are).
    Lighting light;
    /// Isosurfaces inside the volume (none: the volume alone).
    IsoView iso;
};

/// Whether a frame runs the integrators' lit instances (kLit): shaded, or with isosurfaces
/// (which are always lit and need the gradients).
UVR_HOST_DEVICE inline bool litKernel(const MarchParams& p) {
    return p.light.on || p.iso.active();
}

/// Everything a ray needs, as plain data for CPU and GPU.
struct SceneView {
    TetLocator locator;
    TfTableView tf;
    Bounds3f bounds;
    MarchParams params;
};

/// Per-ray counters.
struct RayCounters {
    std::uint32_t samples = 0;            ///< samples taken (point locations)
    std::uint32_t partitionsVisited = 0;  ///< k-d partitions the ray entered
    std::uint32_t partitionsSkipped = 0;  ///< of those, skipped as fully transparent
    LocateCounters locate;
};

}  // namespace uvr
