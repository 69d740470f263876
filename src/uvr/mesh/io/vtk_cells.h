// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/mesh/io/load_budget.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Where a file keeps the faces of its polyhedron (VTK type 42) cells.
enum class PolyhedronFaces : std::uint8_t {
    None,          ///< nowhere (arrays without face streams): polyhedra are refused
    Connectivity,  ///< a polyhedron's node list is its face stream (legacy .vtk, all versions)
    Separate,      ///< VtkCellArrays::faces and faceOffsets (VTU's faces and faceoffsets)
};

/// Cells as VTK files store them (legacy and XML alike), before conversion to the Mesh model.
struct VtkCellArrays {
    std::vector<std::int32_t> types;         ///< VTK type code per cell
    std::vector<std::int64_t> offsets;       ///< cellCount + 1 entries, offsets[0] == 0
    std::vector<std::int64_t> connectivity;  ///< node indices of all cells
    PolyhedronFaces polyhedronFaces = PolyhedronFaces::None;  ///< where polyhedra keep faces
    /// Separate: the face streams [nFaces, n0, ids..., n1, ids...] of all polyhedra, in order.
    std::vector<std::int64_t> faces;
    /// Separate: cellCount + 1 entries from 0; cell c's face stream is
    /// faces[faceOffsets[c], faceOffsets[c + 1]) (empty for cells other than polyhedra).
    std::vector<std::int64_t> faceOffsets;
};

/// Converts VTK cells into mesh cells: quadratic and Lagrange 3D cells keep their corner nodes,
/// voxels become hexahedra, 0D-2D cells are dropped (with a note in mesh.notes), polyhedra and
/// pentagonal and hexagonal prisms (types 15, 16) are decomposed into tetrahedra around a new
/// point at their vertex centroid (decomposePolyhedron's rule; point fields get the mean of the
/// cell's vertex values there, a note says how many), cells VTK's ghost array (`vtkGhostType`,
/// cell and point data in mesh.fields) marks as another piece's duplicates or hidden are left
/// out as ParaView leaves them out (a note says how many), and unknown types, malformed face
/// streams, short cells and point indices outside [0, mesh.pointCount()) throw
/// Error(Parse/Validation/Unsupported) naming the file and cell index. Cell fields in
/// mesh.fields (one tuple per source cell) are filtered to the kept cells and repeated for a
/// decomposed cell's tetrahedra. mesh.points must already be set; the growth from polyhedra is
/// charged to budget when one is given. Returns, per cell added, the index of its cell in
/// `cells`.
std::vector<std::uint64_t> appendVtkCells(const VtkCellArrays& cells, Mesh& mesh,
                                          const std::string& file, LoadBudget* budget = nullptr);

}  // namespace uvr
