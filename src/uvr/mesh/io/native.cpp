// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/native.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <type_traits>
#include <vector>

#include <unistd.h>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"
#include "uvr/core/progress.h"
#include "uvr/mesh/validate.h"

namespace uvr {

namespace {

// Layout of version 1 (docs/NATIVE_FORMAT.md): a 48-byte header, the field descriptors, then the
// arrays, each starting at a multiple of 8 bytes, all little-endian.
constexpr std::uint32_t kNativeVersion = 1;
constexpr std::uint64_t kHeaderBytes = 48;
constexpr std::uint64_t kMinDescriptorBytes = 4 + 1 + 4 + 8;  // empty name
constexpr std::uint32_t kMaxNameBytes = 65535;

static_assert(sizeof(Vec3f) == 12 && std::is_trivially_copyable_v<Vec3f>);
static_assert(sizeof(CellType) == 1);

using FilePtr = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

std::uint64_t align8(std::uint64_t x) {
    return (x + 7) & ~std::uint64_t{7};
}

/// a * b, or UINT64_MAX when that overflows.
std::uint64_t mulSat(std::uint64_t a, std::uint64_t b) {
    std::uint64_t r;
    return __builtin_mul_overflow(a, b, &r) ? UINT64_MAX : r;
}

/// a + b, or UINT64_MAX when that overflows.
std::uint64_t addSat(std::uint64_t a, std::uint64_t b) {
    std::uint64_t r;
    return __builtin_add_overflow(a, b, &r) ? UINT64_MAX : r;
}

template <typename T>
T byteSwap(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::reverse(b, b + sizeof(T));
    std::memcpy(&v, b, sizeof(T));
    return v;
}

/// Converts between little-endian file order and host order (a no-op on little-endian hosts).
template <typename T>
T fromLittle(T v) {
    if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) return byteSwap(v);
    return v;
}

/// Host-order values of `count` elements of `wordBytes` each, swapped in place on big-endian.
void swapWordsIfBigEndian(void* data, std::uint64_t count, size_t wordBytes) {
    if constexpr (std::endian::native == std::endian::big) {
        auto* p = static_cast<unsigned char*>(data);
        for (std::uint64_t i = 0; i < count; ++i)
            std::reverse(p + i * wordBytes, p + (i + 1) * wordBytes);
    } else {
        (void)data, (void)count, (void)wordBytes;
    }
}

template <typename T>
T loadLe(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return fromLittle(v);
}

template <typename T>
void storeLe(std::vector<unsigned char>& out, T v) {
    v = fromLittle(v);
    const size_t at = out.size();
    out.resize(at + sizeof(T));
    std::memcpy(out.data() + at, &v, sizeof(T));
}

/// Field descriptor as stored in the file.
struct FieldDescriptor {
    std::string name;
    std::uint8_t association = 0;
    std::uint32_t components = 0;
    std::uint64_t valueCount = 0;
    std::uint64_t offset = 0;  ///< byte offset of the descriptor
};

/// One array of the file: its name in messages, element count and size, and where it starts.
struct ArraySpan {
    std::string what;
    std::uint64_t count = 0;
    std::uint64_t elementBytes = 0;
    std::uint64_t start = 0;
    std::uint64_t bytes() const { return count * elementBytes; }
};

/// Sequential reader that turns short reads into Parse errors naming the byte offset.
class Reader {
public:
    Reader(const std::string& path, std::uint64_t size) : path_(path), size_(size) {
        file_.reset(std::fopen(path.c_str(), "rb"));
        if (!file_)
            throwError(ErrorKind::Io, path, std::string("cannot open: ") + std::strerror(errno));
    }
    std::uint64_t offset() const { return offset_; }
    std::uint64_t remaining() const { return size_ - std::min(size_, offset_); }

