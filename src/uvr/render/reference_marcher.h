// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>
#include <cstdint>

#include "uvr/accel/point_locator.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/render/camera.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

/// Compositing parameters shared by every integrator.
struct MarchParams {
    float step = 0.f;                ///< sample spacing s1 along the ray (world units)
    float opacityUnit = 1.f;         ///< distance over which a TF opacity applies (ParaView's unit)
    float terminationAlpha = 0.99f;  ///< early ray termination threshold on accumulated opacity
};

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

/// Opacity of a sample taken over distance `step` for a TF opacity `alpha` defined per `unit`:
/// 1 - (1 - alpha)^(step / unit) (opacity correction).
UVR_HOST_DEVICE inline float correctOpacity(float alpha, float step, float unit) {
    if (alpha >= 1.f) return 1.f;
    if (alpha <= 0.f) return 0.f;
    return 1.f - powf(1.f - alpha, step / unit);
}

/// Front-to-back "over" compositing of a straight colour with corrected opacity a into the
/// premultiplied accumulator.
UVR_HOST_DEVICE inline void compositeFrontToBack(Vec4f& acc, Vec3f rgb, float a) {
    const float w = (1.f - acc.w) * a;
    acc.x += w * rgb.x;
    acc.y += w * rgb.y;
    acc.z += w * rgb.z;
    acc.w += w;
}

/// The reference ray marcher: samples at fixed spacing s1 on the global grid t = k * s1 between
/// the ray's entry into and exit from the mesh bounds, locates each sample's tetrahedron
/// (previous tetrahedron first), interpolates barycentrically, classifies through the transfer
/// function, composites front to back with opacity correction and stops early once opaque.
UVR_HOST_DEVICE inline Vec4f marchReference(const SceneView& scene, const Ray& ray,
                                            RayCounters& counters) {
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    float t0 = 0.f, t1 = INFINITY;
    // An empty mesh has inverted bounds, which every ray would "cross" from -FLT_MAX to FLT_MAX.
    if (scene.bounds.empty() || !intersectBox(scene.bounds, ray.org, inv, t0, t1)) return acc;
    const float s = scene.params.step;
    // Global sample grid k * s, so every integrator that samples a span takes the same samples.
    float k = ceilf(t0 / s);
    const float kEnd = floorf(t1 / s);
    std::uint32_t tet = kNoTet;
    float bary[4];
    for (; k <= kEnd; k += 1.f) {
        const Vec3f p = ray.at(k * s);
        ++counters.samples;
        tet = scene.locator.locate(p, tet, bary, counters.locate);
        if (tet == kNoTet) continue;
        const float v = scene.locator.mesh.interpolate(tet, bary);
        const Vec4f c = scene.tf.sample(v);
        const float a = correctOpacity(c.w, s, scene.params.opacityUnit);
        if (a <= 0.f) continue;
        compositeFrontToBack(acc, c.xyz(), a);
        if (acc.w >= scene.params.terminationAlpha) break;
    }
    return acc;
}

}  // namespace uvr
