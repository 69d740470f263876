// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <string>

#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Reads a VTK XML UnstructuredGrid (.vtu): ascii, inline base64 binary, appended raw and appended
/// base64 data, optional zlib compression, UInt32/UInt64 headers, either byte order, all numeric
/// types, one or more Pieces. Throws Error naming file and element/byte offset when malformed.
Mesh readVtu(const std::string& path, const ReadOptions& options = {});

/// Reads a parallel VTK XML UnstructuredGrid (.pvtu): every piece's .vtu, relative to the .pvtu's
/// folder, merged into one mesh (point indices offset per piece).
Mesh readPvtu(const std::string& path, const ReadOptions& options = {});

}  // namespace uvr

namespace uvr {

/// Writes a VTK XML UnstructuredGrid (.vtu) with raw appended little-endian data (Float32 points,
/// Int64 connectivity/offsets, UInt8 types, Float32 fields), atomically; ParaView reads it.
void writeVtu(const Mesh& mesh, const std::string& path,
              const std::function<void(double)>& progress = {});

}  // namespace uvr
