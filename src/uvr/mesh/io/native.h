// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// First 8 bytes of a native uvr mesh file (.uvrm).
inline constexpr char kNativeMagic[8] = {'U', 'V', 'R', 'M', 'E', 'S', 'H', '\0'};

/// Reads a native uvr mesh (.uvrm, documented in docs/NATIVE_FORMAT.md); all counts are checked
/// against the file size before anything is allocated.
Mesh readNative(const std::string& path, const ReadOptions& options = {});

/// Writes a mesh in the native format, atomically (temporary file, then rename).
void writeNative(const Mesh& mesh, const std::string& path);

}  // namespace uvr
