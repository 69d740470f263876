// SPDX-License-Identifier: MIT
#pragma once

namespace uvr {

/// uvr's version (the CMake project's), as `uvr --version`, Python's `uvr.__version__` and the
/// viewer report it.
inline constexpr const char* kVersion = UVR_VERSION_STRING;

}  // namespace uvr
