// SPDX-License-Identifier: MIT
#pragma once

// The CUDA device as the front ends see it: whether there is one, its name, its warm-up, and the
// partition size GPU rendering wants. Nothing here names the backend's types (uvr.h includes only
// this of cuda/).

#include <cstdint>
#include <string>

namespace uvr {

/// Default cells per k-d partition for GPU rendering: the GPU pays per partition a ray crosses
/// more than per sample, so it wants far fewer partitions than the CPU (measured on an H200: at
/// s2 = 16 s1, 65536 gave 1.5x over the reference on a 12M-tet mesh where 1024 gave 0.86x;
/// docs/PERFORMANCE.md).
inline constexpr std::uint32_t kCudaDefaultLeafCells = 65536;

/// True when this uvr was built with CUDA and a CUDA device can be used.
bool cudaDeviceAvailable();

/// One line naming the CUDA device and its memory, or why there is none.
std::string cudaDeviceDescription();

/// Starts initialising CUDA (the driver and the device's context) on a background thread, so
/// that it overlaps other work such as reading a mesh; does nothing when it runs already, when
/// uvr was built without CUDA, or when no thread can start. Errors there are dropped: the same
/// calls report them again where uvr first uses CUDA. cudaDeviceAvailable and
/// cudaDeviceDescription (which every CUDA entry point of uvr calls first) wait for it.
void startCudaWarmUp();

/// Waits for startCudaWarmUp's thread when one runs (call it before the process exits).
void finishCudaWarmUp();

/// Device memory held by uvr's arrays in this process (renderers' scenes, builders' scratch).
struct CudaMemoryUse {
    std::uint64_t bytes = 0;      ///< held now
    std::uint64_t peakBytes = 0;  ///< the most held at once since resetCudaMemoryPeak
};
/// What uvr's arrays hold on the GPU now and at most (zeros in a build without CUDA).
CudaMemoryUse cudaMemoryUse();
/// Starts a new peak from what is held now.
void resetCudaMemoryPeak();
/// The most device memory uvr's arrays may hold at once (0: no limit but the card's). An
/// allocation that would pass it fails as one the card cannot hold does (Error(Resource)), so a
/// test can see what a smaller card does.
void setCudaMemoryLimit(std::uint64_t bytes);

}  // namespace uvr
