// SPDX-License-Identifier: MIT
// CUDA errors as uvr::Error, and the count of the device memory uvr's arrays hold.
#include "uvr/cuda/cuda_check.h"

#include <algorithm>
#include <atomic>
#include <cstdio>

#include "uvr/core/error.h"
#include "uvr/cuda/cuda_device.h"

namespace uvr {

namespace cuda {

namespace {

std::atomic<std::uint64_t> heldBytes{0}, peakBytes{0}, limitBytes{0};

/// What uvr's arrays may still take under a limit of `limit` bytes.
std::uint64_t leftUnder(std::uint64_t limit) {
    return limit - std::min(limit, heldBytes.load());
}

}  // namespace

void check(cudaError_t status, const char* call, const char* file, int line) {
    if (status == cudaSuccess) return;
    if (status == cudaErrorMemoryAllocation) outOfMemory(call, 0);
    const std::string where =
        file ? std::string(" at ") + file + ":" + std::to_string(line) : std::string();
    throw Error(ErrorKind::Internal,
                std::string("CUDA error in ") + call + where + ": " + cudaGetErrorString(status));
}

void outOfMemory(const std::string& what, std::size_t bytes) {
    std::size_t freeBytes = 0, totalBytes = 0;
    cudaMemGetInfo(&freeBytes, &totalBytes);
    const char* of = "";
    if (const std::uint64_t limit = limitBytes.load()) {
        freeBytes = leftUnder(limit);
        totalBytes = limit;
        of = " (uvr's limit)";
    }
    char buf[320];
    std::snprintf(
        buf, sizeof buf,
        "out of GPU memory allocating %s: need %.2f GiB more, %.2f GiB free of %.2f GiB%s",
        what.c_str(), bytes / 1073741824.0, freeBytes / 1073741824.0, totalBytes / 1073741824.0,
        of);
    throw Error(ErrorKind::Resource, buf);
}

bool takeDeviceBytes(std::size_t bytes) {
    const std::uint64_t limit = limitBytes.load();
    std::uint64_t held = heldBytes.load();
    do {
        if (limit && held + bytes > limit) return false;
    } while (!heldBytes.compare_exchange_weak(held, held + bytes));
    const std::uint64_t now = held + bytes;
    std::uint64_t peak = peakBytes.load();
    while (now > peak && !peakBytes.compare_exchange_weak(peak, now)) {
    }
    return true;
}

void returnDeviceBytes(std::size_t bytes) {
    heldBytes -= bytes;
}

std::size_t freeDeviceMemory() {
    std::size_t freeBytes = 0, totalBytes = 0;
    UVR_CUDA_CHECK(cudaMemGetInfo(&freeBytes, &totalBytes));
    if (const std::uint64_t limit = limitBytes.load())
        freeBytes = std::min<std::uint64_t>(freeBytes, leftUnder(limit));
    return freeBytes;
}

}  // namespace cuda

CudaMemoryUse cudaMemoryUse() {
    return {cuda::heldBytes.load(), cuda::peakBytes.load()};
}

void resetCudaMemoryPeak() {
    cuda::peakBytes = cuda::heldBytes.load();
}

void setCudaMemoryLimit(std::uint64_t bytes) {
    cuda::limitBytes = bytes;
}

}  // namespace uvr