    void read(void* dst, std::uint64_t bytes, const std::string& what) {
        if (bytes == 0) return;
        const size_t got = std::fread(dst, 1, bytes, file_.get());
        if (got != bytes) {
            if (std::ferror(file_.get()))
                throwError(ErrorKind::Io, path_,
                           "read failed at " + atByte(offset_ + got) + " in " + what + ": " +
                               std::strerror(errno));
            throwParseError(path_, atByte(offset_ + got),
                            "unexpected end of file in " + what + ": expected " +
                                std::to_string(bytes) + " bytes from " + atByte(offset_));
        }
        offset_ += bytes;
    }
    /// Reads `bytes` from byte `at` without moving the reader (pread: safe from many threads at
    /// once).
    void readAt(void* dst, std::uint64_t at, std::uint64_t bytes, const std::string& what) const {
        auto* p = static_cast<unsigned char*>(dst);
        for (std::uint64_t done = 0; done < bytes;) {
            const ssize_t got = ::pread(::fileno(file_.get()), p + done, bytes - done,
                                        static_cast<off_t>(at + done));
            if (got < 0 && errno == EINTR) continue;
            if (got < 0)
                throwError(ErrorKind::Io, path_,
                           "read failed at " + atByte(at + done) + " in " + what + ": " +
                               std::strerror(errno));
            if (got == 0)
                throwParseError(path_, atByte(at + done),
                                "unexpected end of file in " + what + ": expected " +
                                    std::to_string(bytes) + " bytes from " + atByte(at));
            done += static_cast<std::uint64_t>(got);
        }
    }
    /// Moves to byte `offset` (within the file).
    void seek(std::uint64_t offset) {
        if (::fseeko(file_.get(), static_cast<off_t>(offset), SEEK_SET) != 0)
            throwError(ErrorKind::Io, path_,
                       "cannot seek to " + atByte(offset) + ": " + std::strerror(errno));
        offset_ = offset;
    }

private:
    std::string path_;
    std::uint64_t size_;
    std::uint64_t offset_ = 0;
    FilePtr file_{nullptr, &std::fclose};
};

/// What the header and descriptors say, checked against the file size: the counts, the fields
/// and where every array lies (points, cellTypes, cellOffsets, cellIndices, then the fields').
struct NativeLayout {
    std::uint64_t pointCount = 0, cellCount = 0, indexCount = 0;
    std::vector<FieldDescriptor> descriptors;
    std::vector<ArraySpan> arrays;
};

/// Reads and checks the header and the field descriptors (the reader is left after them).
NativeLayout readLayout(Reader& in, const std::string& path, std::uint64_t size) {
    // Header.
    if (size < kHeaderBytes)
        throwParseError(path, atByte(size),
                        "truncated header: expected at least " + std::to_string(kHeaderBytes) +
                            " bytes, got " + std::to_string(size));
    unsigned char header[kHeaderBytes];
    in.read(header, kHeaderBytes, "the header");
    if (std::memcmp(header, kNativeMagic, 8) != 0) {
        std::string got;
        for (int i = 0; i < 8; ++i) {
            char hex[4];
            std::snprintf(hex, sizeof(hex), " %02x", header[i]);
            got += hex;
        }
        throwParseError(path, atByte(0),
                        "expected the magic bytes 55 56 52 4d 45 53 48 00 (\"UVRMESH\\0\") of a "
                        ".uvrm file, got" +
                            got);
    }
    const auto version = loadLe<std::uint32_t>(header + 8);
    const auto flags = loadLe<std::uint32_t>(header + 12);
    const auto pointCount = loadLe<std::uint64_t>(header + 16);
    const auto cellCount = loadLe<std::uint64_t>(header + 24);
    const auto indexCount = loadLe<std::uint64_t>(header + 32);
    const auto fieldCount = loadLe<std::uint32_t>(header + 40);
    const auto reserved = loadLe<std::uint32_t>(header + 44);
    if (version == 0) throwParseError(path, atByte(8), "expected format version 1, got 0");
    if (version > kNativeVersion)
        throwError(ErrorKind::Unsupported, path,
                   "byte 8: format version " + std::to_string(version) +
                       " is newer than this uvr reads (up to " + std::to_string(kNativeVersion) +
                       ")");
    if (flags != 0)
        throwError(ErrorKind::Unsupported, path,
                   "byte 12: unknown flags " + std::to_string(flags) + " (version 1 defines none)");
    if (reserved != 0)
        throwParseError(path, atByte(44),
                        "expected reserved word 0, got " + std::to_string(reserved));

    // Header consistency: every cell lists 4 to 8 corners.
    if (indexCount < mulSat(cellCount, 4) || indexCount > mulSat(cellCount, 8))
        throwParseError(path, atByte(32),
                        "indexCount " + std::to_string(indexCount) + " is impossible for " +
                            std::to_string(cellCount) + " cells (expected 4 to 8 per cell)");

    // Field descriptors, each checked against the bytes left before anything is allocated.
    if (fieldCount > in.remaining() / kMinDescriptorBytes)
        throwParseError(path, atByte(40),
                        "fieldCount " + std::to_string(fieldCount) + " needs at least " +
                            std::to_string(fieldCount * kMinDescriptorBytes) +
                            " bytes of descriptors, but only " + std::to_string(in.remaining()) +
                            " bytes follow the header");
    std::vector<FieldDescriptor> descriptors(fieldCount);
    for (std::uint32_t f = 0; f < fieldCount; ++f) {
        FieldDescriptor& d = descriptors[f];
        d.offset = in.offset();
        const std::string what = "field " + std::to_string(f) + " descriptor";
        unsigned char word[8];
        in.read(word, 4, what);
        const auto nameBytes = loadLe<std::uint32_t>(word);
        if (nameBytes > kMaxNameBytes || nameBytes > in.remaining())
            throwParseError(
                path, atByte(d.offset),
                what + ": name length " + std::to_string(nameBytes) + ", expected at most " +
                    std::to_string(std::min<std::uint64_t>(kMaxNameBytes, in.remaining())));
        d.name.resize(nameBytes);
        in.read(d.name.data(), nameBytes, what);
        unsigned char rest[13];
        in.read(rest, 13, what);
        d.association = rest[0];
        d.components = loadLe<std::uint32_t>(rest + 1);
        d.valueCount = loadLe<std::uint64_t>(rest + 5);
        const std::string named = "field '" + d.name + "'";
        if (d.association > 1)
            throwParseError(path, atByte(d.offset + 4 + nameBytes),
                            named + ": association " + std::to_string(d.association) +
                                ", expected 0 (point) or 1 (cell)");
        if (d.components == 0 || d.components > INT_MAX)
            throwParseError(path, atByte(d.offset + 5 + nameBytes),
                            named + ": components " + std::to_string(d.components) +
                                ", expected 1 to " + std::to_string(INT_MAX));
        const std::uint64_t tuples = d.association == 0 ? pointCount : cellCount;
        if (mulSat(tuples, d.components) != d.valueCount)
            throwParseError(path, atByte(d.offset + 9 + nameBytes),
                            named + ": valueCount " + std::to_string(d.valueCount) + ", expected " +
                                std::to_string(tuples) + " " +
                                (d.association == 0 ? "points" : "cells") + " x " +
                                std::to_string(d.components) + " components");
    }

    // Array layout: the exact size the counts imply must be the file size.
    NativeLayout layout;
    layout.pointCount = pointCount;
    layout.cellCount = cellCount;
    layout.indexCount = indexCount;
    std::vector<ArraySpan> arrays = {{"points", pointCount, 12},
                                     {"cellTypes", cellCount, 1},
                                     {"cellOffsets", addSat(cellCount, 1), 8},
                                     {"cellIndices", indexCount, 4}};
    for (const FieldDescriptor& d : descriptors)
        arrays.push_back({"field '" + d.name + "' values", d.valueCount, 4});
    std::uint64_t cursor = in.offset();
    for (ArraySpan& a : arrays) {
        a.start = align8(cursor);
        const std::uint64_t bytes = mulSat(a.count, a.elementBytes);
        const std::uint64_t end = addSat(a.start, bytes);
        if (end > size)
            throwParseError(
                path, atByte(a.start),
                a.what + ": " + std::to_string(a.count) + " x " + std::to_string(a.elementBytes) +
                    " bytes need the file to hold " +
                    (end == UINT64_MAX ? std::string("more than 2^64") : std::to_string(end)) +
                    " bytes, but it has " + std::to_string(size) +
                    " (truncated or corrupt header)");
        cursor = end;
    }
    if (cursor != size)
        throwParseError(path, atByte(cursor),
                        "expected the file to end after the last array at " + atByte(cursor) +
                            ", but it has " + std::to_string(size) + " bytes");
    layout.descriptors = std::move(descriptors);
    layout.arrays = std::move(arrays);
    return layout;
}

}  // namespace

