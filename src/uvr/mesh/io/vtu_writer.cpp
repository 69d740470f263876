// SPDX-License-Identifier: MIT
#include <algorithm>
#include <bit>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/output_file.h"
#include "uvr/mesh/io/vtk_compression.h"
#include "uvr/mesh/io/vtu.h"
#include "uvr/mesh/validate.h"

namespace uvr {

namespace {

/// Escapes the five XML special characters of an attribute value.
std::string xmlEscape(const std::string& s) {
    std::string out;
    out.reserve(s.size());
    for (char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            case '\'':
                out += "&apos;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

/// One DataArray to write: its XML attributes and a function that writes the little-endian
/// bytes of its elements [first, first + count) to dst.
struct ArrayOut {
    const char* type = "";
    std::string name;
    int components = 1;
    std::uint64_t elementSize = 1;
    std::uint64_t elements = 0;
    std::function<void(std::uint64_t first, std::uint64_t count, unsigned char* dst)> fill;

    std::uint64_t bytes() const { return elements * elementSize; }
};

/// An ArrayOut of `elements` values T(get(i)).
template <typename T, typename Get>
ArrayOut makeArray(const char* type, std::string name, int components, std::uint64_t elements,
                   Get get) {
    ArrayOut a;
    a.type = type;
    a.name = std::move(name);
    a.components = components;
    a.elementSize = sizeof(T);
    a.elements = elements;
    a.fill = [get](std::uint64_t first, std::uint64_t count, unsigned char* dst) {
        for (std::uint64_t i = 0; i < count; ++i) {
            T v = static_cast<T>(get(first + i));
            if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
                auto* b = reinterpret_cast<unsigned char*>(&v);
                std::reverse(b, b + sizeof(T));
            }
            std::memcpy(dst + i * sizeof(T), &v, sizeof(T));
        }
    };
    return a;
}

/// Appends a UInt64 little-endian value.
void putU64(std::vector<unsigned char>& out, std::uint64_t v) {
    for (int k = 0; k < 8; ++k) out.push_back(static_cast<unsigned char>(v >> (8 * k)));
}

/// An array's appended payload when compressed: VTK's header [blocks, blockSize, lastBlockSize,
/// compressed sizes...] (UInt64) and the compressed blocks.
struct CompressedArray {
    std::vector<unsigned char> header;
    std::vector<std::vector<unsigned char>> blocks;

    std::uint64_t bytes() const {
        std::uint64_t n = header.size();
        for (const auto& b : blocks) n += b.size();
        return n;
    }
};

/// Compresses an array block by block, in parallel, reporting raw bytes done to done().
CompressedArray compressArray(const ArrayOut& a, const VtuWriteOptions& options, int level,
                              const std::string& path,
                              const std::function<void(std::uint64_t)>& done) {
    const std::uint64_t bytes = a.bytes();
    const std::uint64_t blockSize = options.blockSize;
    const std::uint64_t blocks = (bytes + blockSize - 1) / blockSize;
    CompressedArray c;
    putU64(c.header, blocks);
    putU64(c.header, blockSize);
    putU64(c.header, bytes % blockSize);  // 0: the last block is full
    c.blocks.resize(blocks);
    // Batches keep the progress moving and the error of a failed block in one place.
    constexpr std::uint64_t kBatch = 256;
    for (std::uint64_t begin = 0; begin < blocks; begin += kBatch) {
        const std::int64_t end = static_cast<std::int64_t>(std::min(blocks, begin + kBatch));
        std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 1)
        for (std::int64_t b = static_cast<std::int64_t>(begin); b < end; ++b) {
            try {
                const std::uint64_t first = std::uint64_t(b) * blockSize;
                const std::uint64_t n = std::min(blockSize, bytes - first);
                std::vector<unsigned char> raw(n);
                a.fill(first / a.elementSize, n / a.elementSize, raw.data());
                compressBlock(options.compressor, level, raw.data(), raw.size(), c.blocks[b], path);
            } catch (...) {
#pragma omp critical(uvr_vtu_compress_error)
                if (!error) error = std::current_exception();
            }
        }
        if (error) std::rethrow_exception(error);
        done(std::min(bytes, std::uint64_t(end) * blockSize) - std::min(bytes, begin * blockSize));
    }
    for (const auto& b : c.blocks) putU64(c.header, b.size());
    return c;
}

int defaultLevel(VtuCompressor compressor) {
    switch (compressor) {
        case VtuCompressor::Zlib:
            return 5;
        case VtuCompressor::Lz4:
            return 1;
        case VtuCompressor::Lzma:
            return 2;
        case VtuCompressor::None:
            break;
    }
    return 0;
}

}  // namespace

void writeVtu(const Mesh& mesh, const std::string& path,
              const std::function<void(double)>& progress, const VtuWriteOptions& options) {
    // Structure checks, so that VTK never reads past an array.
    validateStructure(mesh, path);
    const bool compress = options.compressor != VtuCompressor::None;
    requireVtuCompressor(options.compressor, path);
    if (options.blockSize == 0 || options.blockSize % 8 != 0)
        throwError(ErrorKind::Argument, path,
                   "VTU block size " + std::to_string(options.blockSize) +
                       " must be a positive multiple of 8");
    const std::uint64_t cells = mesh.cellCount();

    // The arrays in file order: point fields, cell fields, points, connectivity, offsets (VTK's
    // are the END of each cell's run of connectivity), types.
    std::vector<ArrayOut> arrays;
    std::vector<std::size_t> sectionEnds;  // PointData, CellData, Points, Cells
    for (Association association : {Association::Point, Association::Cell}) {
        for (const Field& f : mesh.fields)
            if (f.association == association)
                arrays.push_back(makeArray<float>("Float32", f.name, f.components, f.values.size(),
                                                  [&f](std::uint64_t i) { return f.values[i]; }));
        sectionEnds.push_back(arrays.size());
    }
    arrays.push_back(
        makeArray<float>("Float32", "Points", 3, mesh.pointCount() * 3,
                         [&](std::uint64_t i) { return mesh.points[i / 3][int(i % 3)]; }));
    sectionEnds.push_back(arrays.size());
    arrays.push_back(makeArray<std::int64_t>("Int64", "connectivity", 1, mesh.cellIndices.size(),
                                             [&](std::uint64_t i) { return mesh.cellIndices[i]; }));
    arrays.push_back(makeArray<std::int64_t>(
        "Int64", "offsets", 1, cells, [&](std::uint64_t c) { return mesh.cellOffsets[c + 1]; }));
    arrays.push_back(makeArray<std::uint8_t>("UInt8", "types", 1, cells,
                                             [&](std::uint64_t c) { return mesh.cellTypes[c]; }));

    // Compression first (the XML holds the compressed sizes as offsets), then one pass of
    // writing; progress: the raw bytes compressed, then the bytes written.
    std::uint64_t rawTotal = 0;
    for (const ArrayOut& a : arrays) rawTotal += a.bytes();
    const double compressShare = compress ? 0.9 : 0.0;
    std::uint64_t rawDone = 0;
    auto report = [&](double fraction) {
        if (progress) progress(std::min(1.0, fraction));
    };
    std::vector<CompressedArray> packed;
    if (compress) {
        const int level = options.level >= 0 ? options.level : defaultLevel(options.compressor);
        for (const ArrayOut& a : arrays)
            packed.push_back(compressArray(a, options, level, path, [&](std::uint64_t n) {
                rawDone += n;
                report(compressShare * double(rawDone) /
                       double(std::max<std::uint64_t>(rawTotal, 1)));
            }));
    }
    std::vector<std::uint64_t> payload(arrays.size());
    for (std::size_t k = 0; k < arrays.size(); ++k)
        payload[k] = compress ? packed[k].bytes() : 8 + arrays[k].bytes();

    // XML header: the appended payloads follow in the order their DataArrays are listed;
    // offsets count from the byte after the '_' marker.
    std::string xml =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\"";
    if (compress)
        xml += std::string(" compressor=\"") + vtuCompressorClass(options.compressor) + "\"";
    xml += ">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"" +
           std::to_string(mesh.pointCount()) + "\" NumberOfCells=\"" + std::to_string(cells) +
           "\">\n";
    std::uint64_t offset = 0;
    auto dataArray = [&](std::size_t k) {
        const ArrayOut& a = arrays[k];
        xml += std::string("        <DataArray type=\"") + a.type + "\" Name=\"" +
               xmlEscape(a.name) + "\" NumberOfComponents=\"" + std::to_string(a.components) +
               "\" format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
        offset += payload[k];
    };
    std::size_t k = 0;
    for (Association association : {Association::Point, Association::Cell}) {
        const char* tag = association == Association::Point ? "PointData" : "CellData";
        xml += std::string("      <") + tag;
        for (const Field& f : mesh.fields) {
            if (f.association == association && f.components == 1) {
                xml += " Scalars=\"" + xmlEscape(f.name) + "\"";  // ParaView's default colouring
                break;
            }
        }
        xml += ">\n";
        for (; k < sectionEnds[association == Association::Point ? 0 : 1]; ++k) dataArray(k);
        xml += std::string("      </") + tag + ">\n";
    }
    xml += "      <Points>\n";
    dataArray(k++);
    xml += "      </Points>\n      <Cells>\n";
    for (; k < arrays.size(); ++k) dataArray(k);
    xml +=
        "      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "  <AppendedData encoding=\"raw\">\n"
        "   _";

    // The file: XML, payloads, closing tags.
    OutputFile file(path);
    const std::uint64_t total = xml.size() + offset;
    std::uint64_t written = 0, nextReport = 0;
    auto put = [&](const void* data, std::uint64_t n) {
        file.write(data, n);
        written += n;
        if (written >= nextReport) {
            report(compressShare + (1.0 - compressShare) * double(written) / double(total));
            nextReport = written + total / 200;
        }
    };
    put(xml.data(), xml.size());
    std::vector<unsigned char> chunk;
    for (std::size_t a = 0; a < arrays.size(); ++a) {
        if (compress) {
            put(packed[a].header.data(), packed[a].header.size());
            for (auto& b : packed[a].blocks) {
                put(b.data(), b.size());
                std::vector<unsigned char>().swap(b);  // freed as written
            }
            continue;
        }
        const ArrayOut& out = arrays[a];
        chunk.clear();
        putU64(chunk, out.bytes());
        put(chunk.data(), chunk.size());
        constexpr std::uint64_t kChunkElements = 8192;
        chunk.resize(kChunkElements * out.elementSize);
        for (std::uint64_t first = 0; first < out.elements; first += kChunkElements) {
            const std::uint64_t n = std::min(kChunkElements, out.elements - first);
            out.fill(first, n, chunk.data());
            put(chunk.data(), n * out.elementSize);
        }
    }
    const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
    put(tail.data(), tail.size());
    file.commit();
}

}  // namespace uvr
