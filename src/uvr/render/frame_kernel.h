// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>

#include "uvr/core/host_device.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/camera.h"
#include "uvr/render/exact_integrator.h"
#include "uvr/render/reference_marcher.h"

namespace uvr {

/// Output buffers of one frame, as plain data.
struct FrameView {
    Vec4f* pixels = nullptr;                ///< width * height, premultiplied RGBA
    std::uint32_t* sampleCounts = nullptr;  ///< width * height samples per pixel
    int width = 0;
    int height = 0;
    CameraRays rays;
};

/// Kernel body for one pixel: traces the pixel's centre ray with `march(ray, counters)`, stores
/// colour and sample count, returns the ray's counters. CPU and CUDA backends launch it.
template <class March>
UVR_HOST_DEVICE inline RayCounters shadePixel(const FrameView& frame, int x, int y, March&& march) {
    const Ray ray = frame.rays.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
    RayCounters counters;
    const Vec4f c = march(ray, counters);
    const std::size_t i = static_cast<std::size_t>(y) * frame.width + x;
    frame.pixels[i] = c;
    frame.sampleCounts[i] = counters.samples;
    return counters;
}

/// The reference marcher as a functor for shadePixel (lambdas do not cross to CUDA kernels).
struct ReferenceMarch {
    SceneView scene;
    UVR_HOST_DEVICE Vec4f operator()(const Ray& ray, RayCounters& counters) const {
        return marchReference(scene, ray, counters);
    }
};

/// The exact integrator as a functor for shadePixel (its "samples" are tetrahedra crossed).
struct ExactMarch {
    SceneView scene;
    UVR_HOST_DEVICE Vec4f operator()(const Ray& ray, RayCounters& counters) const {
        return integrateExact(scene, ray, counters);
    }
};

/// The partition integrator as a functor for shadePixel.
struct PartitionMarch {
    PartitionSceneView scene;
    UVR_HOST_DEVICE Vec4f operator()(const Ray& ray, RayCounters& counters) const {
        return marchPartitions(scene, ray, counters);
    }
};

}  // namespace uvr
