// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// First 8 bytes of a native uvr mesh file (.uvrm).
inline constexpr char kNativeMagic[8] = {'U', 'V', 'R', 'M', 'E', 'S', 'H', '\0'};

/// The counts, fields and cell types of a mesh file, known without reading its arrays.
struct MeshSummary {
    std::uint64_t pointCount = 0, cellCount = 0, fileBytes = 0;
    std::map<CellType, std::uint64_t> cellTypes;
    std::vector<FieldInfo> fields;
};

/// Reads a native uvr mesh (.uvrm, documented in docs/NATIVE_FORMAT.md); all counts are checked
/// against the file size before anything is allocated.
Mesh readNative(const std::string& path, const ReadOptions& options = {});

/// A part of a mesh file: some of its cells, the points they use (in the file's order) and every
/// field on them, with the ids of both in the whole file (a data-parallel rank's share).
struct MeshPart {
    Mesh mesh;
    std::vector<std::uint64_t> pointIds;  ///< per point: its index in the file (increasing)
    std::vector<std::uint64_t> cellIds;   ///< per cell: its index in the file (increasing)
};

/// In the ids of a part of a file of pieces (a .pvtu's pieces, a VTKHDF file's partitions), the
/// piece's index sits above this many bits and the point's or cell's index in the piece below,
/// so the ids sort in the order the whole file's reader merges the pieces.
inline constexpr int kPieceIdShift = 40;

/// Reads the cells [firstCell, endCell) of a native mesh and what they use (each array read only
/// where the part lies in it: the points and point values in runs of the ids the cells name),
/// checked as readNative checks a whole file. Throws Error(Argument) for a range beyond the file's
/// cells.
MeshPart readNativePart(const std::string& path, std::uint64_t firstCell, std::uint64_t endCell,
                        const ReadOptions& options = {});

/// The part of a mesh held whole that holds the cells [firstCell, endCell), without fields.
MeshPart meshPart(const MeshView& mesh, std::uint64_t firstCell, std::uint64_t endCell);
/// The same with every field of the mesh on the part's points and cells, and its notes.
MeshPart meshPart(const Mesh& mesh, std::uint64_t firstCell, std::uint64_t endCell);

/// What `uvr info` prints of a .uvrm without reading its arrays: the header's counts and fields
/// and, with cellTypes, the cell types (one byte per cell, read in chunks); checked as
/// readNative checks them.
MeshSummary readNativeSummary(const std::string& path, bool cellTypes = true);

/// Writes a mesh in the native format, atomically (temporary file, then rename).
void writeNative(const Mesh& mesh, const std::string& path,
                 const std::function<void(double)>& progress = {});

class OutputFile;

/// Writes a .uvrm piece by piece, so that a mesh larger than memory can be generated straight
/// into its file: the header (counts and fields) is given first, then the arrays' values in file
/// order (points, cell types, cell offsets, cell indices, each field's values), each in as many
/// pieces as the caller likes. The bytes are those writeNative writes for the same mesh (which
/// uses this writer). Atomic: nothing appears at `path` before commit(). The caller's data is
/// not validated (writeNative validates a whole mesh first); a piece beyond an array's count, or
/// commit() before every array is complete, is an internal error.
class NativeWriter {
public:
    /// Opens the temporary output and writes the header and field descriptors; throws
    /// Error(Argument) for a field name over 65535 bytes or more than 2^32 - 1 fields, and
    /// Error(Io) when the file system has less space available than the file's size.
    NativeWriter(const std::string& path, std::uint64_t pointCount, std::uint64_t cellCount,
                 std::uint64_t indexCount, const std::vector<FieldInfo>& fields,
                 std::function<void(double)> progress = {});
    ~NativeWriter();
    NativeWriter(const NativeWriter&) = delete;
    NativeWriter& operator=(const NativeWriter&) = delete;

    /// Appends points.
    void points(std::span<const Vec3f> values);
    /// Appends cell types.
    void cellTypes(std::span<const CellType> values);
    /// Appends cell offsets (cellCount + 1 in all).
    void cellOffsets(std::span<const std::uint64_t> values);
    /// Writes the whole cell types and offsets arrays of a mesh of tetrahedra only (type 10 and
    /// offsets 0, 4, 8, ..., in pieces of a few MiB); indexCount must be 4 cellCount.
    void tetrahedronTypesAndOffsets();
    /// Appends corner indices.
    void cellIndices(std::span<const std::uint32_t> values);
    /// Appends values of the current field (fields in the order given, each filled before the
    /// next begins).
    void fieldValues(std::span<const float> values);
    /// Checks that every array is complete and makes the file appear at its path.
    void commit();

private:
    enum Array : int { kPoints, kCellTypes, kCellOffsets, kCellIndices, kFirstField };
    void append(int array, const void* data, std::uint64_t count, std::size_t wordBytes);
    void put(const void* data, std::uint64_t bytes);
    void advanceTo(int array);

    std::unique_ptr<OutputFile> file_;
    std::function<void(double)> progress_;
    std::vector<std::uint64_t> counts_;  ///< elements of each array (words for points: x, y, z)
    int current_ = -1;                   ///< the array being written, -1 before the first
    std::uint64_t written_ = 0;          ///< elements of the current array written
    std::uint64_t offset_ = 0, total_ = 0;
};

}  // namespace uvr
