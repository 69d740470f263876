// SPDX-License-Identifier: MIT
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace uvr::cuda {

/// Throws uvr::Error for a failed CUDA call: Error(Resource) with the free and total device
/// memory for out-of-memory, Error(Internal) with the call text, file and line (none when file is
/// null: a named kernel) otherwise.
void check(cudaError_t status, const char* call, const char* file, int line);

/// Throws Error(Resource) naming what could not be allocated, its size and the free memory.
[[noreturn]] void outOfMemory(const std::string& what, std::size_t bytes);

/// Counts `bytes` more as held by DeviceArrays, and the peak (cudaMemoryUse); false, counting
/// nothing, when that would pass setCudaMemoryLimit's limit.
bool takeDeviceBytes(std::size_t bytes);
/// Counts `bytes` as no longer held.
void returnDeviceBytes(std::size_t bytes);
/// Free device memory in bytes: the card's, or less under setCudaMemoryLimit.
std::size_t freeDeviceMemory();

/// A device array owned by RAII; upload() allocates and copies, naming `what` on failure.
template <class T>
class DeviceArray {
public:
    DeviceArray() = default;
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    ~DeviceArray() { release(); }

    /// Makes room for n elements (keeps the allocation when it is large enough).
    void reserve(std::size_t n, const char* what) {
        if (n <= capacity_) {
            size_ = n;
            return;
        }
        release();
        if (n > 0) {
            if (!takeDeviceBytes(n * sizeof(T))) outOfMemory(what, n * sizeof(T));
            if (cudaMalloc(reinterpret_cast<void**>(&ptr_), n * sizeof(T)) != cudaSuccess) {
                cudaGetLastError();  // clear the sticky-free allocation error
                ptr_ = nullptr;
                returnDeviceBytes(n * sizeof(T));
                outOfMemory(what, n * sizeof(T));
            }
        }
        capacity_ = size_ = n;
    }
    /// Allocates and copies n host elements.
    void upload(const T* host, std::size_t n, const char* what) {
        reserve(n, what);
        if (n > 0)
            check(cudaMemcpy(ptr_, host, n * sizeof(T), cudaMemcpyHostToDevice),
                  "cudaMemcpy(upload)", __FILE__, __LINE__);
    }
    /// Allocates and copies a host vector.
    template <class Allocator>
    void upload(const std::vector<T, Allocator>& host, const char* what) {
        upload(host.data(), host.size(), what);
    }
    /// Copies the first n elements to host memory.
    void download(T* host, std::size_t n) const {
        if (n > 0)
            check(cudaMemcpy(host, ptr_, n * sizeof(T), cudaMemcpyDeviceToHost),
                  "cudaMemcpy(download)", __FILE__, __LINE__);
    }
    /// Frees the memory now.
    void clear() { release(); }
    /// Exchanges the allocations of two arrays.
    void swap(DeviceArray& other) noexcept {
        std::swap(ptr_, other.ptr_);
        std::swap(size_, other.size_);
        std::swap(capacity_, other.capacity_);
    }
    T* data() const { return ptr_; }
    std::size_t size() const { return size_; }
    std::size_t bytes() const { return size_ * sizeof(T); }

private:
    void release() {
        if (ptr_) {
            cudaFree(ptr_);
            returnDeviceBytes(capacity_ * sizeof(T));
        }
        ptr_ = nullptr;
        capacity_ = size_ = 0;
    }
    T* ptr_ = nullptr;
    std::size_t size_ = 0, capacity_ = 0;
};

/// Page-locked host memory owned by RAII, kept for reuse: what device-to-host copies run
/// fastest into (the frame's read-back stages through it). Not counted as device memory.
class PinnedBuffer {
public:
    PinnedBuffer() = default;
    PinnedBuffer(const PinnedBuffer&) = delete;
    PinnedBuffer& operator=(const PinnedBuffer&) = delete;
    ~PinnedBuffer() {
        if (ptr_) cudaFreeHost(ptr_);
    }
    /// Makes room for `bytes` (keeps the allocation when it is large enough).
    void reserve(std::size_t bytes, const char* what) {
        if (bytes <= capacity_) return;
        if (ptr_) cudaFreeHost(ptr_);
        ptr_ = nullptr, capacity_ = 0;
        check(cudaMallocHost(&ptr_, bytes), what, __FILE__, __LINE__);
        capacity_ = bytes;
    }
    unsigned char* data() const { return static_cast<unsigned char*>(ptr_); }

private:
    void* ptr_ = nullptr;
    std::size_t capacity_ = 0;
};

}  // namespace uvr::cuda

/// Checks a CUDA runtime call (GUIDE.md §5): the call text, file and line go into the error.
#define UVR_CUDA_CHECK(call) ::uvr::cuda::check((call), #call, __FILE__, __LINE__)
