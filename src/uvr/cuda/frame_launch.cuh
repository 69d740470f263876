// SPDX-License-Identifier: MIT
#pragma once

// The frame kernels: one thread per pixel runs the shared pixel body (render/frame_kernel.h)
// with an integrator's functor. Each method's eight instances (dispatchKernel) are compiled in a
// translation unit of their own (frame_reference.cu, frame_exact.cu, frame_partitions.cu), so
// the three compile in parallel; cuda_renderer.cu calls launchReference, launchExact and
// launchPartitions.

#include <chrono>
#include <cstdint>

#include "uvr/cuda/launch.cuh"
#include "uvr/render/frame_kernel.h"

namespace uvr::cuda {

/// Counters summed over a frame: samples, walk steps, BVH queries, partitions visited, skipped.
constexpr int kCounters = 5;

/// Threads per frame block (16 x 8 pixels) and the blocks per multiprocessor the frame kernels
/// are compiled for: 4 caps them at 128 registers (the partition kernel needed 134, which let
/// only 3 blocks run per multiprocessor).
constexpr int kFrameBlock = 128;
constexpr int kFrameBlocksPerSm = 4;

/// Blocks per multiprocessor of a march's frame kernel: kFrameBlocksPerSm, but 2 (255
/// registers) for the partition integrator with surfaces. At 128 registers it spilled about
/// 2 KB around its non-inlined surface calls, at 255 about 0.1 KB, and the 100M isosurface
/// frames got 6% faster on an H200; the reference's instance with surfaces got 20% slower at 2,
/// so it stays at 4 (PERFORMANCE.md, "Isosurfaces: the surface calls on copies, and 255
/// registers").
template <class March>
inline constexpr int kBlocksPerSm = kFrameBlocksPerSm;
template <bool kNative, bool kLit>
inline constexpr int kBlocksPerSm<PartitionMarch<kNative, kLit, true>> = 2;

/// Kernel: one thread per pixel runs the shared pixel body, then the warp sums its counters.
/// The frame and the integrator are __grid_constant__: the integrators pass references into
/// them to functions not inlined (sampleAtBoundary), which otherwise made the kernel copy them
/// to local memory (the plain reference kernel's stack 1216 -> 2304 bytes, and its loop read
/// the copy).
template <bool Supersampled, class March>
__global__ void __launch_bounds__(kFrameBlock, kBlocksPerSm<March>)
    frameKernel(const __grid_constant__ FrameView frame, const __grid_constant__ March march,
                unsigned long long* totals) {
    const int x = blockIdx.x * blockDim.x + threadIdx.x;
    const int y = blockIdx.y * blockDim.y + threadIdx.y;
    RayCounters c;
    if (x < frame.width && y < frame.height) c = shadePixel<Supersampled>(frame, x, y, march);
    unsigned long long v[kCounters] = {c.samples, c.locate.walkSteps, c.locate.bvhQueries,
                                       c.partitionsVisited, c.partitionsSkipped};
    const unsigned lane = (threadIdx.y * blockDim.x + threadIdx.x) % 32u;
    for (int k = 0; k < kCounters; ++k) {
        for (int offset = 16; offset > 0; offset /= 2)
            v[k] += __shfl_down_sync(0xffffffffu, v[k], offset);
        if (lane == 0 && v[k]) atomicAdd(&totals[k], v[k]);
    }
}

/// Launches the frame kernel for the frame's rays per pixel: the one-ray body when it has one.
template <class March>
void launchFrame(dim3 grid, dim3 block, const FrameView& frame, const March& march,
                 unsigned long long* totals) {
    const auto start = std::chrono::steady_clock::now();
    if (frame.supersample == 1)
        frameKernel<false><<<grid, block>>>(frame, march, totals);
    else
        frameKernel<true><<<grid, block>>>(frame, march, totals);
    finishLaunch("frame", std::uint64_t(frame.width) * std::uint64_t(frame.height), start);
}

/// The frame kernel of each method, for the frame's instance: native cells (the mesh has any),
/// lit (litKernel) and surfaces (surfacesKernel); `totals` receives the kCounters sums.
void launchReference(dim3 grid, dim3 block, const FrameView& frame, const SceneView& scene,
                     bool native, bool lit, bool surfaces, unsigned long long* totals);
void launchExact(dim3 grid, dim3 block, const FrameView& frame, const SceneView& scene, bool native,
                 bool lit, bool surfaces, unsigned long long* totals);
void launchPartitions(dim3 grid, dim3 block, const FrameView& frame,
                      const PartitionSceneView& scene, bool native, bool lit, bool surfaces,
                      unsigned long long* totals);

}  // namespace uvr::cuda
