// SPDX-License-Identifier: MIT
#pragma once

/// Qualifier for functions callable from both CPU and CUDA code (GUIDE.md §2).
#if defined(__CUDACC__)
#define UVR_HOST_DEVICE __host__ __device__
#define UVR_INLINE __forceinline__
#else
#define UVR_HOST_DEVICE
#define UVR_INLINE inline
#endif
