// SPDX-License-Identifier: MIT
// The partitions method's frame kernels (frame_launch.cuh): eight instances, compiled on their own.
#include "uvr/cuda/frame_launch.cuh"

namespace uvr::cuda {

void launchPartitions(dim3 grid, dim3 block, const FrameView& frame,
                      const PartitionSceneView& scene, bool native, bool lit, bool surfaces,
                      unsigned long long* totals) {
    dispatchKernel(native, lit, surfaces, [&](auto kNative, auto kLit, auto kSurf) {
        launchPartitionMarches<kNative(), kLit(), kSurf()>(
            scene, isoRaySplit(scene.base.params, frame), [&](const auto&... marches) {
                (launchFrame(grid, block, frame, marches, totals), ...);
            });
    });
}

}  // namespace uvr::cuda
