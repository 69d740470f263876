// SPDX-License-Identifier: MIT
#pragma once

namespace uvr::cpu {

/// Number of threads parallel CPU work uses.
int threadCount();

/// Most threads uvr starts: 4 per hardware thread, at least 64, at most 1024 (every thread
/// reserves a stack; thousands of them fail to start).
int maxThreadCount();

/// Sets the number of threads later parallel CPU work uses (n >= 1, capped at maxThreadCount();
/// all cores for n <= 0).
void setThreadCount(int n);

/// Index of the calling thread inside parallelFor.
int currentThread();

}  // namespace uvr::cpu
