// SPDX-License-Identifier: MIT
// Large allocations on transparent huge pages (huge_pages.cpp): whether this build has them.
#pragma once

#include <cstddef>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UVR_NO_HUGE_PAGES 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define UVR_NO_HUGE_PAGES 1
#endif

namespace uvr::cli {

/// Allocations of at least this many bytes start on a huge page and are advised for huge pages
/// (unless UVR_HUGE_PAGES=0); sanitizer builds leave operator new to the sanitizer.
inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;
inline constexpr std::size_t kHugeAllocationBytes = std::size_t(32) << 20;
#ifdef UVR_NO_HUGE_PAGES
inline constexpr bool kHugePagesBuilt = false;
#else
inline constexpr bool kHugePagesBuilt = true;
#endif

}  // namespace uvr::cli
