// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <type_traits>

#include "uvr/core/host_device.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/camera.h"
#include "uvr/render/exact_integrator.h"
#include "uvr/render/reference_marcher.h"

namespace uvr {

/// Output buffers of one frame, as plain data.
struct FrameView {
    Vec4f* pixels = nullptr;                ///< width * height, premultiplied RGBA
    std::uint32_t* sampleCounts = nullptr;  ///< width * height samples per pixel (all its rays)
    int width = 0;
    int height = 0;
    CameraRays rays;
    int supersample = 1;  ///< N: N x N rays per pixel, in [1, kMaxSupersample]
    bool jitter = false;  ///< each ray at a hashed position in its sub-pixel cell, not its centre
    /// Depth out (null: none): per pixel the view depth where the ray's opacity first reached
    /// MarchParams::depthAlpha (RayCounters::depth), the nearest over the pixel's rays.
    float* depth = nullptr;
    /// Depth in (null: none): per pixel the view depth of opaque geometry: the rays end there.
    const float* depthIn = nullptr;
    /// Stop in (null: none; RenderSettings::pixelStopAlpha): per pixel the accumulated opacity
    /// at which its ray stops (the sampling methods); 0: the pixel is left transparent, without
    /// a ray. One ray per pixel (supersample 1).
    const float* stopAlpha = nullptr;
    /// Depth alpha in (null: the frame's; RenderSettings::pixelDepthAlpha): per pixel the
    /// opacity whose depth its ray notes (0: none). One ray per pixel (supersample 1).
    const float* depthAlphas = nullptr;
    /// View depths (file units) from ray parameters (rendering units): z = (rayStartDepth + t
    /// dot(dir, viewDirection)) / depthScale.
    Vec3f viewDirection{0.f, 0.f, -1.f};
    float rayStartDepth = 0.f;
    float depthScale = 1.f;