Mesh readNative(const std::string& path, const ReadOptions& options) {
    const std::uint64_t size = fileSize(path);
    Reader in(path, size);
    NativeLayout layout = readLayout(in, path, size);
    const std::vector<ArraySpan>& arrays = layout.arrays;
    std::vector<FieldDescriptor>& descriptors = layout.descriptors;
    const std::uint64_t pointCount = layout.pointCount, cellCount = layout.cellCount,
                        indexCount = layout.indexCount;
    const auto fieldCount = static_cast<std::uint32_t>(descriptors.size());
    for (const ArraySpan& a : arrays)
        checkAllocation(path, a.what, a.count, a.elementBytes, options.maxMemoryBytes);
    const BudgetedOptions budgeted(options);
    for (const ArraySpan& a : arrays)
        budgeted.budget().charge(path, a.what, a.count, a.elementBytes);

    // Arrays: each allocated by a task of its own (largest first), whose pieces are then read
    // straight into the mesh's vectors by tasks of their own: the disk, the page faults, the
    // zeroing of the large arrays and the copies overlap (a 3 GB file reads at the disk's speed).
    Mesh mesh;
    mesh.fields.resize(fieldCount);
    const std::size_t arrayCount = arrays.size();
    struct Piece {
        std::size_t array;
        std::uint64_t from, bytes;
    };
    constexpr std::uint64_t kPiece = 16ull << 20;
    std::vector<Piece> pieces;
    std::vector<std::size_t> firstPiece(arrayCount + 1, 0);
    for (std::size_t k = 0; k < arrayCount; ++k) {
        for (std::uint64_t from = 0; from < arrays[k].bytes(); from += kPiece)
            pieces.push_back({k, from, std::min(kPiece, arrays[k].bytes() - from)});
        firstPiece[k + 1] = pieces.size();
    }
    std::vector<std::size_t> order(arrayCount);
    for (std::size_t k = 0; k < arrayCount; ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
        return arrays[x].bytes() > arrays[y].bytes();
    });
    std::vector<unsigned char*> dst(arrayCount, nullptr);
    std::vector<std::exception_ptr> allocErrors(arrayCount), readErrors(pieces.size());
    ProgressCounter read(options.progress, static_cast<std::int64_t>(size));
    auto allocate = [&](std::size_t k) {
        auto at = [&](auto& v, std::uint64_t n) {
            v.resize(n);
            dst[k] = reinterpret_cast<unsigned char*>(v.data());
        };
        if (k == 0) at(mesh.points, pointCount);
        if (k == 1) at(mesh.cellTypes, cellCount);
        if (k == 2) at(mesh.cellOffsets, cellCount + 1);
        if (k == 3) at(mesh.cellIndices, indexCount);
        if (k >= 4) at(mesh.fields[k - 4].values, descriptors[k - 4].valueCount);
    };
