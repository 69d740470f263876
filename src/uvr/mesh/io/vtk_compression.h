// SPDX-License-Identifier: MIT
// The block compressors of VTK's XML formats (vtkZLibDataCompressor, vtkLZ4DataCompressor,
// vtkLZMADataCompressor): one block in, one block out, as VTK's readers and writers use them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "uvr/mesh/io/vtu.h"

namespace uvr {

/// The compressor named by a VTKFile compressor attribute (VTK's class name), if known.
std::optional<VtuCompressor> parseVtuCompressorClass(std::string_view className);

/// Throws Error(Unsupported) naming file and the package to install when this build lacks the
/// compressor's library.
void requireVtuCompressor(VtuCompressor compressor, const std::string& file);

/// VTK's class name of a compressor ("vtkZLibDataCompressor"; "" for None).
const char* vtuCompressorClass(VtuCompressor compressor);

/// Most bytes one compressed byte can stand for in a valid block of this compressor (deflate
/// 1032:1, LZ4 255:1, LZMA in xz about 7000:1 at best; bounded here by 32768:1).
std::uint64_t maxCompressionRatio(VtuCompressor compressor);

/// Decompresses one block into exactly out.size() bytes; returns "" on success, else what went
/// wrong ("LZ4 data is corrupt", "inflated to 12 bytes, expected 16"). Throws Error(Unsupported)
/// naming file when this build lacks the compressor's library.
std::string decompressBlock(VtuCompressor compressor, const unsigned char* in, std::size_t inSize,
                            unsigned char* out, std::size_t outSize, const std::string& file);

/// Compresses one block into out (replaced) at a compressor-specific level (zlib 1-9, LZ4
/// acceleration from 1, LZMA preset 0-9); throws Error(Unsupported) when this build lacks the
/// compressor's library, Error(Resource) naming file when the library fails.
void compressBlock(VtuCompressor compressor, int level, const unsigned char* in, std::size_t size,
                   std::vector<unsigned char>& out, const std::string& file);

}  // namespace uvr
