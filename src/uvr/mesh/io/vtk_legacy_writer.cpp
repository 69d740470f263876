// SPDX-License-Identifier: MIT
#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/output_file.h"
#include "uvr/mesh/io/vtk_legacy.h"
#include "uvr/mesh/validate.h"

namespace uvr {

namespace {

/// Percent-encodes what a legacy name cannot hold (whitespace, '%', non-printing bytes), as
/// vtkDataWriter does; the readers decode it.
std::string encodeName(const std::string& name) {
    static const char* kHex = "0123456789ABCDEF";
    std::string out;
    for (char ch : name) {
        const auto c = static_cast<unsigned char>(ch);
        if (c <= 0x20 || c >= 0x7f || c == '%' || c == '"') {
            out += '%';
            out += kHex[c >> 4];
            out += kHex[c & 15];
        } else {
            out += ch;
        }
    }
    return out.empty() ? "unnamed" : out;
}

/// Writes big-endian values a chunk at a time, reporting the fraction of `total` bytes written.
class BigEndianWriter {
public:
    BigEndianWriter(OutputFile& file, std::uint64_t total,
                    const std::function<void(double)>& progress)
        : file_(file), total_(std::max<std::uint64_t>(total, 1)), progress_(progress) {}

    void text(const std::string& s) { bytes(s.data(), s.size()); }

    void bytes(const void* data, std::uint64_t count) {
        file_.write(data, count);
        written_ += count;
        if (progress_ && written_ >= nextReport_) {
            progress_(std::min(1.0, double(written_) / double(total_)));
            nextReport_ = written_ + total_ / 200;
        }
    }

    /// Writes T(get(i)) for i in [0, count), then the newline VTK puts after binary data.
    template <typename T, typename Get>
    void values(std::uint64_t count, Get get) {
        constexpr std::uint64_t kChunk = 8192;
        unsigned char chunk[kChunk * sizeof(T)];
        for (std::uint64_t begin = 0; begin < count; begin += kChunk) {
            const std::uint64_t n = std::min(kChunk, count - begin);
            for (std::uint64_t i = 0; i < n; ++i) {
                T v = static_cast<T>(get(begin + i));
                unsigned char* b = chunk + i * sizeof(T);
                std::memcpy(b, &v, sizeof(T));
                if constexpr (std::endian::native == std::endian::little && sizeof(T) > 1)
                    std::reverse(b, b + sizeof(T));
            }
            bytes(chunk, n * sizeof(T));
        }
        text("\n");
    }

private:
    OutputFile& file_;
    std::uint64_t total_, written_ = 0, nextReport_ = 0;
    const std::function<void(double)>& progress_;
};

}  // namespace

void writeVtkLegacy(const Mesh& mesh, const std::string& path,
                    const std::function<void(double)>& progress, VtkLegacyVersion version) {
    validateStructure(mesh, path);
    const std::uint64_t points = mesh.pointCount();
    const std::uint64_t cells = mesh.cellCount();
    const std::uint64_t conn = mesh.cellIndices.size();

    // Version: 4.2's CELLS records (count + ids, int32) must fit int32.
    constexpr std::uint64_t kInt32Max = std::numeric_limits<std::int32_t>::max();
    const bool fits42 = cells + conn <= kInt32Max && points <= kInt32Max;
    if (version == VtkLegacyVersion::V42 && !fits42)
        throwError(ErrorKind::Unsupported, path,
                   "legacy VTK 4.2 cannot hold " + std::to_string(cells) + " cells with " +
                       std::to_string(conn) + " point indices (int32 CELLS); write version 5.1");
    const bool v51 = version == VtkLegacyVersion::V51 || !fits42;

    std::uint64_t total =
        12 * points + (v51 ? 8 * (cells + 1 + conn) : 4 * (cells + conn)) + 4 * cells;
    for (const Field& f : mesh.fields) total += 4 * f.values.size();

    OutputFile file(path);
    BigEndianWriter out(file, total, progress);
    out.text(std::string("# vtk DataFile Version ") + (v51 ? "5.1" : "4.2") +
             "\nwritten by uvr\nBINARY\nDATASET UNSTRUCTURED_GRID\n");
    out.text("POINTS " + std::to_string(points) + " float\n");
    out.values<float>(3 * points, [&](std::uint64_t i) { return mesh.points[i / 3][int(i % 3)]; });
    if (v51) {
        out.text("CELLS " + std::to_string(cells + 1) + " " + std::to_string(conn) +
                 "\nOFFSETS vtktypeint64\n");
        out.values<std::int64_t>(cells + 1, [&](std::uint64_t c) { return mesh.cellOffsets[c]; });
        out.text("CONNECTIVITY vtktypeint64\n");
        out.values<std::int64_t>(conn, [&](std::uint64_t i) { return mesh.cellIndices[i]; });
    } else {
        // Records "k id_1 ... id_k": cell c's record starts at cellOffsets[c] + c.
        out.text("CELLS " + std::to_string(cells) + " " + std::to_string(cells + conn) + "\n");
        std::uint64_t cell = 0;
        out.values<std::int32_t>(cells + conn, [&](std::uint64_t i) -> std::int64_t {
            while (cell < cells && i > mesh.cellOffsets[cell + 1] + cell) ++cell;
            const std::uint64_t start = mesh.cellOffsets[cell] + cell;
            if (i == start)
                return static_cast<std::int64_t>(mesh.cellOffsets[cell + 1] -
                                                 mesh.cellOffsets[cell]);
            return mesh.cellIndices[i - cell - 1];
        });
    }
    out.text("CELL_TYPES " + std::to_string(cells) + "\n");
    out.values<std::int32_t>(cells, [&](std::uint64_t c) { return mesh.cellTypes[c]; });

    // Fields: the first one-component field of each association as SCALARS, the rest as FIELD.
    for (Association association : {Association::Point, Association::Cell}) {
        std::vector<const Field*> fields;
        for (const Field& f : mesh.fields)
            if (f.association == association) fields.push_back(&f);
        if (fields.empty()) continue;
        const bool point = association == Association::Point;
        out.text(std::string(point ? "POINT_DATA " : "CELL_DATA ") +
                 std::to_string(point ? points : cells) + "\n");
        const auto scalars = std::find_if(fields.begin(), fields.end(),
                                          [](const Field* f) { return f->components == 1; });
        if (scalars != fields.end()) {
            const Field& f = **scalars;
            out.text("SCALARS " + encodeName(f.name) + " float 1\nLOOKUP_TABLE default\n");
            out.values<float>(f.values.size(), [&](std::uint64_t i) { return f.values[i]; });
            fields.erase(scalars);
        }
        if (fields.empty()) continue;
        out.text("FIELD FieldData " + std::to_string(fields.size()) + "\n");
        for (const Field* f : fields) {
            out.text(encodeName(f->name) + " " + std::to_string(f->components) + " " +
                     std::to_string(f->values.size() / std::uint64_t(f->components)) + " float\n");
            out.values<float>(f->values.size(), [&](std::uint64_t i) { return f->values[i]; });
        }
    }
    file.commit();
}

}  // namespace uvr
