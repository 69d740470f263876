// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/mesh/mesh.h"

namespace uvr {

/// Cells as VTK files store them (legacy and XML alike), before conversion to the Mesh model.
struct VtkCellArrays {
    std::vector<std::int32_t> types;         ///< VTK type code per cell
    std::vector<std::int64_t> offsets;       ///< cellCount + 1 entries, offsets[0] == 0
    std::vector<std::int64_t> connectivity;  ///< node indices of all cells
};

/// Converts VTK cells into mesh cells: quadratic and Lagrange 3D cells keep their corner nodes,
/// voxels become hexahedra, 0D-2D cells are dropped (with a note in mesh.notes), and unknown
/// types, polyhedra, short cells and point indices outside [0, mesh.pointCount()) throw
/// Error(Parse/Unsupported) naming the file and cell index. Cell fields in mesh.fields (one
/// tuple per source cell) are filtered to the kept cells. mesh.points must already be set.
void appendVtkCells(const VtkCellArrays& cells, Mesh& mesh, const std::string& file);

}  // namespace uvr
