// SPDX-License-Identifier: MIT
#pragma once

/// Qualifier for functions callable from both CPU and CUDA code (GUIDE.md §2).
/// UVR_INLINE: inlined always, for the small functions of a sample's inner loop (point location)
/// that g++ otherwise calls out of line where the loop has several call sites (the adaptive
/// marcher: 13-17% of its CPU frame, docs/PERFORMANCE.md).
#if defined(__CUDACC__)
#define UVR_HOST_DEVICE __host__ __device__
#define UVR_INLINE __forceinline__
#define UVR_NOINLINE __noinline__
#else
#define UVR_HOST_DEVICE
#define UVR_INLINE inline __attribute__((always_inline))
#define UVR_NOINLINE __attribute__((noinline))
#endif
