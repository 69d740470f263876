// SPDX-License-Identifier: MIT
// The reference method's frame kernels (frame_launch.cuh): eight instances, compiled on their own.
#include "uvr/cuda/frame_launch.cuh"

namespace uvr::cuda {

void launchReference(dim3 grid, dim3 block, const FrameView& frame, const SceneView& scene,
                     bool native, bool lit, bool surfaces, unsigned long long* totals) {
    dispatchKernel(native, lit, surfaces, [&](auto kNative, auto kLit, auto kSurf) {
        launchFrame(grid, block, frame, ReferenceMarch<kNative(), kLit(), kSurf()>{scene}, totals);
    });
}

}  // namespace uvr::cuda
