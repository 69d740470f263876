// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/vec.h"
#include "uvr/mesh/cell_types.h"

namespace uvr {

/// Where a field's values live.
enum class Association : std::uint8_t { Point = 0, Cell = 1 };

/// "point" or "cell".
const char* associationName(Association a);

/// A named field: values.size() == tupleCount * components, tuples in point or cell order.
struct Field {
    std::string name;
    Association association = Association::Point;
    int components = 1;         ///< 1 for scalars, 3 for vectors, any count for FIELD arrays
    std::vector<float> values;  ///< tuple-major: values[i * components + c]

    /// Number of tuples (points or cells).
    std::uint64_t tupleCount() const { return components > 0 ? values.size() / components : 0; }
};

/// The owning unstructured mesh as read from a file: float32 points, volumetric cells of VTK types
/// 10/12/13/14 (corner nodes only, VTK vertex order), and fields. Invariants (checked by
/// validateMesh): cellOffsets.size() == cellTypes.size() + 1, cellOffsets.front() == 0,
/// cellOffsets.back() == cellIndices.size(), each cell lists cornerCount(type) indices.
struct Mesh {
    std::vector<Vec3f> points;
    std::vector<CellType> cellTypes;
    std::vector<std::uint64_t> cellOffsets{0};
    std::vector<std::uint32_t> cellIndices;
    std::vector<Field> fields;
    /// Reader remarks a user should see (e.g. "dropped 120 triangle cells"), shown by `uvr info`.
    std::vector<std::string> notes;

    std::uint64_t pointCount() const { return points.size(); }
    std::uint64_t cellCount() const { return cellTypes.size(); }
    /// Corner indices of cell c.
    std::span<const std::uint32_t> cell(std::uint64_t c) const {
        return {cellIndices.data() + cellOffsets[c], cellIndices.data() + cellOffsets[c + 1]};
    }
    /// Appends a cell; ids must hold cornerCount(type) indices.
    void addCell(CellType type, std::span<const std::uint32_t> ids);
    /// Bounds of the points used by cells without NaN/Inf corners (the cells that can render;
    /// validateMesh's bounds also leave out zero-volume ones); unused points do not count.
    Bounds3f bounds() const;
    /// First field with this name and association, or nullptr.
    const Field* findField(const std::string& name, Association association) const;
};

/// A non-owning view of a mesh's points and cells in Mesh's layout (float32 points, VTK cell
/// types, cellCount + 1 offsets, uint32 corner indices): what splitting into tetrahedra reads.
/// It lets arrays owned elsewhere (a Python caller's numpy arrays) be rendered without copying
/// them into a Mesh. The same invariants as Mesh (validateStructure checks them).
struct MeshView {
    std::span<const Vec3f> points;
    std::span<const CellType> cellTypes;
    std::span<const std::uint64_t> cellOffsets;
    std::span<const std::uint32_t> cellIndices;

    MeshView() = default;
    /// A view of a Mesh's arrays (implicit: every function taking a view takes a Mesh).
    MeshView(const Mesh& mesh)  // NOLINT(google-explicit-constructor)
        : points(mesh.points),
          cellTypes(mesh.cellTypes),
          cellOffsets(mesh.cellOffsets),
          cellIndices(mesh.cellIndices) {}

    std::uint64_t pointCount() const { return points.size(); }
    /// Cells: one fewer than the offsets (0 for an empty view).
    std::uint64_t cellCount() const { return cellTypes.size(); }
    /// Corner indices of cell c.
    std::span<const std::uint32_t> cell(std::uint64_t c) const {
        return cellIndices.subspan(cellOffsets[c], cellOffsets[c + 1] - cellOffsets[c]);
    }
    /// Bounds of the points used by cells without NaN/Inf corners (as Mesh::bounds).
    Bounds3f bounds() const;
};

}  // namespace uvr
