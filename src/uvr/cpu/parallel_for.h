// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>

#include "uvr/cpu/threads.h"

namespace uvr::cpu {

/// Runs body(i, threadIndex) for i in [0, n) on all cores (OpenMP, dynamic schedule in chunks),
/// threadIndex in [0, threadCount()).
template <class Body>
void parallelFor(std::int64_t n, std::int64_t chunk, Body&& body) {
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < n; start += chunk) {
        const int thread = currentThread();
        const std::int64_t end = start + chunk < n ? start + chunk : n;
        for (std::int64_t i = start; i < end; ++i) body(i, thread);
    }
}

}  // namespace uvr::cpu
