// SPDX-License-Identifier: MIT
#pragma once

/// Qualifier for functions callable from both CPU and CUDA code (GUIDE.md §2).
#if defined(__CUDACC__)
#define UVR_HOST_DEVICE __host__ __device__
#define UVR_INLINE __forceinline__
/// A rarely taken path kept out of line on the GPU, so its registers do not weigh on the hot
/// loop that calls it (the native cells' Newton iterations beside the tetrahedra's walk).
#define UVR_NOINLINE __noinline__
#else
#define UVR_HOST_DEVICE
#define UVR_INLINE inline
#define UVR_NOINLINE
#endif
