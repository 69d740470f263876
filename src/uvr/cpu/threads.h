// SPDX-License-Identifier: MIT
#pragma once

namespace uvr::cpu {

/// Number of threads parallel CPU work uses.
int threadCount();

/// Sets the number of threads later parallel CPU work uses (n >= 1; all cores for n <= 0).
void setThreadCount(int n);

/// Index of the calling thread inside parallelFor.
int currentThread();

}  // namespace uvr::cpu