#pragma omp parallel
#pragma omp single
    for (const std::size_t k : order) {
#pragma omp task firstprivate(k)
        {
            bool allocated = true;
            try {
                allocate(k);
            } catch (...) {
                allocErrors[k] = std::current_exception();
                allocated = false;
            }
            for (std::size_t i = firstPiece[k]; allocated && i < firstPiece[k + 1]; ++i) {
#pragma omp task firstprivate(i)
                {
                    const Piece& p = pieces[i];
                    try {
                        in.readAt(dst[p.array] + p.from, arrays[p.array].start + p.from, p.bytes,
                                  arrays[p.array].what);
                        read.add(static_cast<std::int64_t>(p.bytes));
                    } catch (...) {
                        readErrors[i] = std::current_exception();
                    }
                }
            }
        }
    }
    for (const std::exception_ptr& e : allocErrors)
        if (e) std::rethrow_exception(e);
    for (const std::exception_ptr& e : readErrors)  // the first piece's error, as a serial read's
        if (e) std::rethrow_exception(e);
    read.finish();
    static_assert(sizeof(CellType) == 1);
    for (std::size_t k = 0; k < arrays.size(); ++k) {
        const std::uint64_t word = k == 0 ? 4 : arrays[k].elementBytes;
        swapWordsIfBigEndian(dst[k], arrays[k].bytes() / word, word);
    }
    for (std::uint32_t f = 0; f < fieldCount; ++f) {
        Field& field = mesh.fields[f];
        field.name = std::move(descriptors[f].name);
        field.association =
            descriptors[f].association == 0 ? Association::Point : Association::Cell;
        field.components = static_cast<int>(descriptors[f].components);
    }

    validateStructure(mesh, path);
    return mesh;
}

