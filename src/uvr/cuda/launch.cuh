// SPDX-License-Identifier: MIT
#pragma once

// Launch helpers of the GPU builders (CUDA sources only).

#include <cstddef>
#include <cstdint>

#include "uvr/cuda/cuda_check.h"

namespace uvr::cuda {

/// Threads per block of the builders' one-thread-per-element kernels.
inline constexpr int kBlock = 256;

/// This thread's index over the whole grid.
__device__ inline std::uint64_t globalThread() {
    return static_cast<std::uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
}

/// Blocks of kBlock threads covering n elements.
inline int blocksFor(std::uint64_t n) {
    return static_cast<int>((n + kBlock - 1) / kBlock);
}

/// Runs a CUB device call the two-phase way: call(nullptr, bytes) asks for its scratch size,
/// then call(scratch, bytes) runs with `temp` grown to it (`what` names it when memory runs out).
template <class Call>
void withScratch(DeviceArray<unsigned char>& temp, const char* what, Call&& call) {
    std::size_t bytes = 0;
    UVR_CUDA_CHECK(call(nullptr, bytes));
    temp.reserve(bytes, what);
    UVR_CUDA_CHECK(call(temp.data(), bytes));
}

}  // namespace uvr::cuda
