// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_compression.h"

#include <zlib.h>

#include <climits>

#include "uvr/core/error.h"

#ifdef UVR_HAVE_LZ4
#include <lz4.h>
#endif
#ifdef UVR_HAVE_LZMA
#include <lzma.h>
#endif

namespace uvr {

namespace {

#ifdef UVR_HAVE_LZMA
/// LZMA decoder memory limit: VTK's presets use dictionaries of at most 64 MiB.
constexpr std::uint64_t kLzmaMemoryLimit = std::uint64_t(1) << 30;

const char* lzmaMessage(lzma_ret rc) {
    switch (rc) {
        case LZMA_MEM_ERROR:
            return "out of memory";
        case LZMA_MEMLIMIT_ERROR:
            return "needs more than 1 GiB of decoder memory";
        case LZMA_FORMAT_ERROR:
            return "not an xz stream";
        case LZMA_OPTIONS_ERROR:
            return "unsupported xz options";
        case LZMA_DATA_ERROR:
            return "xz data is corrupt";
        case LZMA_BUF_ERROR:
            return "xz data is truncated or larger than the header declares";
        default:
            return "xz decoding failed";
    }
}
#endif

}  // namespace

void requireVtuCompressor(VtuCompressor compressor, const std::string& file) {
    if (vtuCompressorAvailable(compressor)) return;
    const bool lz4 = compressor == VtuCompressor::Lz4;
    throwError(ErrorKind::Unsupported, file,
               std::string(vtuCompressorClass(compressor)) + ": this uvr was built without " +
                   (lz4 ? "LZ4; install liblz4-dev" : "LZMA; install liblzma-dev") +
                   " and rebuild");
}

bool vtuCompressorAvailable(VtuCompressor compressor) {
    switch (compressor) {
        case VtuCompressor::None:
        case VtuCompressor::Zlib:
            return true;
        case VtuCompressor::Lz4:
#ifdef UVR_HAVE_LZ4
            return true;
#else
            return false;
#endif
        case VtuCompressor::Lzma:
#ifdef UVR_HAVE_LZMA
            return true;
#else
            return false;
#endif
    }
    return false;
}

std::optional<VtuCompressor> parseVtuCompressorClass(std::string_view className) {
    if (className == "vtkZLibDataCompressor") return VtuCompressor::Zlib;
    if (className == "vtkLZ4DataCompressor") return VtuCompressor::Lz4;
    if (className == "vtkLZMADataCompressor") return VtuCompressor::Lzma;
    return std::nullopt;
}

const char* vtuCompressorClass(VtuCompressor compressor) {
    switch (compressor) {
        case VtuCompressor::None:
            return "";
        case VtuCompressor::Zlib:
            return "vtkZLibDataCompressor";
        case VtuCompressor::Lz4:
            return "vtkLZ4DataCompressor";
        case VtuCompressor::Lzma:
            return "vtkLZMADataCompressor";
    }
    return "";
}

std::uint64_t maxCompressionRatio(VtuCompressor compressor) {
    switch (compressor) {
        case VtuCompressor::Lz4:
            return 255;
        case VtuCompressor::Lzma:
            return 32768;
        default:
            return 1032;  // deflate: 258-byte matches in about 2 bits
    }
}

std::string decompressBlock(VtuCompressor compressor, const unsigned char* in, std::size_t inSize,
                            unsigned char* out, std::size_t outSize, const std::string& file) {
    requireVtuCompressor(compressor, file);
    auto sizeMessage = [&](std::uint64_t produced) {
        return "decompressed to " + std::to_string(produced) + " bytes, expected " +
               std::to_string(outSize);
    };
    switch (compressor) {
        case VtuCompressor::Zlib: {
            uLongf produced = static_cast<uLongf>(outSize);
            const int rc = uncompress(out, &produced, in, static_cast<uLong>(inSize));
            if (rc != Z_OK) return zError(rc);
            return produced == outSize ? "" : sizeMessage(produced);
        }
        case VtuCompressor::Lz4: {
#ifdef UVR_HAVE_LZ4
            if (inSize > INT_MAX || outSize > INT_MAX)
                return "an LZ4 block larger than 2 GiB (LZ4 blocks are at most 2 GiB)";
            const int produced =
                LZ4_decompress_safe(reinterpret_cast<const char*>(in), reinterpret_cast<char*>(out),
                                    static_cast<int>(inSize), static_cast<int>(outSize));
            if (produced < 0) return "LZ4 data is corrupt or larger than the header declares";
            return static_cast<std::size_t>(produced) == outSize ? "" : sizeMessage(produced);
#else
            break;
#endif
        }
        case VtuCompressor::Lzma: {
#ifdef UVR_HAVE_LZMA
            std::uint64_t memlimit = kLzmaMemoryLimit;
            std::size_t inPos = 0, outPos = 0;
            const lzma_ret rc = lzma_stream_buffer_decode(&memlimit, 0, nullptr, in, &inPos, inSize,
                                                          out, &outPos, outSize);
            if (rc != LZMA_OK) return lzmaMessage(rc);
            if (outPos != outSize) return sizeMessage(outPos);
            if (inPos != inSize)
                return std::to_string(inSize - inPos) + " bytes after the end of the xz stream";
            return "";
#else
            break;
#endif
        }
        case VtuCompressor::None:
            break;
    }
    return "no compressor";
}

void compressBlock(VtuCompressor compressor, int level, const unsigned char* in, std::size_t size,
                   std::vector<unsigned char>& out, const std::string& file) {
    requireVtuCompressor(compressor, file);
    auto failed = [&](const std::string& what) {
        throwError(ErrorKind::Resource, file,
                   std::string(vtuCompressorClass(compressor)) + ": " + what);
    };
    switch (compressor) {
        case VtuCompressor::Zlib: {
            uLongf n = compressBound(static_cast<uLong>(size));
            out.resize(n);
            const int rc = compress2(out.data(), &n, in, static_cast<uLong>(size), level);
            if (rc != Z_OK) failed(std::string("zlib compression failed: ") + zError(rc));
            out.resize(n);
            return;
        }
        case VtuCompressor::Lz4: {
#ifdef UVR_HAVE_LZ4
            if (size > LZ4_MAX_INPUT_SIZE) failed("a block larger than LZ4_MAX_INPUT_SIZE");
            out.resize(static_cast<std::size_t>(LZ4_compressBound(static_cast<int>(size))));
            const int n = LZ4_compress_fast(
                reinterpret_cast<const char*>(in), reinterpret_cast<char*>(out.data()),
                static_cast<int>(size), static_cast<int>(out.size()), level);
            if (n <= 0) failed("LZ4 compression failed");
            out.resize(static_cast<std::size_t>(n));
            return;
#else
            break;
#endif
        }
        case VtuCompressor::Lzma: {
#ifdef UVR_HAVE_LZMA
            out.resize(lzma_stream_buffer_bound(size));
            std::size_t n = 0;
            const lzma_ret rc =
                lzma_easy_buffer_encode(static_cast<std::uint32_t>(level), LZMA_CHECK_CRC64,
                                        nullptr, in, size, out.data(), &n, out.size());
            if (rc != LZMA_OK) failed("LZMA compression failed (code " + std::to_string(rc) + ")");
            out.resize(n);
            return;
#else
            break;
#endif
        }
        case VtuCompressor::None:
            break;
    }
    out.assign(in, in + size);
}

}  // namespace uvr