MeshPart readNativePart(const std::string& path, std::uint64_t firstCell, std::uint64_t endCell,
                        const ReadOptions& options) {
    const std::uint64_t size = fileSize(path);
    Reader in(path, size);
    const NativeLayout layout = readLayout(in, path, size);
    const std::vector<ArraySpan>& arrays = layout.arrays;
    if (firstCell > endCell || endCell > layout.cellCount)
        throwError(ErrorKind::Argument, path,
                   "cells [" + std::to_string(firstCell) + ", " + std::to_string(endCell) +
                       ") asked for, but the file has " + std::to_string(layout.cellCount));
    const std::uint64_t n = endCell - firstCell;
    const BudgetedOptions budgeted(options);
    budgeted.budget().charge(path, "the part's cell types and offsets", n, 9);
    MeshPart part;
    Mesh& mesh = part.mesh;
    // The cells: their types and offsets, then their corner indices.
    mesh.cellTypes.resize(n);
    in.readAt(mesh.cellTypes.data(), arrays[1].start + firstCell, n, arrays[1].what);
    std::vector<std::uint64_t> offsets(n + 1);
    in.readAt(offsets.data(), arrays[2].start + 8 * firstCell, 8 * (n + 1), arrays[2].what);
    swapWordsIfBigEndian(offsets.data(), n + 1, 8);
    for (std::uint64_t c = 0; c < n; ++c)
        if (offsets[c + 1] < offsets[c] || offsets[c + 1] > layout.indexCount)
            throwParseError(path, atByte(arrays[2].start + 8 * (firstCell + c + 1)),
                            "cell offsets: offset " + std::to_string(offsets[c + 1]) + " of cell " +
                                std::to_string(firstCell + c + 1) +
                                " is below the one before or past the " +
                                std::to_string(layout.indexCount) + " indices");
    const std::uint64_t i0 = offsets[0], i1 = offsets[n];
    budgeted.budget().charge(path, "the part's cell indices", i1 - i0, 8);
    std::vector<std::uint32_t> indices(i1 - i0);
    in.readAt(indices.data(), arrays[3].start + 4 * i0, 4 * (i1 - i0), arrays[3].what);
    swapWordsIfBigEndian(indices.data(), indices.size(), 4);
    for (std::uint64_t k = 0; k < indices.size(); ++k)
        if (indices[k] >= layout.pointCount)
            throwParseError(path, atByte(arrays[3].start + 4 * (i0 + k)),
                            "cell indices: index " + std::to_string(indices[k]) + " of " +
                                std::to_string(layout.pointCount) + " points");
    // The points they use, in the file's order, read in runs of nearby ids. A part of a file
    // in spatial order uses a narrow band of ids: a table over that band numbers them without
    // sorting every corner (4 bytes per id of the band, no more than the corners take).
    std::vector<std::uint32_t> ids;
    std::vector<std::uint32_t> slot;  // per id of the band from `band` on: 1 + its index in ids
    std::uint32_t band = 0;
    if (!indices.empty()) {
        const auto [mn, mx] = std::minmax_element(indices.begin(), indices.end());
        band = *mn;
        if (std::uint64_t(*mx) - band < indices.size()) slot.assign(std::size_t(*mx) - band + 1, 0);
    }
    if (!slot.empty()) {
        for (std::uint32_t id : indices) slot[id - band] = 1;
        for (std::size_t k = 0; k < slot.size(); ++k)
            if (slot[k])
                ids.push_back(band + std::uint32_t(k)), slot[k] = std::uint32_t(ids.size());
    } else {
        ids = indices;
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    }
    budgeted.budget().charge(path, "the part's points", ids.size(), 20);
    part.pointIds.assign(ids.begin(), ids.end());
    constexpr std::uint64_t kRunGap = 4096;  // ids this close are read in one run
    const auto readRuns = [&](const ArraySpan& array, std::uint64_t wordBytes, unsigned char* out) {
        std::vector<unsigned char> run;
        for (std::size_t a = 0; a < ids.size();) {
            std::size_t b = a + 1;
            while (b < ids.size() && ids[b] - ids[b - 1] <= kRunGap) ++b;
            const std::uint64_t lo = ids[a], hi = ids[b - 1];
            run.resize((hi - lo + 1) * wordBytes);
            in.readAt(run.data(), array.start + lo * wordBytes, run.size(), array.what);
            for (std::size_t k = a; k < b; ++k)
                std::memcpy(out + k * wordBytes, run.data() + (ids[k] - lo) * wordBytes, wordBytes);
            a = b;
        }
    };
    mesh.points.resize(ids.size());
    readRuns(arrays[0], 12, reinterpret_cast<unsigned char*>(mesh.points.data()));
    swapWordsIfBigEndian(mesh.points.data(), 3 * ids.size(), 4);
    mesh.cellOffsets.resize(n + 1);
    for (std::uint64_t c = 0; c <= n; ++c) mesh.cellOffsets[c] = offsets[c] - i0;
    mesh.cellIndices.resize(indices.size());
    for (std::size_t k = 0; k < indices.size(); ++k)
        mesh.cellIndices[k] =
            !slot.empty() ? slot[indices[k] - band] - 1
                          : static_cast<std::uint32_t>(
                                std::lower_bound(ids.begin(), ids.end(), indices[k]) - ids.begin());
    part.cellIds.resize(n);
    for (std::uint64_t c = 0; c < n; ++c) part.cellIds[c] = firstCell + c;
    // Every field on them.
    for (std::size_t f = 0; f < layout.descriptors.size(); ++f) {
        const FieldDescriptor& d = layout.descriptors[f];
        const ArraySpan& array = arrays[4 + f];
        Field field;
        field.name = d.name;
        field.association = d.association == 0 ? Association::Point : Association::Cell;
        field.components = static_cast<int>(d.components);
        const std::uint64_t word = 4ull * d.components;
        if (field.association == Association::Point) {
            field.values.resize(ids.size() * d.components);
            readRuns(array, word, reinterpret_cast<unsigned char*>(field.values.data()));
        } else {
            field.values.resize(n * d.components);
            in.readAt(field.values.data(), array.start + firstCell * word, n * word, array.what);
        }
        swapWordsIfBigEndian(field.values.data(), field.values.size(), 4);
        mesh.fields.push_back(std::move(field));
    }
    validateStructure(mesh, path);
    return part;
}