    /// The view depth of parameter t of ray r (infinity for an infinite t).
    UVR_HOST_DEVICE float viewDepth(const Ray& r, float t) const {
        return t < INFINITY ? (rayStartDepth + t * dot(r.dir, viewDirection)) / depthScale
                            : INFINITY;
    }
    /// The parameter of ray r at view depth z (infinity for none: an infinite or NaN z).
    UVR_HOST_DEVICE float rayParameter(const Ray& r, float z) const {
        const float c = dot(r.dir, viewDirection);
        return z < INFINITY && c > 0.f ? (z * depthScale - rayStartDepth) / c : INFINITY;
    }
};

/// A 32-bit integer hash (lowbias32, Wellons 2018: a bijection with low bias).
UVR_HOST_DEVICE inline std::uint32_t hashU32(std::uint32_t v) {
    v ^= v >> 16;
    v *= 0x7feb352dU;
    v ^= v >> 15;
    v *= 0x846ca68bU;
    v ^= v >> 16;
    return v;
}

/// Sub-pixel offsets in [0, 1)^2 of ray `s` of pixel (x, y) for jittered supersampling: a fixed
/// hash of the three (no random state), so every frame and both devices take the same rays.
UVR_HOST_DEVICE inline void jitterOffsets(int x, int y, int s, float& ox, float& oy) {
    const std::uint32_t h =
        hashU32(static_cast<std::uint32_t>(x) +
                hashU32(static_cast<std::uint32_t>(y) + hashU32(static_cast<std::uint32_t>(s))));
    // 16 bits each: exact in float and below 1.
    ox = static_cast<float>(h & 0xffffU) * (1.f / 65536.f);
    oy = static_cast<float>(h >> 16) * (1.f / 65536.f);
}

/// Kernel body for one pixel: traces its N x N rays (frame.supersample; one through the centre
/// of each cell of an N x N grid over the pixel, or jittered within it) with
/// `march(ray, counters, stop)` (stop: kSceneStop, or frame.stopAlpha's with one ray), stores the
/// mean premultiplied colour and the samples summed over the rays, and returns the counters summed
/// over the rays. With N = 1 the one ray passes through the pixel's centre and the pixel is exactly
/// that ray's colour. CPU and CUDA backends launch it. The rays run one after another in this
/// thread, so no buffer grows with N. Supersampled false is the one-ray body (frame.supersample
/// must be 1): without the loop's sums live across the integrator, the GPU kernels keep their
/// registers (the loop cost the partition kernel 7%).
template <bool Supersampled = true, class March>
UVR_HOST_DEVICE inline RayCounters shadePixel(const FrameView& frame, int x, int y, March&& march) {
    const std::size_t i = static_cast<std::size_t>(y) * frame.width + x;
    if constexpr (!Supersampled) {
        Ray ray = frame.rays.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
        if (frame.depthIn) ray.tMax = frame.rayParameter(ray, frame.depthIn[i]);
        RayCounters counters;
        if constexpr (requires { march.shades(ray); }) {
            if (!march.shades(ray)) return counters;  // another launch's pixel (RaySplit)
        }
        if (frame.depthAlphas) counters.depthAlpha = frame.depthAlphas[i];
        const float stop = frame.stopAlpha ? frame.stopAlpha[i] : kSceneStop;
        if (!(stop != 0.f)) {  // not rendered (a data-parallel second pass's other pixels)
            frame.pixels[i] = Vec4f(0.f, 0.f, 0.f, 0.f);
            frame.sampleCounts[i] = 0;
            if (frame.depth) frame.depth[i] = INFINITY;
            return counters;
        }
        const Vec4f c = march(ray, counters, stop);
        frame.pixels[i] = c;
        frame.sampleCounts[i] = counters.samples;
        if (frame.depth) frame.depth[i] = frame.viewDepth(ray, counters.depth);
        return counters;
    }
    const int n = frame.supersample;
    const float cell = 1.f / static_cast<float>(n);
    Vec4f sum(0.f, 0.f, 0.f, 0.f);
    RayCounters total;
    float nearest = INFINITY;
    for (int s = 0; s < n * n; ++s) {
        float ox = 0.5f, oy = 0.5f;
        if (frame.jitter) jitterOffsets(x, y, s, ox, oy);
        const float px = static_cast<float>(x) + (static_cast<float>(s % n) + ox) * cell;
        const float py = static_cast<float>(y) + (static_cast<float>(s / n) + oy) * cell;
        RayCounters counters;
        Ray ray = frame.rays.ray(px, py);
        if (frame.depthIn) ray.tMax = frame.rayParameter(ray, frame.depthIn[i]);
        sum = sum + march(ray, counters, kSceneStop);
        if (frame.depth) {
            const float z = frame.viewDepth(ray, counters.depth);
            nearest = z < nearest ? z : nearest;
        }
        total.samples += counters.samples;
        total.partitionsVisited += counters.partitionsVisited;
        total.partitionsSkipped += counters.partitionsSkipped;
        total.locate.walkSteps += counters.locate.walkSteps;
        total.locate.bvhQueries += counters.locate.bvhQueries;
    }
    frame.pixels[i] = sum * (cell * cell);
    frame.sampleCounts[i] = total.samples;
    if (frame.depth) frame.depth[i] = nearest;
    return total;
}

/// The reference marcher as a functor for shadePixel (lambdas do not cross to CUDA kernels).
///
/// The integrator functors take kNative false for meshes of tetrahedra only: their kernels are
/// compiled without the native cells' code (dispatchKernel picks the instance), which costs
/// tetrahedra 10-30% of their frame time on the GPU when present; kLit false for frames
/// without shading (without the lighting code: up to 21% of the adaptive kernel's time); kSurf
/// false for frames without isosurfaces or depth.
template <bool kNative = true, bool kLit = true, bool kSurf = kLit>
struct ReferenceMarch {
    SceneView scene;
    UVR_HOST_DEVICE Vec4f operator()(const Ray& ray, RayCounters& counters, float stop) const {
        return marchReference<kNative, kLit, kSurf>(scene, ray, counters, stop);
    }
};

/// The exact integrator as a functor for shadePixel (its "samples" are tetrahedra crossed; its
/// rays run on to segment::kOpacityEnd, whatever the stop).
template <bool kNative = true, bool kLit = true, bool kSurf = kLit>
struct ExactMarch {
    SceneView scene;
    UVR_HOST_DEVICE Vec4f operator()(const Ray& ray, RayCounters& counters, float) const {
        return integrateExact<kNative, kLit, kSurf>(scene, ray, counters);
    }
};

/// Which of a frame's rays a launch of the partition integrator shades (isoRaySplit).
enum class RaySplit : std::uint8_t {
    All,              ///< every ray
    WithoutSurfaces,  ///< the rays that cannot meet an isosurface (mayMeetIsosurface)
    WithSurfaces,     ///< the others
};

/// The partition integrator as a functor for shadePixel; a launch split by RaySplit leaves the
/// other launch's pixels untouched.
template <bool kNative = true, bool kLit = true, bool kSurf = kLit>
struct PartitionMarch {
    PartitionSceneView scene;
    RaySplit split = RaySplit::All;
    UVR_HOST_DEVICE bool shades(const Ray& ray) const {
        return split == RaySplit::All ||
               (split == RaySplit::WithSurfaces) == mayMeetIsosurface(scene, ray);
    }
    UVR_HOST_DEVICE Vec4f operator()(const Ray& ray, RayCounters& counters, float stop) const {
        return marchPartitions<kNative, kLit, kSurf>(scene, ray, counters, stop);
    }
};

/// Whether a frame of the partition integrator splits its rays (RaySplit): where isosurfaces
/// are its only surfaces (no depth out, no cut face), with one ray per pixel and the whole ray in
/// one process (a data-parallel piece's run goes on into its neighbours', whose partitions it
/// does not see). The surfaces' code costs every sample of the instance with surfaces, whether
/// its ray meets a surface or not (PERFORMANCE.md, "Isosurfaces: what the surfaces' code costs a
/// frame with no surface"): a split frame marches the rays that cannot meet one with the
/// instance without it, in a launch of its own (on the GPU, at that kernel's occupancy).
UVR_HOST_DEVICE inline bool isoRaySplit(const MarchParams& p, const FrameView& frame) {
    return p.iso.active() && !(p.depthAlpha > 0.f) && !(p.clip.surface && p.clip.active()) &&
           !p.piece.active && frame.supersample == 1 && !frame.depth && !frame.depthAlphas;
}

/// Calls launch(marches...) with the partition integrator's functors for a frame's instance
/// (kNative, kLit, kSurf): the one functor, or, where isoRaySplit, the instance without surfaces
/// for the rays that cannot meet one and the instance with them for the others (each shades
/// only its rays). The CPU shades each pixel with both in turn; the GPU launches them one after
/// the other.
template <bool kNative, bool kLit, bool kSurf, class Launch>
void launchPartitionMarches(const PartitionSceneView& scene, bool split, Launch&& launch) {
    if constexpr (kSurf) {
        if (split) {
            launch(PartitionMarch<kNative, kLit, false>{scene, RaySplit::WithoutSurfaces},
                   PartitionMarch<kNative, kLit, true>{scene, RaySplit::WithSurfaces});
            return;
        }
    }
    launch(PartitionMarch<kNative, kLit, kSurf>{scene});
}

/// Calls f(kNative, kLit, kSurf) with std::true_type or std::false_type for each: kNative when
/// the mesh has native cells; kLit when the frame is shaded (or has a gradient opacity); kSurf
/// when it has isosurfaces, a cut face or writes depth (the integrator functors' parameters: each
/// compiled eight times, so a frame runs without the code it does not need; the isosurfaces' and
/// depth's code in the shaded kernels cost them 40-90% on the H200, and the volume's lighting
/// code cost an unshaded frame with isosurfaces, which lights only them, 9% on the H100).
template <typename F>
void dispatchKernel(bool hasNative, bool lit, bool surfaces, F&& f) {
    auto withExtras = [&](auto kNative) {
        if (surfaces && lit)
            f(kNative, std::true_type{}, std::true_type{});
        else if (surfaces)
            f(kNative, std::false_type{}, std::true_type{});
        else if (lit)
            f(kNative, std::true_type{}, std::false_type{});
        else
            f(kNative, std::false_type{}, std::false_type{});
    };
    if (hasNative)
        withExtras(std::true_type{});
    else
        withExtras(std::false_type{});
}

}  // namespace uvr
