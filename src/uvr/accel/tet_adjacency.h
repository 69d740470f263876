// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <vector>

#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Marks "no cell" (a boundary face, or a point outside the mesh): kNoCell.
inline constexpr std::uint32_t kNoTet = kNoCell;

/// For every point, the smallest index of a point at exactly the same position (its own index
/// when no earlier point coincides); the same for any thread count.
std::vector<std::uint32_t> coincidentPointIds(const std::vector<Vec3f>& points);

/// Face neighbours: result[faceBase(c) + i] is the cell sharing face i (packedFace's numbering;
/// for a tetrahedron t, 4 t + i, the face opposite vertex i) of cell c, or kNoTet on the
/// boundary (or where more than two cells share a face). A quadrilateral matches only a
/// quadrilateral with the same corners, a triangle only a triangle: a hexahedron's quad face and
/// a pyramid's base, a wedge's and a tetrahedron's triangles.
/// Faces match on positions, not only on indices: coincident points count as one.
/// Faces are bucketed by their smallest vertex (a parallel counting sort); the same table for any
/// thread count.
std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh);

}  // namespace uvr