MeshPart meshPart(const MeshView& whole, std::uint64_t firstCell, std::uint64_t endCell) {
    UVR_CHECK(firstCell <= endCell && endCell <= whole.cellCount(), "cells of a part");
    MeshPart part;
    std::vector<std::uint8_t> used(whole.pointCount(), 0);
    for (std::uint64_t c = firstCell; c < endCell; ++c)
        for (std::uint32_t id : whole.cell(c)) used[id] = 1;
    std::vector<std::uint32_t> local(whole.pointCount(), 0);
    for (std::uint64_t i = 0; i < whole.pointCount(); ++i)
        if (used[i]) {
            local[i] = static_cast<std::uint32_t>(part.pointIds.size());
            part.pointIds.push_back(i);
            part.mesh.points.push_back(whole.points[i]);
        }
    std::vector<std::uint32_t> corners;
    for (std::uint64_t c = firstCell; c < endCell; ++c) {
        corners.clear();
        for (std::uint32_t id : whole.cell(c)) corners.push_back(local[id]);
        part.mesh.addCell(whole.cellTypes[c], corners);
        part.cellIds.push_back(c);
    }
    return part;
}

MeshPart meshPart(const Mesh& whole, std::uint64_t firstCell, std::uint64_t endCell) {
    MeshPart part = meshPart(MeshView(whole), firstCell, endCell);
    for (const Field& f : whole.fields) {
        Field field{f.name, f.association, f.components, {}};
        const std::size_t k = static_cast<std::size_t>(f.components);
        if (f.association == Association::Point) {
            for (std::uint64_t i : part.pointIds)
                field.values.insert(field.values.end(), f.values.begin() + i * k,
                                    f.values.begin() + (i + 1) * k);
        } else {
            field.values.assign(f.values.begin() + firstCell * k, f.values.begin() + endCell * k);
        }
        part.mesh.fields.push_back(std::move(field));
    }
    part.mesh.notes = whole.notes;
    return part;
}

MeshSummary readNativeSummary(const std::string& path, bool cellTypes) {
    const std::uint64_t size = fileSize(path);
    Reader in(path, size);
    const NativeLayout layout = readLayout(in, path, size);
    MeshSummary summary;
    summary.pointCount = layout.pointCount;
    summary.cellCount = layout.cellCount;
    summary.fileBytes = size;
    for (const FieldDescriptor& d : layout.descriptors)
        summary.fields.push_back({d.name,
                                  d.association == 0 ? Association::Point : Association::Cell,
                                  static_cast<int>(d.components)});
    if (!cellTypes) return summary;
    // The cell types (one byte per cell) are counted in chunks: nothing else is read.
    const ArraySpan& types = layout.arrays[1];
    in.seek(types.start);
    std::vector<unsigned char> chunk(std::min<std::uint64_t>(types.count, 1u << 20));
    for (std::uint64_t done = 0; done < types.count;) {
        const std::uint64_t n = std::min<std::uint64_t>(chunk.size(), types.count - done);
        in.read(chunk.data(), n, types.what);
        for (std::uint64_t i = 0; i < n; ++i) {
            const auto t = static_cast<CellType>(chunk[i]);
            if (t != CellType::Tetra && t != CellType::Hexahedron && t != CellType::Wedge &&
                t != CellType::Pyramid)
                throwParseError(path, atByte(types.start + done + i),
                                "cell " + std::to_string(done + i) + ": cell type " +
                                    std::to_string(chunk[i]) +
                                    ", expected 10 (tetra), 12 (hexahedron), 13 (wedge) or 14 "
                                    "(pyramid)");
            ++summary.cellTypes[t];
        }
        done += n;
    }
    return summary;
}

