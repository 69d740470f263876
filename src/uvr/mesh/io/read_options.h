// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>

namespace uvr {

/// Options every mesh reader takes.
struct ReadOptions {
    /// Upper bound on bytes a reader may allocate for one array (0 = no limit). Readers also refuse
    /// counts that the file's size cannot hold before allocating anything.
    std::uint64_t maxMemoryBytes = 0;
};

}  // namespace uvr
