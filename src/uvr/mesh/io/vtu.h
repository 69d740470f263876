// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// The block compression of a VTK XML file's binary data (VTKFile's compressor attribute).
enum class VtuCompressor { None, Zlib, Lz4, Lzma };

/// True when this build can read and write the compressor (LZ4 and LZMA are optional).
bool vtuCompressorAvailable(VtuCompressor compressor);

/// Reads a VTK XML UnstructuredGrid (.vtu): ascii, inline base64 binary, appended raw and appended
/// base64 data, optional zlib, LZ4 or LZMA compression, UInt32/UInt64 headers, either byte order,
/// all numeric types, one or more Pieces. Throws Error naming file and element/byte offset when
/// malformed.
Mesh readVtu(const std::string& path, const ReadOptions& options = {});

/// Reads a parallel VTK XML UnstructuredGrid (.pvtu): every piece's .vtu, relative to the .pvtu's
/// folder, merged into one mesh (point indices offset per piece).
Mesh readPvtu(const std::string& path, const ReadOptions& options = {});

/// How many pieces a .pvtu lists (its XML only is read).
std::size_t pvtuPieceCount(const std::string& path);

/// Reads the pieces [firstPiece, endPiece) of a .pvtu as readPvtu reads them all (a data-parallel
/// rank's part): their points and cells, with ids in the whole file's order (kPieceIdShift). Throws
/// Error(Argument) for an empty range or one beyond the listed pieces.
MeshPart readPvtuPart(const std::string& path, std::size_t firstPiece, std::size_t endPiece,
                      const ReadOptions& options = {});

}  // namespace uvr

namespace uvr {

/// How writeVtu compresses: VTK's block layout (UInt64 header), blocks compressed in parallel.
struct VtuWriteOptions {
    VtuCompressor compressor = VtuCompressor::Zlib;  ///< None writes the arrays as they are
    std::uint32_t blockSize = 1u << 16;              ///< uncompressed bytes per block (VTK: 32768)
    int level = -1;  ///< -1: the compressor's default (zlib 5, LZ4 acceleration 1, LZMA preset 2)
};

/// Writes a VTK XML UnstructuredGrid (.vtu) with raw appended little-endian data (Float32 points,
/// Int64 connectivity/offsets, UInt8 types, Float32 fields), zlib-compressed unless options say
/// otherwise, atomically; ParaView and VTK read it.
void writeVtu(const Mesh& mesh, const std::string& path,
              const std::function<void(double)>& progress = {},
              const VtuWriteOptions& options = {});

}  // namespace uvr
