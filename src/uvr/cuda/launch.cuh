// SPDX-License-Identifier: MIT
#pragma once

// Launch helpers of the GPU code (CUDA sources only): forEachElement, the one launcher of the
// one-thread-per-element kernels, and finishLaunch, which every launch ends with. A launch is
// named: a bad configuration or (with UVR_CUDA_SYNC=1) a fault inside the kernel is reported
// with its name, and UVR_CUDA_SYNC=1 prints each launch's time ("uvr: kernel NAME: N elements,
// T ms"), waiting for it: slower, for finding which kernel failed or is slow.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

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

/// True when UVR_CUDA_SYNC is set to anything but "" or "0": every launch is waited for, checked
/// and timed (read once).
inline bool syncEveryLaunch() {
    static const bool on = [] {
        const char* v = std::getenv("UVR_CUDA_SYNC");
        return v && *v && std::string(v) != "0";
    }();
    return on;
}

/// Ends the launch of the kernel `name` over `elements` elements that started at `start`: an
/// error of the launch (or, with syncEveryLaunch, of the kernel's run) throws naming it.
inline void finishLaunch(const char* name, std::uint64_t elements,
                         std::chrono::steady_clock::time_point start) {
    cudaError_t status = cudaGetLastError();
    if (status == cudaSuccess && syncEveryLaunch()) {
        status = cudaDeviceSynchronize();
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        std::fprintf(stderr, "uvr: kernel %s: %llu elements, %.3f ms\n", name,
                     static_cast<unsigned long long>(elements), ms);
    }
    if (status != cudaSuccess) check(status, ("kernel " + std::string(name)).c_str(), nullptr, 0);
}

/// The kernel of forEachElement: body(i) for this thread's element.
template <class Body>
__global__ void forEachElementKernel(std::uint64_t n, Body body) {
    const std::uint64_t i = globalThread();
    if (i < n) body(i);
}

/// body(i) on the GPU for every i in [0, n), one thread each in blocks of kBlock, on the default
/// stream (asynchronous: later copies and launches wait for it). `name` names the kernel in
/// errors and timings. `body` is a __device__ lambda (it captures device pointers and views by
/// value) or any functor with a __device__ operator()(std::uint64_t).
template <class Body>
void forEachElement(const char* name, std::uint64_t n, Body body) {
    if (n == 0) return;
    const auto start = std::chrono::steady_clock::now();
    forEachElementKernel<<<blocksFor(n), kBlock>>>(n, body);
    finishLaunch(name, n, start);
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