NativeWriter::NativeWriter(const std::string& path, std::uint64_t pointCount,
                           std::uint64_t cellCount, std::uint64_t indexCount,
                           const std::vector<FieldInfo>& fields,
                           std::function<void(double)> progress)
    : progress_(std::move(progress)) {
    // Refuse what the reader would refuse, before creating any file.
    for (const FieldInfo& f : fields) {
        if (f.name.size() > kMaxNameBytes)
            throwError(ErrorKind::Argument, path,
                       "field name of " + std::to_string(f.name.size()) +
                           " bytes, expected at most " + std::to_string(kMaxNameBytes));
    }
    if (fields.size() > UINT32_MAX)
        throwError(ErrorKind::Argument, path, "more than 2^32 - 1 fields");

    // Header and descriptors.
    std::vector<unsigned char> head(8);
    std::memcpy(head.data(), kNativeMagic, 8);
    storeLe<std::uint32_t>(head, kNativeVersion);
    storeLe<std::uint32_t>(head, 0);  // flags
    storeLe<std::uint64_t>(head, pointCount);
    storeLe<std::uint64_t>(head, cellCount);
    storeLe<std::uint64_t>(head, indexCount);
    storeLe<std::uint32_t>(head, static_cast<std::uint32_t>(fields.size()));
    storeLe<std::uint32_t>(head, 0);  // reserved
    counts_ = {3 * pointCount, cellCount, cellCount + 1, indexCount};
    const std::uint64_t wordBytes[4] = {4, 1, 8, 4};
    for (const FieldInfo& f : fields) {
        const std::uint64_t values =
            (f.association == Association::Point ? pointCount : cellCount) *
            static_cast<std::uint64_t>(f.components);
        storeLe<std::uint32_t>(head, static_cast<std::uint32_t>(f.name.size()));
        head.insert(head.end(), f.name.begin(), f.name.end());
        head.push_back(static_cast<unsigned char>(f.association));
        storeLe<std::uint32_t>(head, static_cast<std::uint32_t>(f.components));
        storeLe<std::uint64_t>(head, values);
        counts_.push_back(values);
    }
    total_ = head.size();
    for (size_t a = 0; a < counts_.size(); ++a)
        total_ += counts_[a] * (a < kFirstField ? wordBytes[a] : 4);
    // A file of many gigabytes is refused at once when its file system cannot hold it (the
    // space of a file it replaces counts, since the old one goes only at the rename).
    const OutputTarget target = resolveOutput(path);
    if (target.kind == OutputKind::Atomic) {
        std::error_code ec;
        const auto space =
            std::filesystem::space(std::filesystem::path(target.target).parent_path().empty()
                                       ? std::filesystem::path(".")
                                       : std::filesystem::path(target.target).parent_path(),
                                   ec);
        if (!ec && space.available < total_)
            throwError(ErrorKind::Io, path,
                       "the file needs " + std::to_string(total_) +
                           " bytes, but its file system "
                           "has only " +
                           std::to_string(space.available) + " available");
    }
    file_ = std::make_unique<OutputFile>(path);
    put(head.data(), head.size());
}

NativeWriter::~NativeWriter() = default;

void NativeWriter::put(const void* data, std::uint64_t bytes) {
    // Large pieces go out in 64 MiB parts so that progress moves while an 8 GB file is written.
    constexpr std::uint64_t kPiece = 64ull << 20;
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::uint64_t done = 0; done < bytes; done += kPiece) {
        const std::uint64_t n = std::min(kPiece, bytes - done);
        file_->write(p + done, n);
        if (progress_) progress_(double(offset_ + done + n) / double(total_));
    }
    offset_ += bytes;
}

