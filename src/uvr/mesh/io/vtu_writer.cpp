// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtu.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"
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

/// Writes values converted to little-endian T, a chunk at a time, so that no array is copied whole.
class LittleEndianWriter {
public:
    /// Writes to file, reporting the fraction of `total` bytes written to progress (if given).
    LittleEndianWriter(OutputFile& file, std::uint64_t total,
                       const std::function<void(double)>& progress)
        : file_(file), total_(std::max<std::uint64_t>(total, 1)), progress_(progress) {}

    void bytes(const void* data, std::uint64_t count) {
        file_.write(data, count);
        written_ += count;
        if (progress_ && written_ >= nextReport_) {
            progress_(std::min(1.0, double(written_) / double(total_)));
            nextReport_ = written_ + total_ / 200;
        }
    }

    /// Writes T(get(i)) for i in [0, count).
    template <typename T, typename Get>
    void values(std::uint64_t count, Get get) {
        constexpr std::uint64_t kChunk = 8192;
        T chunk[kChunk];
        for (std::uint64_t begin = 0; begin < count; begin += kChunk) {
            const std::uint64_t n = std::min(kChunk, count - begin);
            for (std::uint64_t i = 0; i < n; ++i) {
                T v = static_cast<T>(get(begin + i));
                if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
                    auto* b = reinterpret_cast<unsigned char*>(&v);
                    std::reverse(b, b + sizeof(T));
                }
                chunk[i] = v;
            }
            bytes(chunk, n * sizeof(T));
        }
    }

private:
    OutputFile& file_;
    std::uint64_t total_, written_ = 0, nextReport_ = 0;
    const std::function<void(double)>& progress_;
};

}  // namespace

void writeVtu(const Mesh& mesh, const std::string& path,
              const std::function<void(double)>& progress) {
    // Structure checks, so that VTK never reads past an array.
    validateStructure(mesh, path);
    const std::uint64_t cells = mesh.cellCount();

    // XML header: the appended blocks follow in the order their DataArrays are listed, each a
    // UInt64 byte count and the data; offsets count from the byte after the '_' marker.
    std::string xml =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\">\n"
        "  <UnstructuredGrid>\n"
        "    <Piece NumberOfPoints=\"" +
        std::to_string(mesh.pointCount()) + "\" NumberOfCells=\"" + std::to_string(cells) + "\">\n";
    std::uint64_t offset = 0;
    auto dataArray = [&](const char* type, const std::string& name, int components,
                         std::uint64_t bytes) {
        xml += std::string("        <DataArray type=\"") + type + "\" Name=\"" + xmlEscape(name) +
               "\" NumberOfComponents=\"" + std::to_string(components) +
               "\" format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
        offset += 8 + bytes;
    };
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
        for (const Field& f : mesh.fields)
            if (f.association == association)
                dataArray("Float32", f.name, f.components, f.values.size() * 4);
        xml += std::string("      </") + tag + ">\n";
    }
    xml += "      <Points>\n";
    dataArray("Float32", "Points", 3, mesh.pointCount() * 12);
    xml += "      </Points>\n      <Cells>\n";
    dataArray("Int64", "connectivity", 1, mesh.cellIndices.size() * 8);
    dataArray("Int64", "offsets", 1, cells * 8);
    dataArray("UInt8", "types", 1, cells);
    xml +=
        "      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "  <AppendedData encoding=\"raw\">\n"
        "   _";

    OutputFile file(path);
    LittleEndianWriter out(file, xml.size() + offset, progress);
    out.bytes(xml.data(), xml.size());
    auto blockHeader = [&](std::uint64_t bytes) {
        out.values<std::uint64_t>(1, [bytes](std::uint64_t) { return bytes; });
    };
    for (Association association : {Association::Point, Association::Cell}) {
        for (const Field& f : mesh.fields) {
            if (f.association != association) continue;
            blockHeader(f.values.size() * 4);
            out.values<float>(f.values.size(), [&f](std::uint64_t i) { return f.values[i]; });
        }
    }
    blockHeader(mesh.pointCount() * 12);
    out.values<float>(mesh.pointCount() * 3,
                      [&](std::uint64_t i) { return mesh.points[i / 3][int(i % 3)]; });
    blockHeader(mesh.cellIndices.size() * 8);
    out.values<std::int64_t>(mesh.cellIndices.size(),
                             [&](std::uint64_t i) { return mesh.cellIndices[i]; });
    // VTK's offsets are the END of each cell's run of connectivity.
    blockHeader(cells * 8);
    out.values<std::int64_t>(cells, [&](std::uint64_t c) { return mesh.cellOffsets[c + 1]; });
    blockHeader(cells);
    out.bytes(mesh.cellTypes.data(), cells);
    const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
    out.bytes(tail.data(), tail.size());
    file.commit();
}

}  // namespace uvr