void NativeWriter::advanceTo(int array) {
    // Arrays in file order, each after zero padding to a multiple of 8.
    while (current_ < array) {
        UVR_CHECK(current_ < 0 || written_ == counts_[current_],
                  "NativeWriter: array " << current_ << " has " << written_ << " of "
                                         << counts_[current_] << " values");
        ++current_;
        written_ = 0;
        static constexpr unsigned char kZeros[8] = {};
        put(kZeros, align8(offset_) - offset_);
    }
}

void NativeWriter::append(int array, const void* data, std::uint64_t count, size_t wordBytes) {
    if (array == kFirstField) {
        // The current field, or the next one when it is full.
        array = std::max(current_, int(kFirstField));
        auto full = [&](int a) { return (a == current_ ? written_ : 0) == counts_[a]; };
        while (count > 0 && array + 1 < int(counts_.size()) && full(array)) ++array;
    }
    UVR_CHECK(array < int(counts_.size()), "NativeWriter: values for a field of none");
    advanceTo(array);
    UVR_CHECK(current_ == array && written_ + count <= counts_[array],
              "NativeWriter: " << count << " values for array " << array << " (now writing "
                               << current_ << ", " << written_ << " of " << counts_[current_]
                               << ")");
    written_ += count;
    if constexpr (std::endian::native == std::endian::little) {
        put(data, count * wordBytes);
    } else {
        // Swapped chunk by chunk into a scratch buffer on big-endian hosts.
        std::vector<unsigned char> chunk;
        const auto* p = static_cast<const unsigned char*>(data);
        constexpr std::uint64_t kWords = 1 << 20;
        for (std::uint64_t i = 0; i < count; i += kWords) {
            const std::uint64_t n = std::min(kWords, count - i);
            chunk.assign(p + i * wordBytes, p + (i + n) * wordBytes);
            swapWordsIfBigEndian(chunk.data(), n, wordBytes);
            put(chunk.data(), chunk.size());
        }
    }
}

void NativeWriter::points(std::span<const Vec3f> values) {
    append(kPoints, values.data(), 3 * values.size(), 4);
}

void NativeWriter::cellTypes(std::span<const CellType> values) {
    append(kCellTypes, values.data(), values.size(), 1);
}

void NativeWriter::cellOffsets(std::span<const std::uint64_t> values) {
    append(kCellOffsets, values.data(), values.size(), 8);
}

void NativeWriter::tetrahedronTypesAndOffsets() {
    const std::uint64_t cells = counts_[kCellTypes];
    UVR_CHECK(counts_[kCellIndices] == 4 * cells, "NativeWriter: " << counts_[kCellIndices]
                                                                   << " indices for " << cells
                                                                   << " tetrahedra");
    constexpr std::uint64_t kPiece = 1 << 20;
    const std::vector<CellType> types(std::min(kPiece, cells), CellType::Tetra);
    for (std::uint64_t c = 0; c < cells; c += kPiece)
        cellTypes(std::span(types).first(std::min(kPiece, cells - c)));
    std::vector<std::uint64_t> offsets;
    for (std::uint64_t c = 0; c <= cells; c += kPiece) {
        offsets.resize(std::min(kPiece, cells + 1 - c));
        for (std::uint64_t i = 0; i < offsets.size(); ++i) offsets[i] = 4 * (c + i);
        cellOffsets(offsets);
    }
}

void NativeWriter::cellIndices(std::span<const std::uint32_t> values) {
    append(kCellIndices, values.data(), values.size(), 4);
}

void NativeWriter::fieldValues(std::span<const float> values) {
    append(kFirstField, values.data(), values.size(), 4);
}

void NativeWriter::commit() {
    advanceTo(int(counts_.size()) - 1);
    UVR_CHECK(written_ == counts_.back(), "NativeWriter: the last array has "
                                              << written_ << " of " << counts_.back() << " values");
    file_->commit();
}

void writeNative(const Mesh& mesh, const std::string& path,
                 const std::function<void(double)>& progress) {
    // Refuse meshes the reader would refuse, before creating any file.
    validateStructure(mesh, path);
    std::vector<FieldInfo> fields;
    for (const Field& f : mesh.fields) fields.push_back({f.name, f.association, f.components});
    NativeWriter out(path, mesh.pointCount(), mesh.cellCount(), mesh.cellIndices.size(), fields,
                     progress);
    out.points(mesh.points);
    out.cellTypes(mesh.cellTypes);
    out.cellOffsets(mesh.cellOffsets);
    out.cellIndices(mesh.cellIndices);
    for (const Field& f : mesh.fields) out.fieldValues(f.values);
    out.commit();
}

}  // namespace uvr
